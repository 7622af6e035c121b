"""The verdict on a solution: ``success`` means verified, not only "IPOPT stopped".

A Solution is a success when every one of these holds, and otherwise it is not, with one
sentence per failed check in its hint (the CLI exits 1):

1. IPOPT reports ``Solve_Succeeded`` (``Solved_To_Acceptable_Level`` is not the requested
   tolerance).
2. The solution's own residuals are within :func:`check_tolerance` (``max(1e-6, 100 tol)``,
   ``tol`` IPOPT's): the discrete Euler-Lagrange residual with the solver's multipliers, the
   reconstruction and constraint residuals, the distance of the final state from its target,
   the distance of every state from its manifold, the violation of the bounds.
3. No prescribed condition is implied by the others at the solution
   (:mod:`~ocgroupoid.solve.dependencies`): LICQ holds.
4. The plan lands: the controls, replayed through the continuous dynamics
   (:mod:`~ocgroupoid.solve.replay`), reach every prescribed final value to within
   ``replay_tolerance`` (default :data:`REPLAY_TOLERANCE`, 5%) of the distance the
   trajectory covers in it (a state: the length of its path, or the distance from its start
   to its target if larger; a velocity: its largest magnitude). An under-resolved grid (steps
   of radians, an extreme inertia ratio) gives a discrete answer that the continuous system
   does not follow; this is where it is caught, with the grid to try. Where no replay exists
   (or ``replay=False``), steps beyond half the retraction's singular step fail instead, and
   a first-order problem's constraints are checked at the nodes, between the points where
   the scheme imposes them (:func:`_between_points`).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..nlp.transcription import DEFAULT_IPOPT, RawResult, Transcription
from .dependencies import dependent_conditions
from .replay import terminal_errors

REPLAY_TOLERANCE = 0.05  # replay terminal error / distance covered
FLOOR = 1e-8  # absolute floor of the replay tolerance (a problem that stays at rest)
RESIDUALS = {  # diagnostics key -> what it measures
    "euler_lagrange_residual_max": "discrete Euler-Lagrange residual",
    "reconstruction_residual_max": "reconstruction residual",
    "constraint_residual_max": "constraint residual",
    "bound_violation_max": "bound violation",
}


def check_tolerance(ipopt: dict[str, Any] | None) -> float:
    """The residual threshold of a solution: ``max(1e-6, 100 tol)``, IPOPT's ``tol``."""
    tol = float({**DEFAULT_IPOPT, **(ipopt or {})}.get("tol", 1e-8))
    return max(1e-6, 100.0 * tol)


def scales(tr: Transcription, out: dict[str, np.ndarray], p: np.ndarray) -> dict[str, float]:
    """The distance every state and velocity covers (item 4 of the module docstring)."""
    G = tr.problem.groupoid
    s = out["node_states"]
    straight = terminal_errors(tr, s[0], None, p)
    found: dict[str, float] = {}
    for f, vs in zip(G.factors, G.velocity_layout.slices):
        path = float(np.sum(np.linalg.norm(out["steps"][:, vs], axis=1)))
        found[f.state] = max(path, straight.get(f.state, 0.0))
        found[f.velocity] = float(np.max(np.linalg.norm(out["velocities"][:, vs], axis=1)))
    return found


def suggested_N(N: int, ratio: float, order: int) -> int:
    """The grid that brings an error ``ratio`` times its tolerance within it, for a scheme of
    ``order`` (a power of two, at least 2N)."""
    factor = max(2.0, (2.0 * ratio) ** (1.0 / order))
    return int(2 ** np.ceil(np.log2(N * factor)))


