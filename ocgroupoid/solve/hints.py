"""What went wrong and what to try: hints from IPOPT's status and the last iterate."""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..nlp.transcription import RawResult, Transcription
from ..verify.dependencies import dependent_conditions

HINTS = {
    "Infeasible_Problem_Detected": "the constraints and boundary conditions look incompatible "
    "from this start: a reachable goal can look so from a poor start, so try multistart "
    "(solver.multistart: true) first; then check the final values (are they reachable?) and "
    "the prescribed components; `ocgroupoid check` lists them",
    "Not_Enough_Degrees_Of_Freedom": "more equality constraints than variables: free a "
    "boundary value or drop a constraint (`ocgroupoid check` names the redundant ones)",
    "Maximum_Iterations_Exceeded": "try multistart, continuation from a coarser N, a longer "
    "horizon, or a larger solver.max_iter",
    "Invalid_Number_Detected": "a stage evaluated to NaN/Inf",
    "Diverging_Iterates": "the iterates left every physical scale (|x| > 1e8): start from "
    "another guess (multistart, continuation) or raise solver.ipopt.diverging_iterates_tol if "
    "your variables are that large",
    "Restoration_Failed": "IPOPT could not reduce the constraint violation: try another start "
    "(solver.multistart) or continuation; if every start fails, the final values may be "
    "unreachable with these controls",
    "Search_Direction_Becomes_Too_Small": "the problem may be degenerate: check for redundant "
    "boundary conditions",
    "Error_In_Step_Computation": "the KKT matrix is singular: check for redundant boundary "
    "conditions or constraints",
    "Maximum_WallTime_Exceeded": "the solve reached solver.max_seconds: raise it, lower N, "
    "or start closer (solver.continuation, fewer multistart starts)",
}


#: statuses where the conditions could not be met: the rank test at the last iterate names the
#: prescribed value that an unactuated direction or a conservation law fixes, and the row
#: violated most is quoted
UNMET = ("Restoration_Failed", "Infeasible_Problem_Detected",
         "Search_Direction_Becomes_Too_Small", "Error_In_Step_Computation")


def hint_for(tr: Transcription, r: RawResult, steps: np.ndarray) -> str:
    """The hint for a failed result; ``steps`` are its algebra increments (N x dim y)."""
    if r.success:
        return ""
    troubles = tr.scheme.troubles(np.concatenate([r.x, r.p]), failed=True)
    parts = [HINTS.get(r.status, "try multistart or continuation"), *troubles]
    if r.status == "Invalid_Number_Detected":
        if tr.scheme.retraction == "first_order":
            parts.append("with first_order a step turned by pi/2 or more; increase N or use "
                         "the cayley retraction")
        parts += nonsmooth(tr)
    if r.status in UNMET:
        if not troubles:  # a coordinate singularity also makes rows dependent: not the cause
            parts += [f"unreachable as posed: {d}, or prescribe the value the motion implies"
                      for d in dependent_conditions(tr, r.x, r.p)]
        parts.append(worst_violation(tr, r))
    G = tr.problem.groupoid
    for f, ret, vs in zip(G.factors, tr.scheme.retractions, G.velocity_layout.slices):
        step = float(np.max(ret.step_norm(steps[:, vs])))
        if tr.scheme.variational and step > 0.5 * ret.step_limit:  # baselines: no retraction
            parts.append(f"{f.velocity} turns {step:.3g} rad in one step ({ret.name} "
                         f"is singular at {ret.step_limit:.2f}); increase N")
    return "; ".join(parts)


def worst_violation(tr: Transcription, r: RawResult) -> str:
    """The constraint row the last iterate violates most, named (``final.p (component 1)``)."""
    g = np.array(tr.g_fun(r.x, r.p)).ravel()
    lbg, ubg = (np.array(v).ravel() for v in tr.bounds_function(r.p)[:2])
    miss = np.maximum(lbg - g, g - ubg)
    i = int(np.argmax(miss)) if miss.size else 0
    if not miss.size or miss[i] <= 0:
        return "the last iterate meets every constraint"
    return f"violated most at the last iterate: {tr.row_labels()[i]} (by {miss[i]:.2g})"


#: operations whose derivative is undefined where their argument is zero (norm = sqrt(sumsqr))
KINKS = {ca.OP_SQRT: "a square root or norm", ca.OP_FABS: "an absolute value"}


def nonsmooth(tr: Transcription) -> list[str]:
    """The user's expressions (cost, bounds, constraints) with a kink or an infinite
    derivative at zero — ``norm(F)`` at F = 0, at rest — and their smooth forms: IPOPT's
    derivatives there are NaN."""
    pb = tr.problem
    exprs = [("the cost", pb.cost), ("the terminal cost", pb.terminal),
             *[(f"bound {b.name!r}", b.expr) for b in pb.inequalities],
             *[(f"constraint {n!r}", c) for n, c in pb.constraints if n != "Phi"]]
    out = []
    for what, expr in exprs:
        if expr is None or not expr.numel():
            continue
        f = ca.Function("kinks", [ca.vertcat(*ca.symvar(expr))], [expr])
        found = sorted({KINKS[op] for k in range(f.n_instructions())
                        if (op := f.instruction_id(k)) in KINKS})
        if found:
            out.append(f"{what} takes {' and '.join(found)}, whose derivative is undefined "
                       "where its argument is 0 (norm(F) at F = 0, at rest): write a smooth "
                       "form — a squared norm sumsqr(F), sqrt(sumsqr(F) + eps**2), or the "
                       "magnitude as a control of its own (pb.control, thrust along a body "
                       "axis)")
    return out
