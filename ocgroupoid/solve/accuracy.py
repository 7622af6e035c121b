"""Accuracy on demand: the smallest grid whose estimated error meets a target.

``solve_to_accuracy`` (a problem file's ``horizon.N: auto``) solves on N = N_min, 2 N_min,
4 N_min, ... up to N_max, each grid warm-started from the last verified one (interpolated with
its multipliers, as ``solver.continuation`` does; the multi-start runs until a grid is
verified: a grid too coarse for the motion is no seed), and stops at the first grid whose
solution is verified and meets the targets:

* ``accuracy``: the relative cost error, estimated by Richardson from this grid and the
  previous one (:mod:`~ocgroupoid.verify.richardson`), ``|J_N - J_N/2| / (2^p - 1) / |J_N|``.
  The order p is the scheme's (:attr:`~ocgroupoid.nlp.schemes.base.Scheme.cost_order`), at
  most 2 when bounds are active on uniform steps (a switch inside an interval), lowered to
  the order observed, so that a grid outside the asymptotic regime is never
  trusted: the replay's terminal errors at both grids (the plan checked against the
  continuous dynamics) and, from the third grid on, the fall of the cost differences give
  it. An estimate never falls faster than the scheme's order from one grid to the next
  (at least the previous estimate / 2^p): a difference that vanishes by a chance
  cancellation (a switch of the controls crossing a node) does not stop the search.
* ``replay_accuracy``: the largest terminal error of the replay
  (``diagnostics["replay"]["max_terminal_error"]``), measured, in its own units.

The estimate checked is the finer grid's, so the grid chosen is at most twice the smallest
grid of the sequence that meets the target (in the asymptotic regime). ``scheme="auto"``
searches with each of :data:`AUTO_SCHEMES` and keeps whichever meets the targets with less
IPOPT time (a later search stops once it has spent more). The Solution reports the search in
``diagnostics["accuracy"]`` (every grid: cost, estimate, replay error, time) and its own
error in ``diagnostics["error_estimate"]`` (:attr:`Solution.error_estimate`).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field, replace
from typing import Any, Callable

from ..errors import ConfigError
from ..model.problem import Problem
from ..nlp.method import Method
from ..nlp.options import SolverOptions
from ..nlp.schemes import SCHEME_NAMES
from ..nlp.shortcuts import choose
from ..verify.diagnostics import replay_of
from ..verify.richardson import estimate as richardson_estimate, observed_order
from .compiled import CompiledProblem, Progress
from .multipliers import onto
from .solution import Solution

#: the schemes ``scheme="auto"`` tries, in this order
AUTO_SCHEMES = ("order6", "order4", "order2")
#: what a file's ``scheme: auto`` builds where no search runs (``ocgroupoid check`` and
#: ``export-c`` on the first grid of ``N: auto``, sweeps): order4, as a file with a fixed N
#: gets (``files.schema.FILE_SCHEME``)
AUTO_BUILT = "order4"
#: the first and the largest grid of the search (defaults of horizon.N_min and N_max)
N_MIN, N_MAX = 8, 1024
#: the loosest relative cost error asked for: beyond it Richardson's leading term is no guide
ACCURACY_MAX = 0.1
#: an observed order at or below this is no convergence: no estimate on that grid
ORDER_FLOOR = 0.5


def check_target(accuracy: float | None, replay_accuracy: float | None) -> None:
    """ConfigError unless at least one target is given, accuracy in (0, ACCURACY_MAX] and
    replay_accuracy > 0 (both finite)."""
    if accuracy is None and replay_accuracy is None:
        raise ConfigError("N auto needs a target: accuracy (a relative cost error, e.g. 1e-6) "
                          "or replay_accuracy (the replay's terminal error)")
    if accuracy is not None and not (math.isfinite(accuracy) and 0 < accuracy <= ACCURACY_MAX):
        raise ConfigError(f"accuracy = {accuracy:g} is outside (0, {ACCURACY_MAX:g}]: it is a "
                          "relative error of the cost, e.g. 1e-6")
    if replay_accuracy is not None and not (math.isfinite(replay_accuracy)
                                            and replay_accuracy > 0):
        raise ConfigError(f"replay_accuracy = {replay_accuracy:g} must be a finite number > 0 "
                          "(in the units of the replay's terminal errors, e.g. 1e-4 rad)")


@dataclass(frozen=True)
class Search:
    """What a search is asked: its targets, its grids, and how each grid is solved (the
    method's retraction, rule and bound points; its N and scheme are the search's; the
    options' ``max_seconds`` is each grid's)."""

    accuracy: float | None
    replay_accuracy: float | None
    method: Method
    options: SolverOptions
    N_min: int
    N_max: int
    values: dict[str, Any]  # params, initial, final and T of every solve

    def __post_init__(self) -> None:
        check_target(self.accuracy, self.replay_accuracy)
        if not 2 <= self.N_min <= self.N_max:
            raise ConfigError(f"N_min = {self.N_min} and N_max = {self.N_max}: need "
                              "2 <= N_min <= N_max")

    def met(self, sol: Solution, est: dict[str, Any] | None, replay_error: float | None
            ) -> bool:
        """Whether a grid's solution is verified and meets every target."""
        if not sol.success:
            return False
        if self.accuracy is not None and (est is None or est["cost_relative"] > self.accuracy):
            return False
        return self.replay_accuracy is None or (replay_error is not None
                                                and replay_error <= self.replay_accuracy)


