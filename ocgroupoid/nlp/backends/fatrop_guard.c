/* A call into fatrop that can be left, so that fatrop runs in the caller's process.
 *
 * fatrop 1.1.8 (as CasADi ships it) has no time limit and no iteration callback, and its
 * inertia correction (IpSearchDirImpl::compute_search_dir) raises the regularisation in a
 * loop without a bound, from which it never returns on some singular KKT systems. The call is
 * left by a jump back to where it began (sigsetjmp in the caller, siglongjmp here), abandoning
 * fatrop's solver, which the caller never touches again:
 *
 * - from the driver's callbacks (ocg_guard_poll, ocg_guard_nan), synchronously: past the
 *   deadline, on Ctrl-C, after `nan_limit` non-finite evaluations, or when the caller's
 *   check (asked every `every` seconds) says stop;
 * - from a timer signal (a POSIX timer of this thread: SIGEV_THREAD_ID), when fatrop does not
 *   call back: every `every` seconds (at least 1 ms) and at the deadline it looks whether the
 *   call is due to be left, and leaves only when the interrupted instruction lies in fatrop's,
 *   blasfeo's or this driver's own code. Those hold no lock and allocate nothing themselves:
 *   the C and C++ runtimes they call (malloc, new, stdio) are other libraries, and a jump out
 *   of one of those could leave a lock held. Where the instruction is elsewhere, the timer
 *   looks again a millisecond later.
 *
 * Ctrl-C is watched from the main thread only: a SIGINT handler that notes it and passes it
 * on to the handler it replaced (Python's, which then raises KeyboardInterrupt or sets its
 * flag as usual once the call returns).
 */
#define _GNU_SOURCE
#include "fatrop_guard.h"

#if !defined(__linux__) /* no per-thread timers, no dl_iterate_phdr: never guarded */
int ocg_guard_available(void) { return 0; }
int ocg_guard_arm(struct ocg_guard *g, double seconds, int watch_sigint) {
  (void)g; (void)seconds; (void)watch_sigint;
  return 0;
}
void ocg_guard_disarm(struct ocg_guard *g) { (void)g; }
void ocg_guard_poll(struct ocg_guard *g) { (void)g; }
void ocg_guard_nan(struct ocg_guard *g) { (void)g; }
#else

#include <link.h>
#include <pthread.h>
#include <stdint.h>
#include <string.h>
#include <sys/syscall.h>
#include <ucontext.h>
#include <unistd.h>

#include <blasfeo.h>
#include "fatrop/ocp/OCPCInterface.h"

#ifndef sigev_notify_thread_id
#define sigev_notify_thread_id _sigev_un._tid
#endif

enum { OCG_RANGES = 8 };
static uintptr_t ocg_lo[OCG_RANGES], ocg_hi[OCG_RANGES]; /* code where a jump may start */
static int ocg_n_ranges, ocg_signal, ocg_ready = -1;     /* -1: not looked at yet */
static volatile sig_atomic_t ocg_sigint_seen;

/* the executable segments of the object holding `address` */
static int ocg_add_object(struct dl_phdr_info *info, size_t size, void *address) {
  int i, found = 0;
  uintptr_t a = (uintptr_t)address;
  (void)size;
  for (i = 0; i < info->dlpi_phnum; ++i) {
    const ElfW(Phdr) *ph = &info->dlpi_phdr[i];
    uintptr_t lo = info->dlpi_addr + ph->p_vaddr;
    if (ph->p_type == PT_LOAD && a >= lo && a < lo + ph->p_memsz) found = 1;
  }
  if (!found) return 0;
  for (i = 0; i < info->dlpi_phnum && ocg_n_ranges < OCG_RANGES; ++i) {
    const ElfW(Phdr) *ph = &info->dlpi_phdr[i];
    if (ph->p_type == PT_LOAD && (ph->p_flags & PF_X)) {
      ocg_lo[ocg_n_ranges] = info->dlpi_addr + ph->p_vaddr;
      ocg_hi[ocg_n_ranges++] = info->dlpi_addr + ph->p_vaddr + ph->p_memsz;
    }
  }
  return 1;
}

