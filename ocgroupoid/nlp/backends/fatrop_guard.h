/* A call into fatrop that can be left: at a deadline, after too many non-finite evaluations,
 * on Ctrl-C, or when the caller asks (fatrop_guard.c). */
#ifndef OCG_FATROP_GUARD_H
#define OCG_FATROP_GUARD_H

#include <setjmp.h>
#include <signal.h>
#include <time.h>

/* why a guarded call was left (ocg_guard.reason) */
enum { OCG_LEFT_NONE = 0, OCG_LEFT_TIME = 1, OCG_LEFT_NAN = 2, OCG_LEFT_STOP = 3 };

struct ocg_guard {
  sigjmp_buf env;               /* where the call is left to (sigsetjmp in the caller) */
  volatile sig_atomic_t armed;  /* between ocg_guard_arm and ocg_guard_disarm */
  volatile sig_atomic_t reason; /* OCG_LEFT_* */
  double deadline;              /* CLOCK_MONOTONIC seconds */
  double every, next_check;     /* the caller's stop request, asked every `every` seconds */
  int (*check)(void);           /* nonzero: stop (NULL: never asked) */
  int nans, nan_limit;          /* non-finite evaluations so far; the most let through */
#if defined(__linux__)
  timer_t timer;
#endif
  int has_timer, sigint;        /* whether Ctrl-C is watched in this call */
  sigset_t mask;                /* the thread's signal mask before the call */
  struct sigaction previous_sigint;
};

double ocg_now(void); /* CLOCK_MONOTONIC seconds (fatrop_ocp.c) */
int ocg_guard_available(void);
int ocg_guard_arm(struct ocg_guard *g, double seconds, int watch_sigint);
void ocg_guard_disarm(struct ocg_guard *g);
void ocg_guard_poll(struct ocg_guard *g);
void ocg_guard_nan(struct ocg_guard *g);

#endif