@dataclass
class Level:
    """One grid of the search."""

    scheme: str
    N: int
    cost: float
    status: str
    verified: bool
    #: the replay's largest terminal error (None: no replay)
    replay_error: float | None
    #: the Richardson estimate of the relative cost error (None: first grid, or no
    #: convergence observed yet)
    estimate: float | None
    #: the order the estimate used (at most the scheme's)
    order: float | None
    met: bool
    ipopt_seconds: float
    seconds: float  # build, IPOPT and diagnostics


@dataclass
class Run:
    """The search with one scheme."""

    scheme: str
    order: int = 2  # the scheme's (Scheme.cost_order), read off its first grid
    levels: list[Level] = field(default_factory=list)
    solution: Solution | None = None  # the grid chosen, or the best one reached
    met: bool = False
    stopped: str = ""  # why it stopped before meeting the targets

    @property
    def ipopt_seconds(self) -> float:
        return sum(lv.ipopt_seconds for lv in self.levels)

    @property
    def best(self) -> Level | None:
        """The level whose solution the run keeps."""
        if self.solution is None:
            return None
        return next(lv for lv in reversed(self.levels) if lv.N == self.solution.N)


def _rank(level: Level) -> tuple[bool, float, int]:
    """Nearer the targets first: verified, then the smaller estimate, then the finer grid."""
    return (not level.verified, level.estimate if level.estimate is not None else math.inf,
            -level.N)


def _estimate(prior: list[Level], sol: Solution, replay_error: float | None, nominal: int
              ) -> dict[str, Any] | None:
    """The error estimate of ``sol`` from the grids before it (module docstring); None on
    the first grid, after a failed one, or where no convergence is observed."""
    if not prior or prior[-1].status != "Solve_Succeeded":
        return None
    if sol.diagnostics.get("bounds_active") and sol.discretization.get("steps") != "adaptive":
        # the active set switches inside intervals on a uniform grid: a control with a kink
        # or a jump there converges at second order at best, whatever the scheme's order
        nominal = min(nominal, 2)
    last = prior[-1]
    observed = {}
    if replay_error is not None and last.replay_error is not None:
        observed["replay"] = observed_order(last.replay_error, replay_error)
    if len(prior) >= 2 and prior[-2].status == "Solve_Succeeded":
        observed["cost"] = observed_order(abs(last.cost - prior[-2].cost),
                                          abs(sol.cost - last.cost))
    seen = {k: q for k, q in observed.items() if q is not None}
    order = min([float(nominal), *seen.values()])
    if order <= ORDER_FLOOR:
        return None
    entry = richardson_estimate(sol.cost, last.cost, sol.N, last.N, order, nominal)
    entry["observed_orders"] = seen
    if last.estimate is not None and last.estimate / 2 ** nominal > entry["cost_relative"]:
        entry["cost_relative"] = last.estimate / 2 ** nominal
        entry["cost"] = entry["cost_relative"] * abs(sol.cost)
        entry["bounded_by_previous"] = True
    return entry


