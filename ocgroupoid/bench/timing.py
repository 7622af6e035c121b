"""One timed solve: a method on N intervals, from the same cold start every repeat.

The NLP is built once (not timed, :class:`Trial`); it is then solved ``repeats`` times from
the same guess (a geodesic, or the multi-start guess labelled ``start`` that found the
reference's minimum) without an iteration callback, more often when it is fast (until the
runs add up to :data:`MIN_SECONDS`, at most :data:`MAX_REPEATS`), and the median of its wall
times is the row's time. A ``+coarse`` method's solve is two (:meth:`Method.coarse_N`): from
the start on the coarse grid, then on N from that solution interpolated, with IPOPT its
multipliers carried over as a solve of the compiled problem carries them
(:func:`~ocgroupoid.solve.multipliers.onto`, again from the interpolated velocities alone
if that start fails; from the start when the coarse grid failed), and its time is all of
theirs. The solves run back to back
(:func:`timed_solve`) or in rounds with other methods and grids (:func:`interleaved`, what
the work-precision benchmark does).
A run's time is what the caller of the built NLP waits for
(:meth:`~ocgroupoid.nlp.transcription.Transcription.solve`, the wall time around it): the
start point of the guess, the backend's arguments and, for fatrop, its guard (or the way to
its helper process and back, where it has one), with the solve itself; the solver's own
time alone left out 0.9-2.4 ms of fatrop's 3-13 ms on so3 at N = 16...128 (IPOPT's 0.8-1.2
ms), when fatrop ran in its helper. The last run is read out and diagnosed as
:meth:`~ocgroupoid.solve.CompiledProblem.solve` does (replay, verdict, hint).

Each run is held to the problem file's ``solver.max_seconds`` (IPOPT's ``max_wall_time``,
fatrop's deadline), and an unsuccessful run is not repeated: it has no accuracy to chart,
and the same start fails the same way again (a divergent start crawling to its time limit
would take it once per repeat).
"""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable, TypeVar

import numpy as np

from ..errors import OcgError
from ..files.schema import ProblemFile
from ..model.problem import Problem
from ..nlp.backends.base import Attempt
from ..nlp.method import DEFAULT_STEPS
from ..nlp.options import MAX_SECONDS
from ..nlp.transcription import Guess, RawResult, Transcription
from ..solve import CompiledProblem, Solution, compile_problem, distinct_minima, make_solution
from ..solve.multipliers import from_carried, onto
from .methods import Method

MIN_SECONDS = 0.25  # a solve faster than this is repeated until the repeats add up to it,
MAX_REPEATS = 15  # at most this often: medians of milliseconds are noisy
Result = TypeVar("Result")


@dataclass(frozen=True)
class Setting:
    """What a problem file fixes of every solve: IPOPT's and fatrop's options, order2's
    rule, the steps and the wall time of one run (``solver.max_seconds``)."""

    ipopt: dict[str, Any]
    rule: str
    steps: str = DEFAULT_STEPS
    max_seconds: float = MAX_SECONDS
    fatrop: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def of(cls, file: ProblemFile) -> "Setting":
        """The setting of a validated problem file."""
        return cls(dict(file.solver.ipopt), file.discretization.rule,
                   file.discretization.steps, file.solver.max_seconds, dict(file.solver.fatrop))

    def compile(self, problem: Problem, method: Method, N: int) -> CompiledProblem:
        """``method`` compiled on N intervals in this setting."""
        return compile_problem(problem, method.on(N, self.rule, self.steps),
                               method.options(self.ipopt, self.max_seconds, N, self.fatrop))


@dataclass
class Timed:
    """A diagnosed solution and the wall times of its repeats (seconds, module docstring)."""

    solution: Solution
    seconds: list[float]
    build_seconds: float
    start: str

    @property
    def median(self) -> float:
        return statistics.median(self.seconds)


def median_seconds(fn: Callable[[], Result], repeats: int) -> tuple[float, Result]:
    """The median wall time of ``repeats`` calls of ``fn()`` (at least one), and the last
    call's result."""
    times = []
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def cold_start(solver_guesses: list[Guess], start: str | None) -> Guess:
    """The guess labelled ``start`` (the first geodesic when None or absent)."""
    return next((g for g in solver_guesses if g.label == start), solver_guesses[0])


