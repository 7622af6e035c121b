"""The reference cost of a work-precision run, from two method families on fine grids.

1. order4 (cayley) on N0 = N/16 intervals from every start of the multi-start (the geodesic
   alone when the problem file turns multi-start off): the best minimum, and the first start
   in the multi-start's order that reaches it (the timed solves start there); the distinct
   minima met (:mod:`~ocgroupoid.bench.minimum` tells rows in another one by them).
2. order4 continued to N/4, N/2, N (each grid started from the last, interpolated, with its
   multipliers where IPOPT solves it: :func:`~ocgroupoid.solve.multipliers.onto`), then
   Richardson for order 4 (:mod:`~ocgroupoid.verify.richardson`):
   ``J_ref = J_N + (J_N - J_{N/2}) / 15``.
3. The check, another family: RK4 shooting on unit quaternions (``rk4_quat``) on N/4, N/2
   and N, started from the order4 solutions, Richardson with the order its three costs show
   (``log2((J_{N/2} - J_{N/4}) / (J_N - J_{N/2}))``, between 1 and 4). RK4 integrates the
   dynamics to fourth order, but its cost converges at second order: piecewise-constant
   controls approximate the optimal control only to O(h), its cost to O(h^2).

Both extrapolations, their difference and each one's Richardson estimate are kept; the
reference's relative uncertainty is the larger of the two measures (costs of problems with
active bounds or switching controls converge more slowly, which the difference shows). The
finest order4 solution is kept too: rows are compared with its path to tell minima apart.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from ..errors import ConfigError, SolverError
from ..model.problem import Problem
from ..nlp.transcription import RawResult
from ..solve import Solution, distinct_minima, interpolate, make_solution
from ..solve.multipliers import onto
from ..verify.richardson import observed_order, relative, richardson_error
from .methods import Method
from .minimum import SAME_COST
from .timing import Setting

ORDER = 4  # order4's order, assumed by its extrapolation
STEPS = 7  # solves: the multi-start at N0 (counted once), order4 and rk4_quat at 3 grids
Step = Callable[[str], None]


def check_reference_N(N: int) -> None:
    """The finest reference grid must be a power of two of at least 16 (N/16 >= 1)."""
    if N < 16 or N & (N - 1):
        raise ConfigError(f"--reference-N: give a power of two of at least 16, got {N}")


def extrapolated(coarse: float, fine: float, order: float) -> float:
    """``J_fine + (J_fine - J_coarse) / (2^order - 1)``: Richardson on grids N/2 and N."""
    return fine + (fine - coarse) / (2 ** order - 1)


def family_order(costs: list[float]) -> float | None:
    """The order three costs on grids N/4, N/2, N converge at (None when they do not)."""
    return observed_order(abs(costs[1] - costs[0]), abs(costs[2] - costs[1]))


def _solved(sol: Solution, what: str) -> Solution:
    if sol.status != "Solve_Succeeded":
        raise SolverError(f"the reference ({what}) did not solve: IPOPT {sol.status}. "
                          f"{sol.hint}".strip())
    return sol


def first_best(results: list[RawResult]) -> RawResult:
    """The first result, in the order of the starts, whose cost is the best one's."""
    solved = [r for r in results if r.success]
    if not solved:
        raise SolverError("the reference did not solve from any start: "
                          + ", ".join(f"{r.label}: {r.status}" for r in results))
    best = min(r.cost for r in solved)
    return next(r for r in solved if abs(r.cost - best) <= SAME_COST * max(1.0, abs(best)))


def reference(problem: Problem, setting: Setting, N: int, multistart: bool,
              step: Step) -> tuple[dict[str, Any], Solution]:
    """The reference cost on grids up to N (module docstring), and the finest order4
    solution; ``step`` hears each solve."""
    check_reference_N(N)
    N0 = max(4, N // 16)
    step(f"reference: order4 N={N0}" + (", every start" if multistart else ""))
    solver = setting.compile(problem, Method("order4"), N0)
    tr = solver.transcription
    p = tr.pack()
    results = [tr.solve(g, p) for g in solver.guesses(tr, p, multistart)]
    first = first_best(results)
    sol = make_solution(tr, first, distinct_minima(results), False, setting.ipopt)
    fine: dict[int, tuple[Any, Solution]] = {}
    for n in (N // 4, N // 2, N):
        step(f"reference: order4 N={n}")
        coarse = solver.transcription
        solver = setting.compile(problem, Method("order4"), n)
        guess = onto(coarse, sol, solver.transcription, solver.transcription.pack())
        sol = _solved(solver.solve(guess=guess, replay=False), f"order4, N={n}")
        fine[n] = (solver.transcription, sol)
    J4 = [fine[n][1].cost for n in (N // 4, N // 2, N)]
    J_ref = extrapolated(J4[1], J4[2], ORDER)
    estimate = richardson_error(J4[2], J4[1], ORDER)
    check = _check(problem, setting, N, fine, J_ref, step)
    uncertainty = max(relative(estimate, J_ref), check.get("relative_difference") or 0.0)
    return {"cost": J_ref, "method": f"order4 (cayley) at N={N // 2} and N={N}, continued "
            f"from N={N0}, Richardson (order 4): J_ref = J_N + (J_N - J_N/2)/15",
            "N": [N // 2, N], "costs": {str(n): J for n, J in zip((N // 4, N // 2, N), J4)},
            "observed_order": family_order(J4), "estimate": estimate,
            "start": first.label, "starts": len(results), "start_cost": first.cost,
            "minima": [m.__dict__ for m in distinct_minima(results)], "check": check,
            "relative_uncertainty": uncertainty}, fine[N][1]


def _check(problem: Problem, setting: Setting, N: int,
           fine: dict[int, tuple[Any, Solution]], J_ref: float, step: Step) -> dict[str, Any]:
    """rk4_quat on N/4, N/2, N from the order4 solutions, extrapolated with its observed
    order (module docstring, item 3)."""
    Ns = (N // 4, N // 2, N)
    check: dict[str, Any] = {"method": f"rk4_quat (RK4 shooting on unit quaternions) at "
                                       f"N={', '.join(map(str, Ns))}, Richardson with the "
                                       "observed order"}
    try:
        Jq = []
        for n in Ns:
            step(f"reference check: rk4_quat N={n}")
            tr, s = fine[n]
            shooting = setting.compile(problem, Method("rk4_quat"), n)
            Jq.append(_solved(shooting.solve(guess=interpolate(tr, s.x, s.p, n),
                                             replay=False), f"rk4_quat, N={n}").cost)
    except (ConfigError, SolverError) as e:  # the baseline may not apply to the problem
        return {**check, "cost": None, "reason": str(e)}
    order = family_order(Jq)
    used = float(np.clip(order, 1.0, 4.0)) if order is not None else 2.0
    J_check = extrapolated(Jq[1], Jq[2], used)
    return {**check, "costs": {str(n): J for n, J in zip(Ns, Jq)}, "observed_order": order,
            "order_used": used, "cost": J_check,
            "estimate": richardson_error(Jq[2], Jq[1], used), "difference": J_ref - J_check,
            "relative_difference": relative(abs(J_ref - J_check), J_ref)}
