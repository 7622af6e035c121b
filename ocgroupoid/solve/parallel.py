"""Multi-start in parallel: the starts of one grid solved by worker processes on the cores.

**Processes, not threads.** CasADi holds Python's GIL through an IPOPT solve: two starts of
``quadrotor.yaml`` (N = 64) in two threads, each with its own nlpsol, took 0.95-1.1 s against
0.9-1.0 s one after the other. Starts overlap only in separate processes.

**How the solver gets into a worker.** The workers are forked from the solving process at
the first multi-start of a transcription, so each holds the compiled
:class:`~ocgroupoid.nlp.transcription.Transcription` as it is: its nlpsol instances, the
iteration callback, the libraries ``solver.jit`` loaded and any Python hook of the problem, for
the price of a fork (2-5 ms each for so3 at N = 64, measured 2026-12-04). The alternatives cost
more and cover less: serialising IPOPT's nlpsol Function took 0.11 s, its 11 MB through a pipe
and 0.13 s to deserialise, and the iteration callback (a Python object) has to be rebuilt
beside it; rebuilding the transcription from the problem took 0.34 s, and a problem holding
CasADi SX expressions or Python hooks does not pickle in general. A worker's copy of a fatrop
backend forks its own helper where it needs one (:mod:`~ocgroupoid.nlp.isolated`). Only the
start (its guess and the parameters) goes to a worker and only its
:class:`~ocgroupoid.nlp.transcription.RawResult` comes back.

**The workers are kept.** Once a multi-start has ended the workers wait for the next one of the
same transcription (and rescue) on as many workers: a solve repeated on one grid (a sweep, a
controller's next sample, a benchmark's repeats) pays neither the forks nor the first solve of
a fresh process, which writes to the pages it shares with its parent (so3, N = 64: 1435 page
faults, and that start 10-20 ms slower than in the solving process, measured). One set of
workers lives at a time: a multi-start of another transcription ends them and forks its own,
as do a worker that died or a start that failed in it, Ctrl-C and the deadline; :func:`close`
ends them, and so does the end of the solving process. What changes in the solving process
after the fork (a Python hook's globals, a patched function) does not reach kept workers: call
:func:`close` after such a change.

**The same result as one start after the other.** Starts are handed out in their order and
reported in it, whatever order they finish in. The iteration budget of a further start
(``START_BUDGET`` of :mod:`~ocgroupoid.solve.compiled`, a multiple of the first start's
iterations) is kept exactly: a further start that reaches the smallest budget before the first
start has finished waits for it, then goes on or stops at the same iteration as it would have
in turn. So every start runs the same iterations from the same point, and the best start,
the distinct minima and the verdict are the sequential path's. The one exception is a further
start that crawls: its seconds are bounded too (:class:`Budget`), and where a clock stops a
start depends on the machine's load, in turn as in parallel.

**No early stop.** Nothing stops a running start because another one did well: IPOPT's
iterates of a nonconvex NLP give no lower bound on the cost a start will end at (an
infeasible iterate's objective says nothing, and the objective of a feasible one may still
fall below any other start's), and a local solver never certifies a minimum as the best. A
criterion that stopped starts early could drop the best minimum, so there is none; the
budget is the only limit, as in turn.

**Ctrl-C, the deadline and failures.** The workers ignore SIGINT; the solving process, which
catches it (:mod:`~ocgroupoid.solve.interrupt`), or its deadline sets a stop event that every
worker's iteration callback (and fatrop's ``stop()``) reads: the running starts end at their
next iteration and come back, the starts not handed out are skipped, as in turn. A start that
raises in its worker, or whose worker dies, is reported as a failed start (status
:data:`WORKER_FAILED`, the error in the report) and the others go on.
"""

from __future__ import annotations

import atexit
import multiprocessing as mp
import os
import signal
import threading
import time
import warnings
from dataclasses import dataclass, replace
from multiprocessing.connection import Connection, wait
from typing import Any, Callable, Sequence

import numpy as np

