"""Solving: IPOPT from good guesses, multi-start over local minima, coarse-to-fine continuation.

Optimal-control problems on SO(3) have several local minima (a slew may turn the short or
the long way round). ``multistart`` solves from every geodesic guess (each group factor both
ways round), the model's own guesses and a few deterministic perturbations, keeps the best
feasible result and lists the distinct minima met. ``continuation`` solves on coarse grids
first and interpolates each solution onto the next grid as its initial guess; it may also
name cheaper schemes solved first on the final grid (``order2`` before ``order4``: a start
far from the optimum converges in the cheap scheme, the costly one then takes a few steps).
A final grid whose every start failed is rescued that way unasked; with fatrop the first
start is, between fatrop's failure and IPOPT's fallback. If that fails too (or the scheme has
no cheaper sibling), a grid a quarter as fine is solved first and the final grid continued
from it, the coarse multipliers carried.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from functools import partial
from typing import Any, Callable, Iterable, Sequence

import numpy as np

from ..errors import ConfigError
from ..model.problem import Problem
from ..nlp import mesh
from ..nlp.backends import INTERRUPTED, LISTENER_STOP, TIMED_OUT, Run, Start
from ..nlp.backends.policy import Rescue
from ..nlp.method import Discretization, Method
from ..nlp.options import SolverOptions
from ..nlp.program import Guess
from ..nlp.schemes import SCHEMES
from ..nlp.shortcuts import choose
from ..nlp.transcription import RawResult, Transcription
from ..verify import richardson
from ..verify.diagnostics import replay_of
from ..verify.verdict import REPLAY_TOLERANCE, scales
from . import parallel
from .guesses import as_guess, geodesic_guesses, interpolate, model_guesses, perturbed_guesses
from .interrupt import Interrupt, interruptible
from .multipliers import from_carried, onto, with_multipliers
from .readout import control_ppoly, make_solution
from .rows import Rows
from .solution import Solution

Progress = Callable[[str], None]
#: a further start of a multi-start gets max(30, 3 x the first start's) iterations, at no
#: more than 3 times its seconds per iteration but at least 1 s in all
#: (:class:`~ocgroupoid.solve.parallel.Rule`; after a first start that failed, those of the
#: first that succeeded, :func:`~ocgroupoid.solve.parallel.budget_of`): one that needs far
#: more is on its way to a worse minimum or nowhere (it is stopped, not counted)
START_BUDGET = parallel.Rule(least=30, times=3, pace=3.0, least_seconds=1.0)
PROGRESS_EVERY = 0.25  # seconds between two reports of IPOPT's iterations
#: the iterations each run of fatrop's rescue (:meth:`CompiledProblem._through`) has: the
#: heavy top from the long way round needs 34-35 of order2's and 4-5 of order4's after them at
#: N = 64-128, where the reaction wheels' long way round, which order2 cannot solve either,
#: took 257 (1.2 s) to fail
RESCUE_ITERATIONS = 100
#: the status of a run that reached its iteration limit
MAX_ITER = "Maximum_Iterations_Exceeded"
#: the grid rescue (:meth:`CompiledProblem._grid_rescue`) solves N / GRID_RESCUE first, where
#: that is at least GRID_RESCUE_MIN intervals: quadrotor_min_time with order6 at N = 512 fails
#: from its first guess (IPOPT's 500 iterations, 70 s), and so does its order2 rescue; N = 128
#: solves from the same guess, and N = 512 from its solution in 25 iterations (4.2 s in all)
GRID_RESCUE, GRID_RESCUE_MIN = 4, 16


def _noop(_: str) -> None:
    return None


@dataclass
class Minimum:
    """A distinct local minimum met by multi-start."""

    cost: float
    label: str
    status: str
    iterations: int


def distinct_minima(results: Iterable[RawResult], rtol: float = 1e-6, xtol: float = 1e-4
                    ) -> list[Minimum]:
    """Successful results grouped into local minima, cheapest first.

    Two results are one minimum when their costs agree to ``rtol`` and their NLP points
    to ``xtol`` (max-norm, relative to max(1, |x|)): minima of equal cost on different
    trajectories (mirror images, e.g. the plate-ball's) stay apart.
    """
    found: list[tuple[Minimum, np.ndarray]] = []
    for r in sorted((r for r in results if r.success), key=lambda r: r.cost):
        if not any(abs(r.cost - m.cost) <= rtol * max(1.0, abs(m.cost))
                   and np.max(np.abs(r.x - x)) <= xtol * max(1.0, float(np.max(np.abs(x))))
                   for m, x in found):
            found.append((Minimum(r.cost, r.label, r.status, r.iterations), r.x))
    return [m for m, _ in found]


class CompiledProblem:
    """A compiled problem: build once, solve for any parameters, boundary values and T.

    ``CompiledProblem(problem, method, options)`` with an :class:`~ocgroupoid.nlp.method.Method` and
    :class:`~ocgroupoid.nlp.options.SolverOptions` (default: every default), their fields
    replaceable by keywords (``CompiledProblem(problem, N=32, backend="fatrop")``,
    :func:`~ocgroupoid.nlp.shortcuts.choose`).

    ``max_seconds`` bounds the wall time of one :meth:`solve` (every start and grid): a start
    past it is stopped (IPOPT at its next iteration, fatrop at once by its guard,
    :mod:`~ocgroupoid.nlp.backends.fatrop`) with status ``Maximum_WallTime_Exceeded``, the starts
    left are skipped, and the best point so far is returned.

    >>> solver = compile_problem(problem, N=64)            # doctest: +SKIP
    >>> sol = solver.solve(params={"inertia": [2, 1, 1]})  # doctest: +SKIP
    """

    def __init__(self, problem: Problem, method: Method | int | None = None,
                 options: SolverOptions | str | None = None, *positional: Any,
                 **keywords: Any) -> None:
        method, options = choose(method, options, *positional, **keywords)
        self.problem, self.options = problem, options
        self.ipopt = options.ipopt
        self.max_seconds = options.max_seconds
        self.disc = Discretization.of(method)
        self.transcription = Transcription(problem, self.disc, options)
        self._coarse: dict[tuple[int, str | None, int | None], Transcription] = {}
        self._phased: dict[tuple[Any, ...], Transcription] = {}

    def _at(self, N: int, scheme: str | None = None, max_iter: int | None = None
            ) -> Transcription:
        """The transcription on N intervals, with another scheme (continuation) and another
        iteration limit (a rescue) if given."""
        if N == self.disc.N and scheme is None and max_iter is None:
            return self.transcription
        if (N, scheme, max_iter) not in self._coarse:
            disc = replace(self.disc, N=N, scheme=scheme or self.disc.scheme)
            if scheme is not None and not SCHEMES[scheme][self.problem.order].adaptive_steps:
                # a start on the way (continuation, rescue): uniform steps, bounds at the
                # scheme's own points; the adaptive steps are placed on the final solve
                disc = replace(disc, steps="uniform", bound_points=0)
            options = self.options if max_iter is None else \
                replace(self.options, ipopt={**self.options.ipopt, "max_iter": max_iter})
            self._coarse[N, scheme, max_iter] = Transcription(self.problem, disc, options)
        return self._coarse[N, scheme, max_iter]

    def guesses(self, tr: Transcription, p: np.ndarray, multistart: bool | int) -> list[Guess]:
        """The first geodesic guess; with ``multistart`` every geodesic guess, the model's own
        and ``multistart`` (True: 3) deterministic perturbations."""
        geo = geodesic_guesses(tr, p)
        if not multistart:
            return geo[:1]
        count = 3 if multistart is True else int(multistart)
        return geo + model_guesses(tr, p, geo[0]) + perturbed_guesses(geo[0], tr.horizon_of(p),
                                                                       count)

    def solve(self, params: dict[str, Any] | None = None, initial: dict[str, Any] | None = None,
              final: dict[str, Any] | None = None, T: float | None = None,
              multistart: bool | int | None = None,
              continuation: Sequence[int | str] | None = None,
              guess: Guess | Solution | np.ndarray | None = None, replay: bool = True,
              progress: Progress = _noop,
              replay_tolerance: float = REPLAY_TOLERANCE, warm: Solution | None = None
              ) -> Solution:
        """Solve with IPOPT and return a diagnosed Solution; ``success`` is the
        :mod:`~ocgroupoid.verify.verdict` (IPOPT converged and the solution checked out).

        ``multistart``: True (every geodesic guess, the model's guesses and 3 perturbations;
        a further start gets the budget :data:`START_BUDGET`; the default of problem files
        and the CLI), False (the first geodesic only; the default of the options, which the
        exported C solver shares) or the number of perturbed starts; the starts run on
        ``options.workers`` processes (:mod:`~ocgroupoid.solve.parallel`). ``continuation``:
        coarser N solved first, in order, then the schemes it names on this N (e.g.
        ``[16, "order2"]``); the last of them gives the Solution a Richardson
        estimate of its cost error (:attr:`Solution.error_estimate`); both default to the
        solver options'. When every start of the final grid fails of itself, a scheme with a
        cheaper sibling (:attr:`Scheme.rescue`: order2 for order4) is rescued through it
        (:meth:`_rescue`, ``diagnostics["rescue"]``); with fatrop, the first start is, before
        IPOPT's fallback (:meth:`_through`, backend ``fatrop through order2``). ``replay``:
        drive the controls through the continuous dynamics (a few ms; it decides whether the
        plan lands, ``replay_tolerance``). ``progress`` hears each start and, every 0.25 s,
        IPOPT's iteration. Ctrl-C stops the solve with the best point so far, ``status:
        interrupted``. ``guess``: where to start instead of the geodesic guesses: an
        :class:`og.Guess` (interval velocities, N x dim y), a Solution of the same problem on
        any grid or scheme (interpolated onto this one; from another grid of this scheme, with
        IPOPT, with its multipliers carried over as in continuation), or an array of interval
        velocities.
        ``warm``: a Solution of this compiled problem (same N and structure) to start from,
        primal and dual (IPOPT's warm start), for re-solves with new parameters or boundary
        values; one start, no continuation.
        """
        if multistart is None:
            multistart = self.options.multistart
        if continuation is None:
            continuation = self.options.continuation
        if warm is not None:
            if warm.x.size != self.transcription.nx or warm.lam_g.size != self.transcription.ng:
                raise ConfigError(
                    f"warm: the solution has {warm.x.size} variables and {warm.lam_g.size} "
                    f"multipliers, this NLP {self.transcription.nx} and "
                    f"{self.transcription.ng}: warm-start from a solution of the same compiled "
                    "problem (same N and structure), or pass guess= instead")
            guess = Guess("warm start", np.zeros((0, 0)), warm.x, warm.lam_g, warm.lam_x)
            multistart, continuation = False, None
        levels = sorted(set(int(n) for n in (continuation or []) if not isinstance(n, str)))
        if any(n >= self.disc.N for n in levels):
            raise ConfigError(f"continuation grids must be coarser than N={self.disc.N}: {levels}")
        schemes = [n for n in (continuation or []) if isinstance(n, str)]
        if self.disc.scheme in schemes or len(set(schemes)) < len(schemes):
            raise ConfigError(f"continuation: the schemes solved first on the final grid must "
                              f"differ from each other and from the solve's own "
                              f"({self.disc.scheme}), got {list(continuation or [])}")
        results: list[RawResult] = []
        multi: dict[str, Any] = {}  # diagnostics["multistart"]
        given = guess
        prev: tuple[Transcription, RawResult] | None = None  # the last grid: the result
        source = prev  # the last grid solved: the next one starts from it
        coarse = prev  # the grid of this scheme solved before the last one (continuation)
        same = prev  # the last grid solved with this scheme
        notes: list[str] = []  # continuation grids that failed or landed above a minimum
        rescue: dict[str, Any] | None = None  # diagnostics["rescue"]
        self._spent = 0.0  # solver seconds of every run of this solve: starts, grids, phases
        adaptive: dict[str, Any] = {}
        deadline = time.monotonic() + self.max_seconds
        with interruptible() as interrupt:
            plan: list[tuple[int, str | None]] = [*((n, None) for n in levels),
                                                  *((self.disc.N, s) for s in schemes),
                                                  (self.disc.N, None)]
            for i, (n, scheme) in enumerate(plan):
                tr = self._at(n, scheme)
                p = tr.pack(params, initial, final, T)
                starts = self._starts_of(tr, p, source, given, multistart)
                # the cheaper scheme a failure of the final grid is rescued through, if any
                cheaper = tr.scheme.rescue if i == len(plan) - 1 and not schemes and \
                    not _whole_point(given) else None
                through = self._through(tr, cheaper, (params, initial, final, T)) \
                    if cheaper and tr.fatrop is not None else None
                level, report = self._starts(tr, starts, p, progress, interrupt, deadline,
                                             through)
                best = min(level, key=lambda r: (not r.success, r.cost))
                primal = starts[0].primal
                if primal is not None and not best.success and not interrupt.requested and \
                        time.monotonic() < deadline:  # the carried warm start failed
                    again, _ = self._starts(tr, [primal], p, progress, interrupt, deadline,
                                            through)
                    notes.append(f"N={n}: the warm start ({starts[0].label}) ended "
                                 f"{best.status}; solved again without the multipliers "
                                 f"({again[0].status})")
                    level = [*level, *again]  # a rescue follows only if this failed too
                    best = min(level, key=lambda r: (not r.success, r.cost))
                if cheaper and tr.fatrop is None and _rescuable(level) and \
                        not interrupt.requested and time.monotonic() < deadline:
                    via = self._at(n, cheaper)
                    pv = via.pack(params, initial, final, T)
                    rescued, rescue = self._rescue(
                        tr, p, via, pv, self._starts_of(via, pv, source, given, False)[0],
                        level[0], progress, interrupt, deadline)
                    best = rescued or best
                elif cheaper and through is not None and best.backend == through_label(cheaper):
                    rescue = _through_report(best, tr.disc.scheme, cheaper)
                if len(plan) == 1 and not best.success and _rescuable(level) and \
                        n // GRID_RESCUE >= GRID_RESCUE_MIN and not _whole_point(given) and \
                        not interrupt.requested and time.monotonic() < deadline:
                    rescued, rescue = self._grid_rescue(
                        tr, p, starts[0], level[0], (params, initial, final, T), rescue,
                        progress, interrupt, deadline)
                    best = rescued or best
                if i == 0:
                    results, multi = level, report
                if scheme is None and same is not None and not interrupt.requested and \
                        _higher(best, same[1], CONTINUATION_GAP):  # against this scheme's
                    best, note = self._bridge(same, n, best, params, initial, final, T, progress)
                    notes.append(note)
                prev = (tr, best)
                if best.success:
                    source = prev
                elif i < len(plan) - 1 and not interrupt.requested:
                    notes.append(f"continuation: {tr.disc.scheme} on N={n} failed "
                                 f"({best.status}); the next grid starts from "
                                 + (f"N={source[0].N} ({source[0].disc.scheme}), the last "
                                    "solved" if source else "the guesses, not from it"))
                if scheme is None:
                    coarse, same = same, prev
                if interrupt.requested or time.monotonic() > deadline:
                    break
            assert prev is not None
            tr, best = prev
            if interrupt.requested:
                best = replace(best, status="interrupted", success=False)
            elif self.disc.steps == "adaptive" and best.success:
                tr, best, adaptive = self._adapt(tr, best, params, initial, final, progress)
        progress("diagnostics")
        solution = make_solution(tr, best, distinct_minima(results), replay, self.ipopt,
                                 replay_tolerance)
        if self.disc.steps == "adaptive" and not interrupt.requested and best.success:
            solution.diagnostics["adaptive"] = adaptive
            solution.discretization["steps"] = "adaptive" if adaptive["used"] else "uniform"
            if not adaptive["used"] and len(adaptive["phases"]) > 1:  # switches, unresolved
                why = (f"adaptive steps were asked for but not used: {adaptive['reason']}; "
                       "this uniform solution does not resolve the switches of its controls "
                       "to the scheme's order: ask for uniform steps (a finer N), or another N")
                solution = replace(solution, success=False, hint="; ".join(
                    filter(None, [why, solution.hint])))
                solution.diagnostics["verdict"]["verified"] = False
                solution.diagnostics["verdict"]["failures"].append(why)
        if multi["starts"] > 1:
            solution.diagnostics["multistart"] = multi
        if len(plan) > 1:  # the minima are the first grid's starts'
            solution.diagnostics["minima_grid"] = {"N": plan[0][0],
                                                   "scheme": plan[0][1] or self.disc.scheme}
        if rescue is not None:
            solution.diagnostics["rescue"] = rescue
            if not solution.success:
                solution = replace(solution, hint="; ".join(
                    filter(None, [rescue["message"], solution.hint])))
        if notes:
            solution.diagnostics["continuation"] = notes
            solution = replace(solution, hint="; ".join([*notes, *filter(None, [solution.hint])]))
        if coarse is not None and coarse[1].success and best.success and \
                tr is self.transcription:  # Richardson from the last continuation grid
            order = tr.scheme.cost_order
            solution.diagnostics["error_estimate"] = richardson.estimate(
                best.cost, coarse[1].cost, tr.N, coarse[0].N, order, order)
        return replace(solution, starts=len(results),
                       ipopt_seconds_total=self._spent)

    def _starts_of(self, tr: Transcription, p: np.ndarray,
                   source: tuple[Transcription, RawResult] | None, given: Any,
                   multistart: bool | int) -> list[Guess]:
        """The starts of one grid: the last solved grid's solution interpolated onto it (with
        its multipliers where they carry over, :func:`~ocgroupoid.solve.multipliers.onto`),
        else the guess given (a Solution of another grid: with its multipliers too, where
        they carry over), else the geodesic (and with ``multistart`` every) guess."""
        if source is not None:
            return [onto(source[0], source[1], tr, p)]
        if given is not None:
            if isinstance(given, Guess) and given.primal is not None and \
                    given.x is not None and given.x.size != tr.nx:  # a rescue's scheme
                given = given.primal
            start = as_guess(given, tr, p)
            rows = self._rows_of(given) if isinstance(given, Solution) else None
            if rows is not None and start.x is None:
                start = with_multipliers(rows, given, tr, p, start)  # another grid's
            return [start]
        return self.guesses(tr, p, multistart)

    def _rows_of(self, sol: Solution) -> Rows | None:
        """The constraint rows ``sol``'s multipliers are laid out in: its own, or, for a
        Solution read from a file (which keeps none), those of this problem's grid of its N,
        where it was solved on one like it: the same problem (by name), scheme, retraction
        and rule, uniform steps, and a point and finite multipliers of that grid's sizes. None
        otherwise (its velocities alone start the solve)."""
        if sol.rows is not None:
            return sol.rows
        d = sol.discretization
        if sol.problem != self.problem.name or sol.lam_g.size == 0 or sol.N < 1 or \
                not (np.isfinite(sol.lam_g).all() and np.isfinite(sol.lam_x).all()) or \
                d.get("steps", "uniform") != "uniform" or \
                (d.get("scheme"), d.get("retraction"), d.get("rule")) != \
                (self.disc.scheme, self.transcription.scheme.retraction, self.disc.rule):
            return None
        rows = Rows.of(self._at(sol.N))
        return rows if (rows.nx, rows.ng) == (sol.x.size, sol.lam_g.size) and \
            sol.lam_x.size == rows.nx else None

    def _rescue(self, tr: Transcription, p: np.ndarray, via: Transcription, pv: np.ndarray,
                start: Guess, failed: RawResult, progress: Progress, interrupt: Interrupt,
                deadline: float) -> tuple[RawResult | None, dict[str, Any]]:
        """Every start of the final grid failed, the first (``failed``) of itself: solve the
        cheaper scheme ``via`` (:attr:`Scheme.rescue`, order2 for order4) on the same grid
        from the first start, then this grid from its solution (``continuation: [order2]``
        after the fact: a start far from the optimum converges in the cheap scheme, and the
        costly one then takes a few steps). The rescued run if it succeeded, else None; and
        ``diagnostics["rescue"]``."""
        name, other = tr.disc.scheme, via.disc.scheme
        runs: list[RawResult] = []
        for t, q in ((via, pv), (tr, p)):
            g = interpolate(via, runs[0].x, runs[0].p, t.N) if runs else start
            where = f"N={t.N}: {name} failed ({failed.status}), rescue: {t.disc.scheme}"
            progress(where)
            listen, stop = parallel.watch(where, progress, interrupt, parallel.fixed(None),
                                          deadline, PROGRESS_EVERY)
            r = t.solve(g, q, listen, deadline, stop)
            runs.append(parallel.timed(r, deadline))
            self._spent += r.solve_seconds
            if not r.success or interrupt.requested or time.monotonic() > deadline:
                break
        done = len(runs) == 2 and runs[1].success
        what = (f"{name} failed from the start '{start.label}' ({failed.status}); "
                + ("solved" if done else "tried") + f" {other} on the same grid first, then "
                f"{name} from its solution: " + ", ".join(
                    f"{t} {r.status} in {r.iterations} iterations"
                    for t, r in zip((other, name), runs)))
        report = {"message": what, "scheme": other, "failed": failed.status,
                  "rescued": done, "iterations": [r.iterations for r in runs],
                  "seconds": sum(r.solve_seconds for r in runs)}
        if not done:
            return None, report
        return replace(runs[1], label=f"{start.label}, through {other}"), report

    def _grid_rescue(self, tr: Transcription, p: np.ndarray, start: Guess, failed: RawResult,
                     pack: tuple[Any, ...], before: dict[str, Any] | None, progress: Progress,
                     interrupt: Interrupt, deadline: float
                     ) -> tuple[RawResult | None, dict[str, Any]]:
        """Every start of the final grid failed, the first (``failed``) of itself, and the
        scheme's rescue (``before``, its report) if it had one: solve N / :data:`GRID_RESCUE`
        from the first ``start`` (interpolated onto it), then this grid from its solution with
        its multipliers carried (``continuation: [N / 4]`` after the fact: a crude start that
        the fine grid cannot solve from, the coarse one may, and the fine grid then takes a few
        steps), from its velocities alone if that fails. The rescued run if it succeeded, else
        None; and ``diagnostics["rescue"]`` (``before``'s, extended)."""
        coarse = self._at(tr.N // GRID_RESCUE)
        runs: list[RawResult] = []
        what = f"{tr.disc.scheme} on N={tr.N} failed from the start '{failed.label}' " \
               f"({failed.status})"

        def solve(t: Transcription, q: np.ndarray, where: str, g: Guess) -> RawResult:
            listen, stop = parallel.watch(where, progress, interrupt, parallel.fixed(None),
                                          deadline, PROGRESS_EVERY)
            r = parallel.timed(t.solve(g, q, listen, deadline, stop), deadline)
            self._spent += r.solve_seconds
            return r

        for t in (coarse, tr):
            q = p if t is tr else t.pack(*pack)
            first = self._starts_of(t, q, (coarse, runs[0]), None, False)[0] if runs else \
                interpolate(tr, tr.start_point(start, p)[0], p, coarse.N)
            where = f"{what}, rescue: N={t.N}" + (f" from N={coarse.N}" if runs else "")
            progress(where)
            r = from_carried(first, partial(solve, t, q, where), lambda r: r.success,
                             lambda: not interrupt.requested and time.monotonic() <= deadline)[-1]
            runs.append(r)
            if not r.success or interrupt.requested or time.monotonic() > deadline:
                break
        done = len(runs) == 2 and runs[1].success
        told = (("" if before is None else "then ") + ("solved" if done else "tried")
                + f" N={coarse.N} first, then N={tr.N} from its solution: " + ", ".join(
                    f"N={t.N} {r.status} in {r.iterations} iterations"
                    for t, r in zip((coarse, tr), runs)))
        report = {"message": f"{what}; {told}" if before is None else
                  f"{before['message']}; {told}",
                  "grid": coarse.N, "failed": failed.status, "rescued": done,
                  "iterations": [*(before or {}).get("iterations", []),
                                 *(r.iterations for r in runs)],
                  "seconds": (before or {}).get("seconds", 0.0)
                  + sum(r.solve_seconds for r in runs),
                  **({"scheme": before["scheme"]} if before and "scheme" in before else {})}
        if not done:
            return None, report
        return replace(runs[1], label=f"{failed.label}, through N={coarse.N}"), report

    def _through(self, tr: Transcription, name: str, pack: tuple[Any, ...]) -> Rescue:
        """The rescue of a start fatrop failed on (:func:`~ocgroupoid.nlp.backends.in_turn`,
        before IPOPT's fallback): fatrop on the scheme ``name`` (order2) on the same grid from
        the start's velocities (built on first use, in the solving process), then fatrop again
        from its solution; the run in ``tr``'s variables. Both runs are fatrop's alone, with
        :data:`RESCUE_ITERATIONS`: where they fail the start is hopeless more often than not,
        and IPOPT's fallback follows anyway. Not after fatrop ran out of iterations: that is a
        crawl near a solution (quadrotor_min_time, N = 256, before fatrop's acceptable stop:
        500 iterations, the cost 1e-5 above the optimum), which the rescue's order4 run
        repeats (the solve took 37 s with the rescue, 27-32 s without), and IPOPT's fallback
        finishes; nor after fatrop's acceptable stop, which IPOPT polishes
        (:func:`~ocgroupoid.nlp.backends.in_turn`)."""
        assert tr.backends[0].name == "fatrop"  # (through_label)

        def rescue(start: Start, failed: Run) -> tuple[Run, str] | None:
            if failed.status == MAX_ITER:  # a crawl, not a breakdown: IPOPT's to finish
                return None
            via = self._at(tr.N, name, RESCUE_ITERATIONS)
            x0, pv = via.start_point(interpolate(tr, start.x0, start.p, tr.N), via.pack(*pack))
            cheap = via.backends[0].run(replace(start, x0=x0, p=pv, lam_g0=None, lam_x0=None))
            if not cheap.success:
                return replace(cheap, x=start.x0, f=float("nan"), lam_g=np.zeros(tr.ng),
                               lam_x=np.zeros(tr.nx)), f"{name} rescue"
            x0, _ = tr.start_point(interpolate(via, cheap.x, pv, tr.N), start.p)
            again = self._at(tr.N, None, RESCUE_ITERATIONS).backends[0]  # tr's NLP
            run = again.run(replace(start, x0=x0, lam_g0=None, lam_x0=None))
            run = replace(run, seconds=run.seconds + cheap.seconds,
                          earlier=((name, cheap.status, cheap.iterations),))
            return run, through_label(name) if run.success else f"{name} rescue"

        return rescue

    def _starts(self, tr: Transcription, starts: list[Guess], p: np.ndarray,
                progress: Progress, interrupt: Interrupt, deadline: float,
                rescue: Rescue | None = None) -> tuple[list[RawResult], dict[str, Any]]:
        """The starts of one grid, in order, on worker processes (``options.workers``,
        :mod:`~ocgroupoid.solve.parallel`) or in turn, each after the first with
        the budget :data:`START_BUDGET` (from the first start that succeeded before it); none
        started after Ctrl-C or the deadline. The first, which has no budget, has ``rescue``
        between fatrop's failure and IPOPT's fallback (:meth:`_through`); the others' fallback
        is bounded by their budget, if they have one. With
        ``diagnostics["multistart"]``: the starts asked for and finished, the workers, the
        wall time of all, the sum of their solver times, the best start's, and the starts
        their budget stopped (status :data:`~ocgroupoid.solve.parallel.BUDGET_SPENT`)."""
        t0 = time.perf_counter()
        workers, why = parallel.plan(self.options.workers, len(starts))

        def where(i: int) -> str:
            return f"N={tr.N}: start {i + 1}/{len(starts)} ({starts[i].label})"

        failed: list[dict[str, Any]] = []
        if workers > 1:
            level, failed = parallel.run(tr, starts, p, workers, where, progress, interrupt,
                                         deadline, START_BUDGET, PROGRESS_EVERY, rescue)
        else:
            level = []
            for i, g in enumerate(starts):
                progress(where(i))
                budget = parallel.budget_of(dict(enumerate(level)), i, START_BUDGET)[1]
                listen, stop = parallel.watch(where(i), progress, interrupt,
                                              parallel.fixed(budget), deadline, PROGRESS_EVERY)
                r = tr.solve(g, p, listen, deadline, stop, rescue if i == 0 else None)
                if i > 0:
                    r = parallel.budgeted(r, deadline, interrupt.requested)
                level.append(parallel.timed(r, deadline))
                if interrupt.requested or time.monotonic() > deadline:
                    break
        spent = sum(r.solve_seconds for r in level)
        self._spent += spent
        best = min(level, key=lambda r: (not r.success, r.cost))
        report = {"starts": len(starts), "finished": len(level), "workers": workers,
                  "wall_seconds": time.perf_counter() - t0, "sequential_seconds": spent,
                  "best_start_seconds": best.solve_seconds}
        spent_budget = [r.label for r in level if r.status == parallel.BUDGET_SPENT]
        return level, {**report, **({"note": why} if why else {}),
                       **({"failed": failed} if failed else {}),
                       **({"budget_spent": spent_budget} if spent_budget else {})}

    def _bridge(self, prev: tuple[Transcription, RawResult], n: int, landed: RawResult,
                params: dict[str, Any] | None, initial: dict[str, Any] | None,
                final: dict[str, Any] | None, T: float | None, progress: Progress
                ) -> tuple[RawResult, str]:
        """The grid n landed above the minimum the coarser grid found: solve it again through
        every doubling of the coarse grid (each interpolated from the last), keep the cheaper
        of the two, and say what happened."""
        (ctr, cr), m = prev, prev[0].N * 2
        chain = []
        while m < n:
            chain.append(m)
            m *= 2
        src = prev
        for k in [*chain, n]:
            tr = self._at(k)
            p = tr.pack(params, initial, final, T)
            progress(f"N={k}: continued from N={src[0].N} (bridging)")
            r = tr.solve(interpolate(src[0], src[1].x, src[1].p, k), p)
            self._spent += r.solve_seconds
            src = (tr, r)
        bridged = src[1]
        better = min((landed, bridged), key=lambda r: (not r.success, r.cost))
        what = (f"continuation: N={n} interpolated from N={ctr.N} landed at cost "
                f"{landed.cost:.6g}, above the minimum {cr.cost:.6g} that N={ctr.N} found")
        if better is bridged and not _higher(bridged, cr, CONTINUATION_GAP):
            return better, (f"{what}; solving through N={', '.join(map(str, chain or [n]))} "
                            f"reached {bridged.cost:.6g}, kept")
        return better, (f"{what}, and through the doublings too ({bridged.cost:.6g}): "
                        f"kept {better.cost:.6g}; the fine grid may lack that minimum, or "
                        "try solver.continuation with grids closer together, or multistart "
                        "on the fine grid")

    def _adapt(self, tr: Transcription, r: RawResult, params: dict[str, Any] | None,
               initial: dict[str, Any] | None, final: dict[str, Any] | None,
               progress: Progress) -> tuple[Transcription, RawResult, dict[str, Any]]:
        """Adaptive steps: the phases between the switches of the uniform solution r
        (:mod:`ocgroupoid.nlp.mesh`), their durations solved for. The phased solution is
        kept only when it solved and its plan lands at least as well as the uniform one's
        (driven through the continuous problem: a mesh that stretches an arc over a few long
        steps can shorten the discrete T below the optimum, and the replay shows it);
        otherwise r, and the report (``diagnostics["adaptive"]``) says why."""
        phases = mesh.phases(tr, r)
        report: dict[str, Any] = {"used": False, "phases": list(phases)}
        if len(phases) < 2:
            report["reason"] = "no switch of the bounds' active set: uniform steps kept"
            return tr, r, report
        src, result, phased = (tr, r), None, tr
        for _ in range(MESH_ROUNDS):  # the switches a phased solve shows: the next mesh
            progress(f"adaptive steps: phases of {', '.join(map(str, phases))} intervals")
            held = mesh.held_sides(src[0], src[1], phases)
            key = (phases, held)
            if key not in self._phased:
                self._phased[key] = Transcription(
                    self.problem, replace(self.disc, phases=phases, active=held), self.options)
            phased = self._phased[key]
            p = phased.pack(params, initial, final, src[0].horizon(src[1].x, src[1].p))
            result = phased.solve(interpolate(src[0], src[1].x, src[1].p, self.disc.N), p)
            self._spent += result.solve_seconds
            if not result.success:
                break
            src = (phased, result)
            report["phases"] = list(phases)
            report["held"] = [list(h) for h in held]
        assert result is not None
        if src[0] is tr:  # no phased solve succeeded
            report["reason"] = f"the phased solve ended {result.status}: uniform steps kept"
            return tr, r, report
        phased, result = src
        miss = {"uniform": landing(tr, r), "adaptive": landing(phased, result)}
        report["landing"] = miss
        if miss["adaptive"] > 1.1 * miss["uniform"] + LANDING_FLOOR:
            report["reason"] = (f"the phased plan lands worse than the uniform one "
                                f"({miss['adaptive']:.2g} against {miss['uniform']:.2g} of the "
                                "distance covered): uniform steps kept")
            return tr, r, report
        report["used"] = True
        report["steps"] = [float(v) for v in result.x[phased.layout.phase_steps] / self.disc.N]
        return phased, result, report


#: phased solves of adaptive steps (the phases on the switches of the uniform solve, its
#: bang-bang arcs held at their bound)
MESH_ROUNDS = 1
#: landing misses (fractions of the distance covered) below this are exact for the comparison
LANDING_FLOOR = 1e-10


def through_label(scheme: str | None) -> str:
    """The backend of a run fatrop's rescue (:meth:`CompiledProblem._through`) produced."""
    return f"fatrop through {scheme}"


def _through_report(best: RawResult, name: str, cheaper: str) -> dict[str, Any]:
    """``diagnostics["rescue"]`` of a start fatrop's rescue solved (:meth:`_through`): fatrop's
    failed run and the rescue's two (``best.earlier`` and ``best``)."""
    (_, status, tried), (_, _, cheap) = best.earlier[:2]
    return {"message": f"fatrop failed from the start '{best.label}' ({status} after {tried} "
            f"iterations); solved {cheaper} on the same grid first in {cheap} iterations "
            f"(fatrop, at most {RESCUE_ITERATIONS}), then {name} from its solution in "
            f"{best.iterations}, before IPOPT's fallback", "scheme": cheaper, "failed": status,
            "backend": "fatrop", "rescued": True, "iterations": [tried, cheap, best.iterations],
            "seconds": best.solve_seconds}


def _rescuable(level: list[RawResult]) -> bool:
    """Whether a grid's failure may be rescued through a cheaper scheme: every start failed,
    the first of itself (not stopped by the time or an interrupt; the further starts may
    have been stopped by their budget)."""
    return not any(r.success for r in level) and \
        level[0].status not in (TIMED_OUT, INTERRUPTED, LISTENER_STOP)


def _whole_point(guess: Any) -> bool:
    """Whether a given guess is a point of one NLP (a warm start), which another scheme's
    cannot start from (a start carried from a coarser grid can: its velocities)."""
    return isinstance(guess, Guess) and guess.x is not None and guess.primal is None


def landing(tr: Transcription, r: RawResult) -> float:
    """The largest miss of a solved point's plan, driven through the continuous problem, as a
    fraction of the distance each quantity covers (inf when it cannot be driven)."""
    out = tr.readout(r.x, r.p, r.lam_g)
    rep = replay_of(tr).run(out, control_ppoly(out), r.p)
    if not rep.get("available"):
        return float("inf")
    scale = scales(tr, out, r.p)
    return max((e / max(scale.get(n, 0.0), 1e-12) for n, e in rep["terminal_error"].items()),
               default=0.0)


#: a continued grid whose cost exceeds the coarser grid's minimum by more than this fraction
#: landed on another minimum (discretisation alone moves a cost by far less between grids)
CONTINUATION_GAP = 0.01


def _higher(fine: RawResult, coarse: RawResult, gap: float) -> bool:
    """Whether a solved fine grid landed above a solved coarse grid's minimum by more than
    ``gap`` of its size (or failed where the coarse grid solved)."""
    if not coarse.success:
        return False
    if not fine.success:
        return True
    return fine.cost > coarse.cost + gap * max(abs(coarse.cost), 1e-12)