static int ocg_jumpable(uintptr_t pc) {
  int i;
  for (i = 0; i < ocg_n_ranges; ++i)
    if (pc >= ocg_lo[i] && pc < ocg_hi[i]) return 1;
  return 0;
}

static uintptr_t ocg_pc(void *context) {
  ucontext_t *uc = (ucontext_t *)context;
#if defined(__x86_64__)
  return (uintptr_t)uc->uc_mcontext.gregs[REG_RIP];
#elif defined(__aarch64__)
  return (uintptr_t)uc->uc_mcontext.pc;
#else
  (void)uc;
  return 0;
#endif
}

static struct timespec ocg_timespec(double seconds) {
  struct timespec t;
  t.tv_sec = (time_t)seconds;
  t.tv_nsec = (long)((seconds - (double)t.tv_sec) * 1e9);
  if (t.tv_nsec >= 1000000000L) t.tv_nsec = 999999999L;
  if (t.tv_sec == 0 && t.tv_nsec == 0) t.tv_nsec = 1; /* zero would disarm the timer */
  return t;
}

static void ocg_retry_soon(struct ocg_guard *g) {
  struct itimerspec t;
  t.it_value = t.it_interval = ocg_timespec(1e-3);
  timer_settime(g->timer, 0, &t, NULL);
}

static void ocg_on_timer(int sig, siginfo_t *info, void *context) {
  struct ocg_guard *g = (struct ocg_guard *)info->si_value.sival_ptr;
  (void)sig;
  if (info->si_code != SI_TIMER || !g || !g->armed) return;
  if (ocg_sigint_seen && g->sigint) g->reason = OCG_LEFT_STOP;
  else if (ocg_now() >= g->deadline) g->reason = OCG_LEFT_TIME;
  else return;
  if (!ocg_jumpable(ocg_pc(context))) {
    ocg_retry_soon(g);
    return;
  }
  g->armed = 0;
  siglongjmp(g->env, 1);
}

static struct ocg_guard *ocg_sigint_guard; /* the guarded call that watches Ctrl-C */

static void ocg_on_sigint(int sig, siginfo_t *info, void *context) {
  struct ocg_guard *g = ocg_sigint_guard;
  ocg_sigint_seen = 1;
  if (!g) return;
  if (g->previous_sigint.sa_flags & SA_SIGINFO) g->previous_sigint.sa_sigaction(sig, info, context);
  else g->previous_sigint.sa_handler(sig);
}

/* Whether calls can be guarded here: the instruction pointer of an interrupted thread is
 * readable (x86-64, AArch64), the code ranges are found, and a real-time signal is free for
 * the timer (its handler installed once, for the life of the process). */
int ocg_guard_available(void) {
  struct sigaction action, old;
  int candidate;
  if (ocg_ready >= 0) return ocg_ready;
  ocg_ready = 0;
#if !defined(__x86_64__) && !defined(__aarch64__)
  return 0;
#endif
  dl_iterate_phdr(ocg_add_object, (void *)&fatrop_ocp_c_solve);
  dl_iterate_phdr(ocg_add_object, (void *)&blasfeo_dgese);
  dl_iterate_phdr(ocg_add_object, (void *)&ocg_guard_available);
  if (ocg_n_ranges < 3) return 0;
  for (candidate = SIGRTMIN + 4; candidate <= SIGRTMAX; ++candidate) {
    if (sigaction(candidate, NULL, &old) != 0) continue;
    if (!(old.sa_flags & SA_SIGINFO) && old.sa_handler == SIG_DFL) break;
  }
  if (candidate > SIGRTMAX) return 0;
  memset(&action, 0, sizeof action);
  action.sa_sigaction = ocg_on_timer;
  action.sa_flags = SA_SIGINFO | SA_RESTART;
  sigemptyset(&action.sa_mask);
  if (sigaction(candidate, &action, NULL) != 0) return 0;
  ocg_signal = candidate;
  ocg_ready = 1;
  return 1;
}