from ..nlp.backends import INTERRUPTED, TIMED_OUT, IpoptBackend
from ..nlp.backends.policy import Rescue
from ..nlp.program import Guess
from ..nlp.transcription import RawResult, Transcription
from .interrupt import Interrupt

#: the status of a start that raised in its worker process or lost it
WORKER_FAILED = "Worker_Failed"
#: the status of a further start stopped by its :class:`Budget`
BUDGET_SPENT = "Start_Budget_Spent"
#: a further start's budget before the first start has finished, and when it has none
_UNKNOWN, _UNLIMITED = -2, -1
#: seconds between two looks at Ctrl-C, the deadline and the workers
POLL = 0.05
#: seconds the workers get to stop at their next iteration before they are killed
GRACE = 5.0


@dataclass(frozen=True)
class Rule:
    """How a further start's budget follows from the first start: ``least`` iterations at
    least, ``times`` its iterations, and ``pace`` times its seconds per iteration over them,
    but never less than ``least_seconds``.

    The seconds catch a start that crawls: the heavy top with rotors from the long way round
    (order4, N = 128) diverges with IPOPT's regularisation at 1e10 and MUMPS reallocating, at
    about 1 s an iteration against the first start's 24-27 ms; its 66 iterations took 69 s where
    the eight other starts took 7 s together. Their floor keeps a start's fixed costs (a
    fatrop helper's, a fallback's) from stopping a quick start: the plate-ball's long way round
    (first-order rule, N = 16, fatrop) took 0.08 s where its first start's pace gave it 0.09 s."""

    least: int
    times: int
    pace: float
    least_seconds: float


@dataclass(frozen=True)
class Budget:
    """What a further start may spend: iterations, and seconds of its own solve."""

    iterations: int
    seconds: float

    def spent(self, iteration: int, seconds: float) -> bool:
        """Whether a start at ``iteration`` after ``seconds`` has used its budget."""
        return iteration >= self.iterations or seconds >= self.seconds


def budget_after(first: RawResult, rule: Rule) -> Budget | None:
    """A further start's budget once the first start has ended (no limit, None, when it
    failed): max(least, times x its iterations), and pace x its seconds per iteration over
    them, at least least_seconds."""
    if not first.success:
        return None
    iterations = max(rule.least, rule.times * first.iterations)
    return Budget(iterations, max(rule.least_seconds, rule.pace * iterations
                                  * first.solve_seconds / max(first.iterations, 1)))


def budgeted(r: RawResult, deadline: float, stopped: bool) -> RawResult:
    """A further start's ``r``, its status :data:`BUDGET_SPENT` when its run was stopped (by
    IPOPT's listener or fatrop's ``stop()``) and neither by the deadline nor, ``stopped``, by
    Ctrl-C or the stop event: then its budget stopped it."""
    if not r.success and r.status in ("User_Requested_Stop", INTERRUPTED) and not stopped \
            and time.monotonic() <= deadline:
        return replace(r, status=BUDGET_SPENT)
    return r


def timed(r: RawResult, deadline: float) -> RawResult:
    """``r``, its status ``TIMED_OUT`` when its listener stopped it past the deadline."""
    if r.status == "User_Requested_Stop" and time.monotonic() > deadline:
        return replace(r, status=TIMED_OUT)
    return r


def iteration_line(where: str, iteration: int, objective: float, infeasibility: float
                   ) -> str:
    """How progress reports one iteration of a start."""
    return (f"{where}: iteration {iteration}, objective {objective:.6g}, "
            f"infeasibility {infeasibility:.1e}")


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def plan(workers: int | None, starts: int) -> tuple[int, str]:
    """The worker processes for ``starts`` starts (1: in turn, in this process) and, when
    more were asked for than can run, why. ``workers`` None (the default) means one per core,
    and in turn away from the main thread (a host that runs threads, such as a Dask worker,
    keeps its cores); never more than the starts."""
    want = min(cores() if workers is None else workers, starts)
    if want < 2:
        return 1, ""
    if workers is None and threading.current_thread() is not threading.main_thread():
        return 1, ""
    if "fork" not in mp.get_all_start_methods():
        return 1, "in turn: this system cannot fork worker processes"
    if mp.current_process().daemon:
        return 1, "in turn: a daemonic process (a worker of a pool) cannot start workers"
    return want, ""