class Trial:
    """``method`` built on N intervals and its cold start (module docstring): its solves are
    run one at a time (:meth:`run`), alone (:func:`timed_solve`) or in rounds with others
    (:func:`interleaved`). Building raises what building raises (ConfigError,
    SingularityError)."""

    def __init__(self, problem: Problem, method: Method, N: int, setting: Setting,
                 start: str | None = None) -> None:
        t0 = time.perf_counter()
        self.tr, self.p, self.guess = _built(problem, method, N, setting, start)
        self.ipopt = setting.ipopt
        n = method.coarse_N(N)
        #: the coarse grid solved first (``+coarse``): its NLP, parameters and start
        self.coarse = None if n is None else \
            _built(problem, replace(method, coarse=False), n, setting, start)
        self.build_seconds = time.perf_counter() - t0
        #: the wall time of every solve so far, and the last solve's result
        self.seconds: list[float] = []
        self.last: RawResult | None = None
        #: what a solve raised (a start point that cannot be formed, ...): no more solves
        self.error: OcgError | None = None

    def wants(self, repeats: int) -> bool:
        """Whether it takes another solve: ``repeats`` in all, more while they add up to
        less than :data:`MIN_SECONDS` (at most :data:`MAX_REPEATS`); none after a failure."""
        if self.error is not None:
            return False
        if self.last is None:
            return True
        return self.last.success and (len(self.seconds) < max(1, repeats) or (
            sum(self.seconds) < MIN_SECONDS and len(self.seconds) < MAX_REPEATS))

    def run(self) -> None:
        """One solve from the cold start, timed as its caller waits for it (what it raises
        is kept in :attr:`error`)."""
        t0 = time.perf_counter()
        try:
            self.last = self._solve()
        except OcgError as e:
            self.error = e
            return
        self.seconds.append(time.perf_counter() - t0)

    def _solve(self) -> RawResult:
        """From the cold start, or through the coarse grid (module docstring): the coarse
        run is listed first among the runs before the last (``diagnostics["runs"]``)."""
        if self.coarse is None:
            return self.tr.solve(self.guess, self.p)
        tr, p, guess = self.coarse
        deadline = time.monotonic() + self.tr.max_seconds  # both runs' time
        first = tr.solve(guess, p, deadline=deadline)
        start = onto(tr, first, self.tr, self.p) if first.success else self.guess
        *carried, r = from_carried(start, lambda g: self.tr.solve(g, self.p, deadline=deadline),
                                   lambda r: r.success)
        earlier: tuple[Attempt, ...] = (
            (f"{first.backend} on N={tr.N}", first.status, first.iterations),
            *((f"{c.backend} with the multipliers", c.status, c.iterations) for c in carried))
        seconds = first.solve_seconds + sum(c.solve_seconds for c in (*carried, r))
        return replace(r, solve_seconds=seconds, earlier=(*earlier, *r.earlier))

    def timed(self) -> Timed:
        """The last solve read out and diagnosed, with the times of all (after a run);
        raises what a solve raised."""
        if self.error is not None:
            raise self.error
        assert self.last is not None, "a trial is timed after a solve"
        sol = make_solution(self.tr, self.last, distinct_minima([self.last]), True, self.ipopt)
        return Timed(sol, self.seconds, self.build_seconds, self.guess.label)


def _built(problem: Problem, method: Method, N: int, setting: Setting, start: str | None
           ) -> tuple[Transcription, np.ndarray, Guess]:
    """``method``'s NLP on N intervals, its parameters and its cold start."""
    solver = setting.compile(problem, method, N)
    tr = solver.transcription
    p = tr.pack()
    return tr, p, cold_start(solver.guesses(tr, p, start is not None), start)


def timed_solve(problem: Problem, method: Method, N: int, setting: Setting, repeats: int,
                start: str | None = None) -> Timed:
    """Build ``method`` on N intervals and solve it ``repeats`` times from one cold start
    (module docstring); raises what building raises (ConfigError, SingularityError)."""
    trial = Trial(problem, method, N, setting, start)
    while trial.wants(repeats):
        trial.run()
    return trial.timed()


def interleaved(trials: list[Trial], repeats: int,
                progress: Callable[[int, int], None] = lambda *_: None) -> None:
    """Solve the trials in rounds, one solve of each that wants another per round
    (:meth:`Trial.wants`), until none does; ``progress(round, solves)`` before each round.
    Each row's repeats are spread over the whole run rather than taken back to back, so a
    slow phase of a shared machine (seconds long) slows every row alike and leaves their
    ratios. plate_ball_rotating, fatrop, N = 64, four builds solved in turn 15 times each,
    twice: medians 14.7-15.4 ms in one run, 10.5-12.5 ms in the other. Over the 11 problem
    files' work-precision runs (2 cores, 2026-11-28) the time of ``order4@fatrop+jit`` over
    ``rk4_quat+jit`` at the same N moved by 1.15 times between two runs in rounds (median
    over 42 pairs; 1.41 at the 90th percentile), by 1.26 (1.68) between two back to back."""
    round_ = 0
    while todo := [t for t in trials if t.wants(repeats)]:
        progress(round_, len(todo))
        for t in todo:
            t.run()
        round_ += 1