def _solve_grid(problem: Problem, scheme: str, N: int, search: Search,
                seed: tuple[CompiledProblem, Solution] | None, progress: Progress
                ) -> tuple[CompiledProblem, Solution]:
    """One grid: from ``seed`` (the last verified grid, interpolated, with its multipliers
    where they carry over: :func:`~ocgroupoid.solve.multipliers.onto`), or with the
    multi-start when there is none."""
    progress(f"{scheme}, N={N}: building the NLP")
    solver = CompiledProblem(problem, replace(search.method, N=N, scheme=scheme), search.options)
    if search.replay_accuracy is not None and replay_of(solver.transcription).rhs is None:
        raise ConfigError(f"replay_accuracy: this problem has no replay "
                          f"({replay_of(solver.transcription).reason}); ask for accuracy "
                          "(a relative cost error) instead")

    def where(message: str) -> None:
        progress(f"{scheme}, {message}")

    if seed is None:
        return solver, solver.solve(**search.values, progress=where)
    tr = solver.transcription
    guess = onto(seed[0].transcription, seed[1], tr, tr.pack(**search.values))
    return solver, solver.solve(**search.values, guess=guess, progress=where)


def _search(problem: Problem, scheme: str, search: Search, budget: float | None,
            progress: Progress, report: Callable[[Level], None]) -> Run:
    """Double N from ``N_min`` with ``scheme`` until the targets are met, N_max is passed,
    Ctrl-C is pressed or the IPOPT time exceeds ``budget``."""
    run = Run(scheme)
    seed: tuple[CompiledProblem, Solution] | None = None
    N = search.N_min
    while N <= search.N_max:
        t0 = time.perf_counter()
        solver, sol = _solve_grid(problem, scheme, N, search, seed, progress)
        run.order = solver.transcription.scheme.cost_order
        rep = sol.diagnostics.get("replay", {})
        replay_error = rep.get("max_terminal_error") if rep.get("available") else None
        est = _estimate(run.levels, sol, replay_error, run.order)
        if est is not None:
            sol.diagnostics["error_estimate"] = est
        level = Level(scheme, N, sol.cost, sol.status, sol.success, replay_error,
                      est["cost_relative"] if est else None, est["order"] if est else None,
                      search.met(sol, est, replay_error), sol.ipopt_seconds_total,
                      time.perf_counter() - t0)
        run.levels.append(level)
        report(level)
        if sol.status == "interrupted" or level.met:
            run.solution, run.met = sol, level.met
            run.stopped = "" if level.met else "interrupted"
            return run
        if run.best is None or _rank(level) < _rank(run.best):
            run.solution = sol
        if sol.success:
            seed = (solver, sol)
        if budget is not None and run.ipopt_seconds > budget:
            run.stopped = "stopped: more IPOPT time than a scheme that met the targets"
            return run
        N *= 2
    run.stopped = f"N_max = {search.N_max} reached"
    return run


def suggested_N(N: int, error: float, target: float, order: float) -> int:
    """The power of two that brings ``error`` at N down to ``target`` at ``order``."""
    factor = max(2.0, (error / target) ** (1.0 / max(order, 1.0)))
    return int(2 ** math.ceil(math.log2(N * factor)))


def _message(run: Run, search: Search, grids: int, seconds: float) -> str:
    """What the search found: the grid chosen and its estimate, or the best estimate reached
    and what to try."""
    best = run.best
    assert best is not None
    acc, racc = search.accuracy, search.replay_accuracy
    parts = []
    if acc is not None:
        parts.append("no estimate of the cost error" if best.estimate is None else
                     f"estimated relative cost error {best.estimate:.1e} (target {acc:g})")
    if racc is not None:
        parts.append("no replay" if best.replay_error is None else
                     f"replay terminal error {best.replay_error:.1e} (target {racc:g})")
    found = f"N = {best.N} ({run.scheme}), {', '.join(parts)}"
    took = f"{grids} grids in {seconds:.2f} s"
    if run.met:
        return f"{found}; {took}"
    if run.stopped == "interrupted":
        return f"interrupted at {found}"
    tries = [] if run.scheme in ("order4", "order6") else \
        ["discretization.scheme: order4 (or auto)"]
    order = best.order or run.order
    if acc is not None and best.estimate is not None:
        N = suggested_N(best.N, best.estimate, acc, order)
    elif racc is not None and best.replay_error is not None:
        N = suggested_N(best.N, best.replay_error, racc, order)
    else:
        N = 2 * search.N_max
    tries += [f"horizon.N_max: {max(N, 2 * best.N)}", "a looser target"]
    return (f"target not met ({run.stopped}): the best estimate reached is {found}"
            f"{'' if best.verified else ', not verified'}; {took}. Try {', or '.join(tries)}")