def verdict(tr: Transcription, r: RawResult, out: dict[str, np.ndarray],
            d: dict[str, Any], ipopt: dict[str, Any] | None,
            replay_tolerance: float = REPLAY_TOLERANCE) -> list[str]:
    """Why the solution ``r`` (read out as ``out``, diagnosed as ``d``) is not a verified
    success: one sentence per failed check; [] when it is one (module docstring)."""
    if not r.success:
        return []  # IPOPT failed: its hint says why
    failures = []
    if r.status != "Solve_Succeeded":
        failures.append(f"IPOPT stopped at {r.status}, not at the requested tolerance: try "
                        "multistart, a finer N or a larger solver.ipopt.max_iter")
    tol = check_tolerance(ipopt)
    for key, what in RESIDUALS.items():
        if d.get(key, 0.0) > tol:
            failures.append(f"{what} {d[key]:.2g} exceeds {tol:.0e}")
    for group, what in (("final_residual", "misses its target by"),
                        ("manifold_distance", "is off its manifold by")):
        for name, value in d.get(group, {}).items():
            if value > tol:
                failures.append(f"{name} {what} {value:.2g} (more than {tol:.0e})")
    failures += dependent_conditions(tr, r.x, r.p)
    failures += tr.scheme.troubles(np.concatenate([r.x, r.p]))
    order = tr.scheme.accuracy
    rep = d.get("replay", {})
    if rep.get("available"):
        scale = scales(tr, out, r.p)
        worst = max(((e / (replay_tolerance * scale.get(n, 0.0) + FLOOR), n, e)
                     for n, e in rep["terminal_error"].items()), default=(0.0, "", 0.0))
        if worst[0] > 1.0:
            failures.append(
                f"the plan does not land: the controls replayed through the continuous "
                f"dynamics miss final.{worst[1]} by {worst[2]:.2g} "
                f"({worst[2] / max(scale[worst[1]], FLOOR):.1%} of the distance it covers, "
                f"tolerance {replay_tolerance:.0%}): the grid is too "
                f"coarse for this motion; increase N to {suggested_N(tr.N, worst[0], order)}")
    else:
        if "replay" in d:  # the problem has no replay (not: replay=False)
            failures += _between_points(tr, out, r.p, replay_tolerance)
        for name, angle in d.get("step_angle_max", {}).items():
            limit = next(ret.step_limit for f, ret in zip(tr.problem.groupoid.factors,
                                                         tr.scheme.retractions)
                         if f.velocity == name)
            if angle > 0.5 * limit:
                failures.append(f"{name} turns {angle:.3g} rad in one step (more than half of "
                                f"{limit:.2f}, where {tr.scheme.retraction} is singular): "
                                f"increase N to {suggested_N(tr.N, angle / (0.25 * limit), order)}")
    return failures


def _between_points(tr: Transcription, out: dict[str, np.ndarray], p: np.ndarray,
                    replay_tolerance: float) -> list[str]:
    """Without a replay, the constraints Phi(q, y) of a first-order problem checked where the
    scheme does not impose them: at the nodes, with the mean of the adjacent interval
    velocities. A solution of the continuous problem meets them there to O(h^2); a discrete
    artefact (a zigzag whose midpoints alone satisfy Phi, found when the continuous problem
    has no solution) misses them by O(1). Tolerance: ``replay_tolerance`` times the size of
    the states (at least 1)."""
    pb, G = tr.problem, tr.problem.groupoid
    if pb.order != 1 or not pb.constraints:
        return []
    S, V = out["node_states"], out["velocities"]
    if len(V) != len(S) - 1:
        return []
    V = np.vstack([V[:1], (V[1:] + V[:-1]) / 2, V[-1:]])
    s = ca.SX.sym("s", G.state_size)
    phi = ca.vertcat(*[c for _, c in pb.constraints])
    f = ca.Function("phi", [s, pb.y, pb.P], [ca.substitute(phi, pb.q, G.base(s))])
    worst = float(np.max(np.abs(np.array(f.map(len(S))(S.T, V.T, tr.part(p, "P"))))))
    tol = replay_tolerance * max(1.0, float(np.max(np.abs(S))))
    if worst <= tol:
        return []
    return [f"the constraints hold only where the scheme imposes them: at the nodes they miss "
            f"by {worst:.2g} (tolerance {tol:.2g}); the discrete answer is an artefact of the "
            "grid — the conditions may be incompatible (check the final values), or increase N"]