@dataclass(frozen=True)
class _Shared:
    """What every worker reads: the stop event, the further starts' budget (iterations and
    seconds, shared numbers) and the solving process's pid (a worker whose parent is gone
    ends)."""

    stop: Any
    budget: Any
    seconds: Any
    parent: int

    def reset(self) -> None:
        """Before a multi-start on kept workers: no stop, the first start's budget unknown."""
        self.stop.clear()
        self.seconds.value = 0.0
        self.budget.value = _UNKNOWN


@dataclass(frozen=True)
class _Task:
    """One start as a worker gets it: its number, guess, parameters and deadline, the
    further starts' budget rule and the seconds between two progress messages."""

    i: int
    guess: Guess
    p: np.ndarray
    deadline: float
    rule: Rule
    every: float


def _over(i: int, shared: _Shared, began: float, waited: list[float]) -> Callable[[], bool]:
    """Whether start i's fatrop run (which has no iteration callback) should stop, asked by its
    guard or its helper: the stop event, or the seconds of a further start's budget spent (the
    seconds it waited at the smallest budget not counted)."""
    def over() -> bool:
        if shared.stop.is_set():
            return True
        if i == 0 or shared.budget.value in (_UNKNOWN, _UNLIMITED):
            return False
        return time.perf_counter() - began - waited[0] >= shared.seconds.value

    return over


def _listener(conn: Connection, task: _Task, shared: _Shared,
              waited: list[float]) -> Callable[[int, float, float], bool]:
    """A worker's iteration callback: progress to the solving process at most every
    ``task.every`` seconds; stop on the stop event, past the deadline, or at the budget of a
    further start, waiting at the smallest budget until the first start has set it (the
    seconds waited added to ``waited[0]``: not the start's solver time)."""
    i, deadline, rule = task.i, task.deadline, task.rule
    last = [time.perf_counter()]
    began = last[0]

    def stopped() -> bool:
        return shared.stop.is_set() or time.monotonic() > deadline or \
            os.getppid() != shared.parent

    def listen(iteration: int, objective: float, infeasibility: float) -> bool:
        now = time.perf_counter()
        if now - last[0] >= task.every:
            last[0] = now
            conn.send(("progress", i, (iteration, objective, infeasibility)))
        if stopped():
            return True
        if i == 0:
            return False
        if shared.budget.value == _UNKNOWN:  # the first start is still running
            if iteration < rule.least:
                return False
            t0 = time.perf_counter()
            try:
                while shared.budget.value == _UNKNOWN:
                    time.sleep(POLL / 10)
                    if stopped():
                        return True
            finally:
                waited[0] += time.perf_counter() - t0
        if shared.budget.value == _UNLIMITED:
            return False
        return Budget(shared.budget.value, shared.seconds.value).spent(
            iteration, time.perf_counter() - began - waited[0])

    return listen