def solve_to_accuracy(problem: Problem, accuracy: float | None = None,
                      replay_accuracy: float | None = None, scheme: str | None = None,
                      retraction: str | None = None, rule: str | None = None,
                      ipopt: dict[str, Any] | None = None, multistart: bool | int | None = None,
                      N_min: int = N_MIN, N_max: int = N_MAX, *,
                      params: dict[str, Any] | None = None,
                      initial: dict[str, Any] | None = None,
                      final: dict[str, Any] | None = None, T: float | None = None,
                      progress: Progress | None = None,
                      report: Callable[[Level], None] | None = None, jit: bool | None = None,
                      backend: str | None = None, max_seconds: float | None = None,
                      method: Method | None = None, options: SolverOptions | None = None
                      ) -> Solution:
    """Solve on the smallest grid N = N_min 2^k whose estimated error meets ``accuracy``
    (relative cost error) and/or ``replay_accuracy`` (the replay's terminal error); see the
    module docstring. ``method`` and ``options`` as in :func:`compile_problem` (the method's N is
    the search's, its scheme too unless ``scheme`` is given: one of the schemes, or
    ``auto``); the other keywords replace their fields (``multistart``, ``jit``,
    ``backend``, ``max_seconds`` of each grid's solve, ...). ``progress`` hears what runs (a
    spinner's text); ``report`` gets every grid as it is done.

    >>> sol = solve_to_accuracy(problem, accuracy=1e-6)   # doctest: +SKIP
    >>> sol.N, sol.error_estimate                         # doctest: +SKIP

    Returns the chosen grid's Solution; if no grid meets the targets, the one nearest them,
    with ``success: false`` and the message (best estimate reached, what to try) as hint.
    """
    method, options = choose(method, options, retraction=retraction, rule=rule, ipopt=ipopt,
                             multistart=multistart, jit=jit, backend=backend,
                             max_seconds=max_seconds)
    if options.continuation:
        raise ConfigError("the accuracy search solves its own grids, each from the one before: "
                          "give no continuation")
    scheme = scheme or method.scheme
    search = Search(accuracy, replay_accuracy, method, options, N_min, N_max,
                    {"params": params, "initial": initial, "final": final, "T": T})
    if scheme != "auto" and scheme not in SCHEME_NAMES:
        raise ConfigError(f"unknown scheme {scheme!r}; choose one of "
                          f"{', '.join(SCHEME_NAMES)} or auto")
    t0 = time.perf_counter()
    runs: list[Run] = []
    budget: float | None = None
    for name in AUTO_SCHEMES if scheme == "auto" else (scheme,):
        run = _search(problem, name, search, budget, progress or _quiet, report or _quiet)
        runs.append(run)
        if run.met:
            budget = run.ipopt_seconds if budget is None else min(budget, run.ipopt_seconds)
        if run.stopped == "interrupted":
            break
    chosen = _choose(runs)
    seconds = time.perf_counter() - t0
    sol = chosen.solution
    assert sol is not None  # every run solves its first grid
    message = _message(chosen, search, sum(len(r.levels) for r in runs), seconds)
    sol.diagnostics["accuracy"] = {
        "target": accuracy, "replay_target": replay_accuracy, "met": chosen.met,
        "N": sol.N, "scheme": chosen.scheme, "seconds": seconds,
        "ipopt_seconds": sum(r.ipopt_seconds for r in runs), "message": message,
        "schemes": {r.scheme: {"met": r.met, "ipopt_seconds": r.ipopt_seconds,
                               "stopped": r.stopped} for r in runs},
        "levels": [asdict(lv) for r in runs for lv in r.levels]}
    if chosen.met or chosen.stopped == "interrupted":
        return sol
    verdict = sol.diagnostics.setdefault("verdict", {"failures": []})
    verdict["verified"] = False
    verdict["failures"] = [*verdict.get("failures", []), message]
    return replace(sol, success=False, hint="; ".join(verdict["failures"]))


def _choose(runs: list[Run]) -> Run:
    """The run that met the targets with the least IPOPT time; else the one nearest them."""
    met = [r for r in runs if r.met]
    if met:
        return min(met, key=lambda r: r.ipopt_seconds)
    if runs[-1].stopped == "interrupted":
        return runs[-1]
    return min(runs, key=lambda r: _rank(r.best) if r.best else (True, math.inf, 0))


def _quiet(_: Any) -> None:
    return None
