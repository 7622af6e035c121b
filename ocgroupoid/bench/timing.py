"""One timed solve: a method on N intervals, from the same cold start every repeat.

The NLP is built once (not timed); it is then solved ``repeats`` times from the same guess
(a geodesic, or the multi-start guess labelled ``start`` that found the reference's minimum)
without an iteration callback, more often when it is fast (until the runs add up to
:data:`MIN_SECONDS`, at most :data:`MAX_REPEATS`), and the median of its wall times is the
row's time. A run's time is what the caller of the built NLP waits for
(:meth:`~ocgroupoid.nlp.transcription.Transcription.solve`, the wall time around it): the
start point of the guess, the backend's arguments and, for fatrop, the way to its helper
process and back, with the solve itself; the solver's own time alone left out 0.9-2.4 ms of
fatrop's 3-13 ms on so3 at N = 16...128 (IPOPT's 0.8-1.2 ms). The last run is read out and
diagnosed as
:meth:`~ocgroupoid.solve.CompiledProblem.solve` does (replay, verdict, hint).

Each run is held to the problem file's ``solver.max_seconds`` (IPOPT's ``max_wall_time``,
fatrop's deadline), and an unsuccessful run is not repeated: it has no accuracy to chart,
and the same start fails the same way again (a divergent start crawling to its time limit
would take it once per repeat).
"""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass
from typing import Any, Callable, TypeVar

from ..files.schema import ProblemFile
from ..model.problem import Problem
from ..nlp.method import DEFAULT_STEPS
from ..nlp.options import MAX_SECONDS
from ..nlp.transcription import Guess, RawResult
from ..solve import CompiledProblem, Solution, compile_problem, distinct_minima, make_solution
from .methods import Method

MIN_SECONDS = 0.25  # a solve faster than this is repeated until the repeats add up to it,
MAX_REPEATS = 15  # at most this often: medians of milliseconds are noisy
Result = TypeVar("Result")


@dataclass(frozen=True)
class Setting:
    """What a problem file fixes of every solve: IPOPT's options, order2's rule, the steps
    and the wall time of one run (``solver.max_seconds``)."""

    ipopt: dict[str, Any]
    rule: str
    steps: str = DEFAULT_STEPS
    max_seconds: float = MAX_SECONDS

    @classmethod
    def of(cls, file: ProblemFile) -> "Setting":
        """The setting of a validated problem file."""
        return cls(dict(file.solver.ipopt), file.discretization.rule,
                   file.discretization.steps, file.solver.max_seconds)

    def compile(self, problem: Problem, method: Method, N: int) -> CompiledProblem:
        """``method`` compiled on N intervals in this setting."""
        return compile_problem(problem, method.on(N, self.rule, self.steps),
                               method.options(self.ipopt, self.max_seconds))


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


def timed_solve(problem: Problem, method: Method, N: int, setting: Setting, repeats: int,
                start: str | None = None) -> Timed:
    """Build ``method`` on N intervals and solve it ``repeats`` times from one cold start
    (module docstring); raises what building raises (ConfigError, SingularityError)."""
    t0 = time.perf_counter()
    solver = setting.compile(problem, method, N)
    tr = solver.transcription
    p = tr.pack()
    guess = cold_start(solver.guesses(tr, p, start is not None), start)
    build = time.perf_counter() - t0
    seconds: list[float] = []

    def run() -> RawResult:
        t0 = time.perf_counter()
        r = tr.solve(guess, p)
        seconds.append(time.perf_counter() - t0)
        return r

    last = run()
    while last.success and (len(seconds) < max(1, repeats) or (
            sum(seconds) < MIN_SECONDS and len(seconds) < MAX_REPEATS)):
        last = run()
    sol = make_solution(tr, last, distinct_minima([last]), True, setting.ipopt)
    return Timed(sol, seconds, build, guess.label)