/* Arm the guard for `seconds` (after sigsetjmp(g->env, 1) in the caller); 0 when the timer
 * cannot be created. */
int ocg_guard_arm(struct ocg_guard *g, double seconds, int watch_sigint) {
  struct sigevent event;
  struct itimerspec t;
  struct sigaction action;
  sigset_t only;
  double now = ocg_now(), tick = g->every > 1e-3 ? g->every : 1e-3;
  double first = seconds < tick ? seconds : tick;
  if (ocg_guard_available() != 1) return 0;
  memset(&event, 0, sizeof event);
  event.sigev_notify = SIGEV_THREAD_ID;
  event.sigev_signo = ocg_signal;
  event.sigev_value.sival_ptr = g;
  event.sigev_notify_thread_id = (pid_t)syscall(SYS_gettid);
  g->reason = OCG_LEFT_NONE;
  g->nans = 0;
  g->deadline = now + seconds;
  g->next_check = now + g->every;
  g->has_timer = timer_create(CLOCK_MONOTONIC, &event, &g->timer) == 0;
  if (!g->has_timer) return 0;
  sigemptyset(&only);
  sigaddset(&only, ocg_signal);
  pthread_sigmask(SIG_UNBLOCK, &only, &g->mask);
  g->sigint = 0;
  if (watch_sigint) {
    memset(&action, 0, sizeof action);
    action.sa_sigaction = ocg_on_sigint;
    action.sa_flags = SA_SIGINFO | SA_RESTART;
    sigemptyset(&action.sa_mask);
    if (sigaction(SIGINT, NULL, &g->previous_sigint) == 0 &&
        !(g->previous_sigint.sa_flags & SA_SIGINFO) &&
        (g->previous_sigint.sa_handler == SIG_DFL || g->previous_sigint.sa_handler == SIG_IGN)) {
      /* no handler to pass Ctrl-C on to: it keeps its usual effect */
    } else {
      ocg_sigint_seen = 0;
      ocg_sigint_guard = g;
      g->sigint = sigaction(SIGINT, &action, NULL) == 0;
    }
  }
  g->armed = 1;
  t.it_value = ocg_timespec(first > 0 ? first : 0);
  t.it_interval = ocg_timespec(tick);
  timer_settime(g->timer, 0, &t, NULL);
  return 1;
}

/* Disarm: after the call returned, or once it was left (then from the sigsetjmp branch). */
void ocg_guard_disarm(struct ocg_guard *g) {
  g->armed = 0;
  if (g->has_timer) timer_delete(g->timer); /* a signal still pending is delivered here */
  g->has_timer = 0;
  if (g->sigint) {
    sigaction(SIGINT, &g->previous_sigint, NULL);
    ocg_sigint_guard = NULL;
    g->sigint = 0;
  }
  pthread_sigmask(SIG_SETMASK, &g->mask, NULL);
}

static void ocg_leave(struct ocg_guard *g, int reason) {
  g->reason = reason;
  g->armed = 0;
  siglongjmp(g->env, 1);
}

/* From a callback: leave if the call is due to be left (the caller's check asked at most
 * every `every` seconds). */
void ocg_guard_poll(struct ocg_guard *g) {
  double now;
  if (!g || !g->armed) return;
  if (g->sigint && ocg_sigint_seen) ocg_leave(g, OCG_LEFT_STOP);
  now = ocg_now();
  if (now >= g->deadline) ocg_leave(g, OCG_LEFT_TIME);
  if (g->check && now >= g->next_check) {
    g->next_check = now + g->every;
    if (g->check()) ocg_leave(g, OCG_LEFT_STOP);
  }
}

/* From a callback: one more non-finite evaluation; leave at the limit. */
void ocg_guard_nan(struct ocg_guard *g) {
  if (!g || !g->armed) return;
  if (++g->nans >= g->nan_limit) ocg_leave(g, OCG_LEFT_NAN);
}
#endif