def _serve(conn: Connection, tr: Transcription, shared: _Shared,
           rescue: Rescue | None) -> None:
    """A worker's loop: solve each start sent (the first with ``rescue``), answer ``done``
    with its result or ``error`` with what it raised; end on None, or when the solving
    process is gone."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the solving process's
    while True:
        while not conn.poll(1.0):
            if os.getppid() != shared.parent:
                return
        task: _Task | None = conn.recv()
        if task is None:
            return
        i = task.i
        waited = [0.0]
        try:
            r = tr.solve(task.guess, task.p, _listener(conn, task, shared, waited),
                         task.deadline, _over(i, shared, time.perf_counter(), waited),
                         rescue if i == 0 else None)
            if i > 0:
                r = budgeted(r, task.deadline, shared.stop.is_set())
            conn.send(("done", i, replace(r, solve_seconds=r.solve_seconds - waited[0])))
        except Exception as err:  # noqa: BLE001  (reported as a failed start)
            conn.send(("error", i, f"{type(err).__name__}: {err}"))


def _failed(tr: Transcription, guess: Guess, p: np.ndarray, why: str) -> RawResult:
    """The result of a start that failed in its worker: its start point, no cost."""
    x0, _ = tr.start_point(guess, p)
    return RawResult(guess.label, np.asarray(x0, dtype=float), p, np.zeros(tr.ng),
                     float("inf"), WORKER_FAILED, False, 0, 0.0, np.zeros(tr.nx))


@dataclass
class _Pool:
    """Worker processes forked from the solving process (``owner``) for one transcription
    and rescue, kept between multi-starts (module docstring)."""

    owner: int
    tr: Transcription
    rescue: Rescue | None
    shared: _Shared
    conns: list[Connection]
    procs: list[Any]

    def serves(self, tr: Transcription, workers: int, rescue: Rescue | None) -> bool:
        """Whether these workers, all alive, can solve the starts of ``tr`` with ``rescue``
        on ``workers`` processes."""
        return (self.owner == os.getpid() and self.tr is tr and self.rescue is rescue
                and len(self.procs) == workers and all(p.is_alive() for p in self.procs))

    def close(self) -> None:
        """End the workers: stop their starts, tell them to end, kill those still running
        after :data:`GRACE` seconds."""
        if self.owner != os.getpid():  # a copy in a forked child: not its workers
            return
        self.shared.stop.set()
        for conn, proc in zip(self.conns, self.procs):
            if proc.is_alive():
                try:
                    conn.send(None)
                except OSError:
                    pass
        end = time.monotonic() + GRACE
        for proc in self.procs:
            proc.join(max(0.0, end - time.monotonic()))
            if proc.is_alive():
                proc.kill()
                proc.join()
        for conn in self.conns:
            conn.close()


_kept: _Pool | None = None  # the workers of the last multi-start, if kept


def close() -> None:
    """End the worker processes the last multi-start kept for the next one, if any
    (:mod:`ocgroupoid.solve.parallel`): after a change in this process they should see (what a
    Python hook of the problem reads), or to free them; the next multi-start forks new ones."""
    global _kept
    pool, _kept = _kept, None
    if pool is not None:
        pool.close()


atexit.register(close)


def _pool(tr: Transcription, workers: int, rescue: Rescue | None) -> _Pool:
    """The kept workers when they serve ``tr`` and ``rescue`` on ``workers`` processes, ready
    for a multi-start; else (the kept ones ended) ``workers`` new ones."""
    global _kept
    if _kept is not None and _kept.serves(tr, workers, rescue):
        pool, _kept = _kept, None
        pool.shared.reset()
        return pool
    close()
    ctx = mp.get_context("fork")
    for backend in tr.backends:  # IPOPT's instance with the iteration callback, built once
        if isinstance(backend, IpoptBackend):  # here for every worker (else in each)
            backend.watched_solver  # noqa: B018
    shared = _Shared(ctx.Event(), ctx.RawValue("q", _UNKNOWN), ctx.RawValue("d", 0.0),
                     os.getpid())
    pool = _Pool(os.getpid(), tr, rescue, shared, [], [])
    with warnings.catch_warnings():  # a multi-threaded caller: the workers have one thread
        warnings.simplefilter("ignore", DeprecationWarning)
        for _ in range(workers):
            mine, theirs = ctx.Pipe()
            proc = ctx.Process(target=_serve, args=(theirs, tr, shared, rescue), daemon=True)
            proc.start()
            theirs.close()
            pool.conns.append(mine)
            pool.procs.append(proc)
    return pool


def run(tr: Transcription, starts: Sequence[Guess], p: np.ndarray, workers: int,
        where: Callable[[int], str], progress: Callable[[str], None], interrupt: Interrupt,
        deadline: float, rule: Rule, every: float, rescue: Rescue | None = None
        ) -> tuple[list[RawResult], list[dict[str, Any]]]:
    """Solve ``starts`` on ``workers`` forked processes (module docstring): the results of
    the starts that ran, in their order, and the starts that failed in a worker (number from
    1, label, error). ``where(i)`` names start i for ``progress``, which hears each start as
    it is handed out and as it finishes, and the workers' iterations; ``rule`` is the
    further starts' budget, ``every`` the seconds between two progress messages
    of a start. The workers are kept for the next multi-start when every start ran and
    none was stopped (:func:`close` ends them)."""
    global _kept
    pool = _pool(tr, workers, rescue)
    shared, conns, procs = pool.shared, pool.conns, pool.procs
    failed: list[dict[str, Any]] = []
    results: dict[int, RawResult] = {}
    todo = list(range(len(starts)))
    running: dict[int, int] = {}  # worker -> the start it solves

    def fail(i: int, why: str) -> None:
        results[i] = _failed(tr, starts[i], p, why)
        failed.append({"start": i + 1, "label": starts[i].label, "error": why})
        progress(f"{where(i)}: failed in its worker ({why})")

    try:
        while todo or running:
            alive = [w for w, proc in enumerate(procs) if proc.is_alive()]
            for w in alive:
                if w not in running and todo:
                    i = todo.pop(0)
                    progress(where(i))
                    running[w] = i
                    try:
                        conns[w].send(_Task(i, starts[i], p, deadline, rule, every))
                    except OSError:  # it died: its sentinel says so below
                        pass
            if not alive:  # every worker died: what is left cannot run
                for i in todo:
                    fail(i, "not run: every worker process died")
                todo.clear()
            if interrupt.requested or time.monotonic() > deadline:  # the first start ran
                shared.stop.set()
                todo.clear()
            ready = wait([conns[w] for w in running] + [procs[w].sentinel for w in running],
                         POLL)
            for w in list(running):
                if conns[w] in ready or procs[w].sentinel in ready:
                    _receive(w, conns[w], procs[w], running, results, shared, fail, where,
                             progress, deadline, len(starts), rule)
    finally:
        if running or shared.stop.is_set() or failed:
            pool.close()
        else:
            close()  # another thread's workers, kept meanwhile: one set at a time
            _kept = pool
    return [results[i] for i in sorted(results)], failed


def _receive(w: int, conn: Connection, proc: Any, running: dict[int, int],
             results: dict[int, RawResult], shared: _Shared, fail: Callable[[int, str], None],
             where: Callable[[int], str], progress: Callable[[str], None], deadline: float,
             total: int, rule: Rule) -> None:
    """Read what worker w sent: progress, its start's result or error; or see it dead."""
    i = running[w]
    while conn.poll():
        try:
            kind, j, value = conn.recv()
        except (EOFError, OSError):
            break
        if kind == "progress":
            progress(iteration_line(where(j), *value))
            continue
        del running[w]
        if kind == "error":
            fail(j, value)
        else:
            r: RawResult = timed(value, deadline)
            results[j] = r
            progress(f"{len(results)}/{total} starts done; {where(j)}: {r.status}")
        _settle(shared, rule, j, results.get(j))
        return
    if not proc.is_alive():
        del running[w]
        code = proc.exitcode
        fail(i, "its worker process died (" + (f"signal {-code}" if code is not None and
                                                code < 0 else f"exit code {code}") + ")")
        _settle(shared, rule, i, None)


def _settle(shared: _Shared, rule: Rule, i: int, r: RawResult | None) -> None:
    """Once the first start has ended: the further starts' budget (:func:`budget_after`;
    none when it failed), as in turn."""
    if i == 0:
        budget = None if r is None else budget_after(r, rule)
        if budget is not None:
            shared.seconds.value = budget.seconds  # before the iterations, which workers poll
        shared.budget.value = _UNLIMITED if budget is None else budget.iterations
