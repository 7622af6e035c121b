"""Multi-start in parallel: the starts of one grid solved by worker processes on the cores.

**Processes, not threads.** CasADi holds Python's GIL through an IPOPT solve: two starts of
``quadrotor.yaml`` (N = 64) in two threads, each with its own nlpsol, took 0.95-1.1 s against
0.9-1.0 s one after the other. Starts overlap only in separate processes.

**The solving process is one of the workers.** With ``workers`` w, w - 1 processes are forked
and the solving process solves starts too: the first start (the one with the rescue of a
fatrop grid, whose iterations set the others' budget if it succeeds), then, like the forked
workers, the next start nobody has taken, until none is left (:meth:`_Shared.take`: a shared
counter under a lock, so that whoever is free takes the next start, in their order). Between
its iterations it reads what the workers sent, so their progress reaches the caller as it
happens. On two cores this forks one process, not two, and the first start runs where
nothing has to be copied: so3's six starts at N = 64 (about 30 ms each), timed one by one,
ran in 0.59 of their time in turn at the first multi-start of a process and 0.50 at the next
ones; ``scripts/bench_multistart.py`` gives medians of 0.52-0.58 on the problem files, and
0.57-0.81 for a process's first parallel solve (measured 2026-12-04, late).

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
starts (their guesses and the parameters) go to a worker and only each start's
:class:`~ocgroupoid.nlp.transcription.RawResult` comes back.

**The workers are kept.** Once a multi-start has ended the workers wait for the next one of the
same transcription on as many workers: a solve repeated on one grid (a sweep, a
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
(``START_BUDGET`` of :mod:`~ocgroupoid.solve.compiled`, a multiple of the iterations of the
first start that succeeded before it, :func:`budget_of`) is kept exactly: a further start
that reaches the smallest budget before the starts ahead of it have decided its budget waits
for them, then goes on or stops at the same iteration as it would have in turn. So every
start runs the same iterations from the same point, and the best start, the distinct minima
and the verdict are the sequential path's. The one exception is a further
start that crawls: its seconds are bounded too (:class:`Budget`), and where a clock stops a
start depends on the machine's load, in turn as in parallel.

**No early stop.** Nothing stops a running start because another one did well: IPOPT's
iterates of a nonconvex NLP give no lower bound on the cost a start will end at (an
infeasible iterate's objective says nothing, and the objective of a feasible one may still
fall below any other start's), and a local solver never certifies a minimum as the best. A
criterion that stopped starts early could drop the best minimum, so there is none; the
budget is the only limit, as in turn.

**Ctrl-C, the deadline and failures.** The workers ignore SIGINT; the solving process, which
catches it (:mod:`~ocgroupoid.solve.interrupt`), or its deadline sets a stop event that
every worker's iteration callback (IPOPT's, fatrop's) and fatrop's ``stop()`` read: the
running starts end at their next iteration and come back, the starts not handed out are
skipped, as in turn. A start that raises in a forked worker, or whose worker dies, is
reported as a failed start (status :data:`WORKER_FAILED`, the error in the report) and the
others go on (a worker that died takes no more, the others and the solving process take
them); a start that raises in the solving process raises, as in turn.
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
from functools import partial
from multiprocessing.connection import Connection, wait
from typing import Any, Callable, Sequence

import numpy as np

from ..nlp.backends import INTERRUPTED, LISTENER_STOP, TIMED_OUT, IpoptBackend
from ..nlp.backends.policy import Rescue
from ..nlp.program import Guess
from ..nlp.transcription import RawResult, Transcription
from ..nlp.watch import Listener
from .interrupt import Interrupt

#: the status of a start that raised in its worker process or lost it
WORKER_FAILED = "Worker_Failed"
#: the status of a further start stopped by its :class:`Budget`
BUDGET_SPENT = "Start_Budget_Spent"
#: the further starts' budget before a start has succeeded
_UNKNOWN = -2
#: no start (a worker that took none)
_NONE = -1
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


#: what a further start's budget is, asked at one of its iterations: (True, the budget) once
#: the starts ahead of it have decided it (None: no limit), (False, None) until then
Ask = Callable[[], "tuple[bool, Budget | None]"]


def fixed(budget: Budget | None) -> Ask:
    """The budget of a start that is known before it runs (None: no limit)."""
    return lambda: (True, budget)


def settled(ask: Ask) -> Ask:
    """``ask``, asked no more once it has answered (a decided budget does not change within
    a multi-start): the solving process's iteration callback asks at every iteration, and
    its ask scans the starts ended before. (A worker reads two shared numbers instead.)"""
    known: list[Budget | None] = []

    def asked() -> tuple[bool, Budget | None]:
        if known:
            return True, known[0]
        decided, budget = ask()
        if decided:
            known.append(budget)
        return decided, budget

    return asked


def budget_after(first: RawResult, rule: Rule) -> Budget | None:
    """The budget a start gives the starts after it once it has ended (no limit, None, when it
    failed): max(least, times x its iterations), and pace x its seconds per iteration over
    them, at least least_seconds. Its iterations are those of all its runs (fatrop's before
    IPOPT's polish: ``first.earlier``), as its seconds are; a further start's runs are each
    held to the budget (the listener counts a run's iterations)."""
    if not first.success:
        return None
    done = first.iterations + sum(iterations for _, _, iterations in first.earlier)
    iterations = max(rule.least, rule.times * done)
    return Budget(iterations, max(rule.least_seconds, rule.pace * iterations
                                  * first.solve_seconds / max(done, 1)))


def budget_of(ended: dict[int, RawResult], k: int, rule: Rule) -> tuple[bool, Budget | None]:
    """Start k's budget from the starts ``ended`` before it (by their number): that of the
    first of them that succeeded (:func:`budget_after`), no limit when all of them failed,
    unknown (False) while one ahead of that first success is still running. A first start
    that failed says nothing of what a solve takes, so it sets no budget; the next one that
    succeeds does (before, every start after a failed first ran without a limit: on a fine
    grid, each to its iteration limit)."""
    for j in range(k):
        if j not in ended:
            return False, None
        if ended[j].success:
            return True, budget_after(ended[j], rule)
    return True, None


def budgeted(r: RawResult, deadline: float, stopped: bool) -> RawResult:
    """A further start's ``r``, its status :data:`BUDGET_SPENT` when its run was stopped (by
    IPOPT's listener or fatrop's ``stop()``) and neither by the deadline nor, ``stopped``, by
    Ctrl-C or the stop event: then its budget stopped it."""
    if not r.success and r.status in (LISTENER_STOP, INTERRUPTED) and not stopped \
            and time.monotonic() <= deadline:
        return replace(r, status=BUDGET_SPENT)
    return r


def timed(r: RawResult, deadline: float) -> RawResult:
    """``r``, its status ``TIMED_OUT`` when its listener stopped it past the deadline."""
    if r.status == LISTENER_STOP and time.monotonic() > deadline:
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
    """What the solving process and its workers share: the stop event, the further starts'
    budget (iterations and seconds, set by the first start that succeeded, number ``lead``;
    before that ``lead`` counts the starts that failed from the first on), the next start to
    hand out and the start each worker took (shared numbers; ``lock`` guards the handing out),
    and the solving process's pid (a worker whose parent is gone ends)."""

    stop: Any
    budget: Any
    seconds: Any
    lead: Any
    next: Any
    taken: Any
    lock: Any
    parent: int

    @classmethod
    def make(cls, ctx: Any, workers: int) -> _Shared:
        """For ``workers`` workers of this process, from the multiprocessing context ``ctx``."""
        return cls(ctx.Event(), ctx.RawValue("q", _UNKNOWN), ctx.RawValue("d", 0.0),
                   ctx.RawValue("q", 0), ctx.RawValue("q", 1),
                   ctx.RawArray("q", [_NONE] * workers), ctx.Lock(), os.getpid())

    def reset(self) -> None:
        """Before a multi-start: no stop, the further starts' budget unknown, the second
        start the next to hand out (the first is the solving process's), none taken."""
        self.stop.clear()
        self.seconds.value = 0.0
        self.budget.value = _UNKNOWN
        self.lead.value = 0
        self.next.value = 1
        for w in range(len(self.taken)):
            self.taken[w] = _NONE

    def publish(self, ended: dict[int, RawResult], rule: Rule) -> None:
        """What the starts ``ended`` (by their number) decide of the budget, for the workers
        (:meth:`budget_of`): the failed starts from the first on (``lead``), then the budget
        of the first that succeeded. ``lead`` is written before the budget, which a worker
        reads first: once it sees the budget, ``lead`` is final."""
        if self.budget.value != _UNKNOWN:
            return
        lead = self.lead.value
        while lead in ended and not ended[lead].success:
            lead += 1
        self.lead.value = lead
        if lead in ended:
            budget = budget_after(ended[lead], rule)
            assert budget is not None
            self.seconds.value = budget.seconds
            self.budget.value = budget.iterations

    def budget_of(self, k: int) -> tuple[bool, Budget | None]:
        """Start k's budget as :func:`budget_of` gives it, from what the solving process
        published (:meth:`publish`)."""
        iterations = self.budget.value
        lead = self.lead.value
        if iterations != _UNKNOWN:
            return True, Budget(iterations, self.seconds.value) if k > lead else None
        return lead >= k, None

    def take(self, total: int, deadline: float, w: int | None) -> int | None:
        """The next of ``total`` starts, handed out (to worker ``w``, None: the solving
        process); None when every start is out, or after the stop or the deadline (none is
        started then, as in turn)."""
        with self.lock:
            i = self.next.value
            if i >= total or self.stop.is_set() or time.monotonic() > deadline:
                return None
            self.next.value = i + 1
            if w is not None:
                self.taken[w] = i
            return i


@dataclass(frozen=True)
class _Batch:
    """The starts of one multi-start as the workers get them: their guesses, parameters and
    deadline, the further starts' budget rule and the seconds between two progress messages
    of a start."""

    starts: tuple[Guess, ...]
    p: np.ndarray
    deadline: float
    rule: Rule
    every: float


def _spent(ask: Ask, iteration: int, began: float, least: int, halted: Callable[[], bool],
           pause: Callable[[], None], waited: list[float]) -> bool:
    """Whether a further start at ``iteration``, begun at ``began`` (``time.perf_counter()``),
    has used its budget (``ask``), waiting at the smallest budget (``least`` iterations) while
    the starts ahead of it have not decided it: ``pause()`` between two asks, True at once
    once ``halted()``. The seconds waited are added to ``waited[0]``: they are not the start's
    solver time, which its budget's seconds count."""
    known, budget = ask()
    if not known:
        if iteration < least:
            return False
        t0 = time.perf_counter()
        try:
            while not known:
                pause()
                if halted():
                    return True
                known, budget = ask()
        finally:
            waited[0] += time.perf_counter() - t0
    return budget is not None and \
        budget.spent(iteration, time.perf_counter() - began - waited[0])


def _out_of_seconds(ask: Ask, began: float, waited: list[float]) -> bool:
    """Whether a start has spent the seconds of its budget (``ask``), once known, the seconds
    it waited at the smallest budget not counted."""
    known, budget = ask()
    return known and budget is not None and \
        time.perf_counter() - began - waited[0] >= budget.seconds


def _over(shared: _Shared, i: int, began: float, waited: list[float]) -> Callable[[], bool]:
    """Whether further start i's fatrop run in a worker should stop, asked by its guard or
    its helper (where fatrop hears no listener): the stop event, or the seconds of its budget
    spent (the seconds it waited at the smallest budget not counted)."""
    def over() -> bool:
        return shared.stop.is_set() or \
            _out_of_seconds(lambda: shared.budget_of(i), began, waited)

    return over


def _listener(conn: Connection, i: int, batch: _Batch, shared: _Shared,
              waited: list[float]) -> Listener:
    """The iteration callback of further start i in a worker: progress to the solving process
    at most every ``batch.every`` seconds; stop on the stop event, past the deadline, or at
    its budget, waiting at the smallest budget until the starts ahead of it have decided it
    (:func:`_spent`; the seconds waited added to ``waited[0]``)."""
    deadline, rule = batch.deadline, batch.rule
    last = [time.perf_counter()]
    began = last[0]

    def stopped() -> bool:
        return shared.stop.is_set() or time.monotonic() > deadline or \
            os.getppid() != shared.parent

    def listen(iteration: int, objective: float, infeasibility: float) -> bool:
        now = time.perf_counter()
        if now - last[0] >= batch.every:
            last[0] = now
            conn.send(("progress", i, (iteration, objective, infeasibility)))
        return stopped() or _spent(lambda: shared.budget_of(i), iteration, began, rule.least,
                                   stopped, lambda: time.sleep(POLL / 10), waited)

    return listen


def watch(where: str, progress: Callable[[str], None], interrupt: Interrupt,
          budget: Ask, deadline: float, every: float,
          look: Callable[[float], None] | None = None, least: int = 0,
          waited: list[float] | None = None) -> tuple[Listener, Callable[[], bool]]:
    """A start solved in the solving process: IPOPT's iteration callback, which reports
    (iteration, objective, infeasibility) to ``progress`` at most every ``every`` seconds and
    stops once Ctrl-C was pressed, past ``deadline`` (``time.monotonic()``) or once its
    ``budget`` (iterations or seconds from now) is spent (fatrop hears it too, through its own
    interface: :meth:`~ocgroupoid.nlp.backends.fatrop_ocp.FatropOcp.solve`); and fatrop's
    ``stop()``, asked by its guard or its helper (which hears no listener): Ctrl-C, or the
    budget's seconds. Both call ``look()`` first, which reads what the workers sent
    meanwhile. A budget not yet decided (a start ahead of this one still runs in a worker) is
    waited for at ``least`` iterations, reading the workers (``look(POLL)``), the seconds
    waited added to ``waited[0]``."""
    last = [time.perf_counter()]
    began = last[0]
    waited = [0.0] if waited is None else waited
    budget = settled(budget)

    def halted() -> bool:
        return interrupt.requested or time.monotonic() > deadline

    def pause() -> None:
        if look is not None:
            look(POLL)
        time.sleep(POLL / 10)  # the workers that decide it may be between two words

    def listen(iteration: int, objective: float, infeasibility: float) -> bool:
        if look is not None:
            look(0.0)
        now = time.perf_counter()
        if now - last[0] >= every:
            last[0] = now
            progress(iteration_line(where, iteration, objective, infeasibility))
        return halted() or _spent(budget, iteration, began, least, halted, pause, waited)

    def stop() -> bool:
        if look is not None:
            look(0.0)
        return interrupt.requested or _out_of_seconds(budget, began, waited)

    return listen, stop


def _serve(conn: Connection, w: int, tr: Transcription, shared: _Shared) -> None:
    """Worker w's loop: for each multi-start sent (a :class:`_Batch`), take its starts not
    yet handed out one after the other (:meth:`_Shared.take`), say ``start`` as it takes one
    and ``done`` with its result or ``error`` with what it raised, and ``idle`` once none is
    left; end on None, or when the solving process is gone."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the solving process's
    while True:
        while not conn.poll(1.0):
            if os.getppid() != shared.parent:
                return
        batch: _Batch | None = conn.recv()
        if batch is None:
            return
        while (i := shared.take(len(batch.starts), batch.deadline, w)) is not None:
            conn.send(("start", i, None))
            waited = [0.0]
            try:
                r = tr.solve(batch.starts[i], batch.p,
                             _listener(conn, i, batch, shared, waited), batch.deadline,
                             _over(shared, i, time.perf_counter(), waited))
                r = budgeted(r, batch.deadline, shared.stop.is_set())
                conn.send(("done", i, replace(r, solve_seconds=r.solve_seconds - waited[0])))
            except Exception as err:  # noqa: BLE001  (reported as a failed start)
                conn.send(("error", i, f"{type(err).__name__}: {err}"))
            shared.taken[w] = _NONE
        conn.send(("idle", _NONE, None))


def _failed(tr: Transcription, guess: Guess, p: np.ndarray, why: str) -> RawResult:
    """The result of a start that failed in its worker: its start point, no cost."""
    x0, _ = tr.start_point(guess, p)
    return RawResult(guess.label, np.asarray(x0, dtype=float), p, np.zeros(tr.ng),
                     float("inf"), WORKER_FAILED, False, 0, 0.0, np.zeros(tr.nx))


@dataclass
class _Pool:
    """Worker processes forked from the solving process (``owner``) for one transcription,
    kept between multi-starts (module docstring)."""

    owner: int
    tr: Transcription
    shared: _Shared
    conns: list[Connection]
    procs: list[Any]

    def serves(self, tr: Transcription, workers: int) -> bool:
        """Whether these workers, all alive, can solve the starts of ``tr`` as ``workers``
        processes."""
        return (self.owner == os.getpid() and self.tr is tr and len(self.procs) == workers
                and all(p.is_alive() for p in self.procs))

    def end(self) -> None:
        """Tell the workers to end (their starts stopped), without waiting for them."""
        if self.owner != os.getpid():  # a copy in a forked child: not its workers
            return
        self.shared.stop.set()
        for conn, proc in zip(self.conns, self.procs):
            if proc.is_alive():
                try:
                    conn.send(None)
                except OSError:
                    pass

    def join(self) -> None:
        """Wait for the workers told to end, killing those still running after
        :data:`GRACE` seconds."""
        if self.owner != os.getpid():
            return
        end = time.monotonic() + GRACE
        for proc in self.procs:
            proc.join(max(0.0, end - time.monotonic()))
            if proc.is_alive():
                proc.kill()
                proc.join()
        for conn in self.conns:
            conn.close()

    def close(self) -> None:
        """End the workers and wait until they have."""
        self.end()
        self.join()

    def ended(self) -> bool:
        """Whether every worker has ended (then its pipes are closed)."""
        if any(proc.is_alive() for proc in self.procs):
            return False
        self.join()
        return True


_kept: _Pool | None = None  # the workers of the last multi-start, if kept
#: workers told to end and not waited for (:func:`_retire`): joined by :func:`close`
_ending: list[_Pool] = []


def close() -> None:
    """End the worker processes the last multi-start kept for the next one, if any
    (:mod:`ocgroupoid.solve.parallel`), and wait until they have: after a change in this
    process they should see (what a Python hook of the problem reads), or to free them; the
    next multi-start forks new ones."""
    _retire()
    while _ending:
        _ending.pop().join()


def _retire() -> None:
    """Tell the kept workers to end without waiting for them: a multi-start that forks its
    own does not wait for the exit of the last one's (5-7 ms for so3's, measured
    2026-12-04). Workers that have ended meanwhile are joined."""
    global _kept
    pool, _kept = _kept, None
    if pool is not None:
        pool.end()
        _ending.append(pool)
    _ending[:] = [p for p in _ending if not p.ended()]


atexit.register(close)


def _pool(tr: Transcription, workers: int) -> _Pool:
    """The kept workers when they serve ``tr`` as ``workers`` processes, ready for a
    multi-start; else (the kept ones ended) ``workers`` new ones."""
    global _kept
    if _kept is not None and _kept.serves(tr, workers):
        pool, _kept = _kept, None
        pool.shared.reset()
        return pool
    _retire()
    ctx = mp.get_context("fork")
    for backend in tr.backends:  # IPOPT's instance with the iteration callback, built once
        if isinstance(backend, IpoptBackend):  # here for every worker (else in each)
            backend.watched_solver  # noqa: B018
    pool = _Pool(os.getpid(), tr, _Shared.make(ctx, workers), [], [])
    with warnings.catch_warnings():  # a multi-threaded caller: the workers have one thread
        warnings.simplefilter("ignore", DeprecationWarning)
        for w in range(workers):
            mine, theirs = ctx.Pipe()
            proc = ctx.Process(target=_serve, args=(theirs, w, tr, pool.shared), daemon=True)
            proc.start()
            theirs.close()
            pool.conns.append(mine)
            pool.procs.append(proc)
    return pool


def run(tr: Transcription, starts: Sequence[Guess], p: np.ndarray, workers: int,
        where: Callable[[int], str], progress: Callable[[str], None], interrupt: Interrupt,
        deadline: float, rule: Rule, every: float, rescue: Rescue | None = None
        ) -> tuple[list[RawResult], list[dict[str, Any]]]:
    """Solve ``starts`` on ``workers`` processes, this one and ``workers - 1`` forked ones
    (module docstring): the results of the starts that ran, in their order, and the starts
    that failed in a worker (number from 1, label, error). This process solves the first
    start (with ``rescue``), then takes the next start not handed out, as the workers do,
    until none is left; ``where(i)`` names start i for ``progress``, which hears each start
    as it is handed out and as it finishes, and the iterations of every start; ``rule`` is
    the further starts' budget, ``every`` the seconds between two progress messages of a
    start. The workers are kept for the next multi-start when every start ran and none was
    stopped (:func:`close` ends them)."""
    global _kept
    pool = _pool(tr, workers - 1)
    shared, conns, procs = pool.shared, pool.conns, pool.procs
    failed: list[dict[str, Any]] = []
    results: dict[int, RawResult] = {}
    busy = set(range(len(procs)))  # the workers still on this multi-start
    batch = _Batch(tuple(starts), p, deadline, rule, every)
    for conn in conns:
        try:
            conn.send(batch)
        except OSError:  # it died: its sentinel says so
            pass

    def fail(i: int, why: str) -> None:
        results[i] = _failed(tr, starts[i], p, why)
        shared.publish(results, rule)
        failed.append({"start": i + 1, "label": starts[i].label, "error": why})
        progress(f"{where(i)}: failed in its worker ({why})")

    def done(i: int, r: RawResult) -> None:
        results[i] = timed(r, deadline)
        shared.publish(results, rule)
        progress(f"{len(results)}/{len(starts)} starts done; {where(i)}: {r.status}")

    def look(seconds: float = 0.0) -> None:
        """Read what the busy workers sent, waiting up to ``seconds`` for the first word."""
        if not busy:
            return
        ready = wait([conns[w] for w in busy] + [procs[w].sentinel for w in busy], seconds)
        for w in sorted(busy):
            if conns[w] in ready or procs[w].sentinel in ready:
                _receive(w, conns[w], procs[w], shared, busy, results, done, fail, where,
                         progress)

    clean = False
    try:
        i: int | None = 0
        while i is not None:
            progress(where(i))
            waited = [0.0]
            listen, stop = watch(where(i), progress, interrupt,
                                 partial(budget_of, results, i, rule), deadline, every, look,
                                 rule.least, waited)
            r = tr.solve(starts[i], p, listen, deadline, stop, rescue if i == 0 else None)
            r = replace(r, solve_seconds=r.solve_seconds - waited[0])
            done(i, budgeted(r, deadline, interrupt.requested) if i > 0 else r)
            if interrupt.requested or time.monotonic() > deadline:
                shared.stop.set()
            i = shared.take(len(starts), deadline, None)
        while busy:
            if interrupt.requested or time.monotonic() > deadline:
                shared.stop.set()
            look(POLL)
        clean = True
    finally:
        if not clean or shared.stop.is_set() or failed:
            pool.close()
        else:
            _retire()  # another thread's workers, kept meanwhile: one set at a time
            _kept = pool
    return [results[i] for i in sorted(results)], failed


def _receive(w: int, conn: Connection, proc: Any, shared: _Shared, busy: set[int],
             results: dict[int, RawResult], done: Callable[[int, RawResult], None],
             fail: Callable[[int, str], None], where: Callable[[int], str],
             progress: Callable[[str], None]) -> None:
    """Read what worker w sent: a start it took, progress, a start's result or error, that
    it is idle; or see it dead, and its start, if it had one, failed."""
    while conn.poll():
        try:
            kind, i, value = conn.recv()
        except (EOFError, OSError):
            break
        if kind == "start":
            progress(where(i))
        elif kind == "progress":
            progress(iteration_line(where(i), *value))
        elif kind == "error":
            fail(i, value)
        elif kind == "done":
            done(i, value)
        else:  # idle: none of this multi-start's starts left
            busy.discard(w)
            return
    if not proc.is_alive():
        busy.discard(w)
        i = shared.taken[w]
        if i != _NONE and i not in results:
            code = proc.exitcode
            fail(i, "its worker process died (" + (f"signal {-code}" if code is not None and
                                                   code < 0 else f"exit code {code}") + ")")
