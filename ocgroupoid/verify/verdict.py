"""The verdict on a solution: ``success`` means verified, not only "IPOPT stopped".

A Solution is a success when every one of these holds, and otherwise it is not, with one
sentence per failed check in its hint (the CLI exits 1):

1. IPOPT reports ``Solve_Succeeded`` (``Solved_To_Acceptable_Level`` is not the requested
   tolerance).
2. The solution's own residuals are within :func:`check_tolerance` (``max(1e-6, 100 tol)``,
   ``tol`` IPOPT's): the discrete Euler-Lagrange residual with the solver's multipliers, the
   reconstruction and constraint residuals, the distance of the final state from its target,
   the distance of every state from its manifold, the violation of the bounds at the points
   where the scheme imposes them.
3. No prescribed condition is implied by the others at the solution
   (:mod:`~ocgroupoid.verify.dependencies`): LICQ holds.
4. The plan was checked against the continuous problem (:mod:`~ocgroupoid.verify.replay`):
   driven through it (the dynamics, the kinematics of its controls, or for a first-order plan
   its velocities through ``g' = g y``), it reaches every prescribed final value to within
   the landing tolerance, ``replay_tolerance`` (default :data:`REPLAY_TOLERANCE`) of the
   distance the trajectory covers in it (a state: the length of its path, or the distance
   from its start to its target if larger; a velocity: its largest magnitude); along it,
   every bound holds to ``replay_tolerance`` of its size (on a dense grid: between the
   points too) and, for a first-order plan driven by its velocities, the constraints hold to
   ``replay_tolerance`` of the states' size. A problem with nothing to drive it (a
   second-order problem without mechanics whose controls are not accelerations), or
   ``replay=False``, is not verified: no success without a check.
5. The retraction stayed where it is accurate: no step of the seeds' ``first_order`` rule
   turns by more than :data:`FIRST_ORDER_RANGE` (its read-out ``sin`` of the angle lets a
   long step turn further than it pays for).

The Solution states what the check found: the tolerances (``diagnostics["verdict"]``), the
largest bound violation along the replay (``bound_violation_max``) and an a-posteriori
estimate of the cost's (and a free T's) error (``diagnostics["estimate"]``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..nlp.backends import DEFAULT_IPOPT
from ..nlp.transcription import RawResult, Transcription
from .dependencies import dependent_conditions
from .diagnostics import replay_of
from .replay import terminal_errors

REPLAY_TOLERANCE = 0.01  # replay terminal error / distance covered; bound violation / its size
FIRST_ORDER_RANGE = 0.5  # rad: the first_order rule's read-out is accurate to ~4% up to here
FLOOR = 1e-8  # absolute floor of the replay tolerance (a problem that stays at rest)
RESIDUALS = {  # diagnostics key -> what it measures
    "euler_lagrange_residual_max": "discrete Euler-Lagrange residual",
    "reconstruction_residual_max": "reconstruction residual",
    "constraint_residual_max": "constraint residual",
    "bound_violation_points": "bound violation at the points where the bounds are imposed",
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
            replay_tolerance: float = REPLAY_TOLERANCE,
            scale: dict[str, float] | None = None) -> list[str]:
    """Why the solution ``r`` (read out as ``out``, diagnosed as ``d``) is not a verified
    success: one sentence per failed check; [] when it is one (module docstring).
    ``scale``: :func:`scales` of ``out``, if the caller has it."""
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
    order = tr.scheme.cost_order
    rep = d.get("replay")
    if rep is None:
        failures.append("not verified: the plan was not checked against the continuous "
                        "problem (replay=False); solve with the replay on")
    elif not rep.get("available"):
        failures.append(f"not verifiable: {rep.get('reason', 'no replay')} — nothing drives "
                        "this plan through the continuous problem, so nothing confirms it")
    else:
        scale = scales(tr, out, r.p) if scale is None else scale
        failures += _landing(tr, rep, replay_tolerance, order, scale)
        failures += _along(tr, rep, replay_tolerance, order,
                           tolerances(tr, out, r.p, replay_tolerance, scale))
    failures += _rule_range(tr, d, order)
    return failures


def tolerances(tr: Transcription, out: dict[str, np.ndarray], p: np.ndarray,
               replay_tolerance: float, scale: dict[str, float] | None = None
               ) -> dict[str, Any]:
    """The absolute tolerances of item 4: per prescribed final value (landing), per bound
    (``replay_tolerance`` of its largest finite side, at least of 1) and for the constraints
    along a velocity-driven replay. ``scale``: :func:`scales` of ``out``, if the caller has
    it."""
    scale = scales(tr, out, p) if scale is None else scale
    landing = {n: float(replay_tolerance * v + FLOOR) for n, v in scale.items()}
    out_b: dict[str, float] = {}
    rep = replay_of(tr)  # its sides of every bound row, built once
    if rep.names:
        lo, hi = (np.array(v).ravel() for v in rep.sides(tr.part(p, "P")))
        for name, a, b in zip(rep.names, lo, hi):
            size = max([abs(v) for v in (a, b) if np.isfinite(v)] + [1.0])
            out_b[name] = float(replay_tolerance * size)
    states = float(np.max(np.abs(out["node_states"]))) if out["node_states"].size else 1.0
    return {"landing": landing, "bounds": out_b,
            "constraints": float(replay_tolerance * max(1.0, states))}


def _landing(tr: Transcription, rep: dict[str, Any], replay_tolerance: float, order: int,
             scale: dict[str, float]) -> list[str]:
    """Item 4: the replay reaches every prescribed final value within its tolerance (the
    distances covered: ``scale``)."""
    worst = max(((e / (replay_tolerance * scale.get(n, 0.0) + FLOOR), n, e)
                 for n, e in rep["terminal_error"].items()), default=(0.0, "", 0.0))
    if worst[0] <= 1.0:
        return []
    return [(f"the plan does not land: driven through the continuous problem it misses "
             f"final.{worst[1]} by {worst[2]:.2g} "
             f"({worst[2] / max(scale[worst[1]], FLOOR):.2%} of the distance it covers, "
             f"tolerance {replay_tolerance:.2%}): the grid is too coarse for this motion; "
             f"increase N to {suggested_N(tr.N, worst[0], order)}")]


def _along(tr: Transcription, rep: dict[str, Any], replay_tolerance: float, order: int,
           tol: dict[str, Any]) -> list[str]:
    """Item 4: the bounds (and a velocity-driven plan's constraints) along the replay (their
    tolerances: ``tol``)."""
    failures = []
    for name, v in rep.get("bound_violation", {}).items():
        limit = tol["bounds"].get(name, replay_tolerance)
        if v > limit:
            failures.append(
                f"bound {name} is violated by {v:.3g} between the points where it is imposed "
                f"(along the replayed plan; tolerance {limit:.2g}): increase N to "
                f"{suggested_N(tr.N, v / limit, order)}, or impose the bounds at more points "
                "per interval (discretization.bound_points)")
            break  # the worst is enough to act on; all are in diagnostics["bound_violation"]
    psi = rep.get("constraint_residual_max")
    if psi is not None and psi > tol["constraints"]:
        failures.append(
            f"the constraints hold only where the scheme imposes them: along the path the plan "
            f"drives they miss by {psi:.2g} (tolerance {tol['constraints']:.2g}); the discrete "
            f"answer is an artefact of the grid — the conditions may be incompatible (check "
            f"the final values), or increase N to "
            f"{suggested_N(tr.N, psi / tol['constraints'], order)}")
    return failures


def _rule_range(tr: Transcription, d: dict[str, Any], order: int) -> list[str]:
    """Item 5: steps of the first_order rule beyond its accurate range, and steps beyond half
    of any retraction's singular step."""
    failures = []
    for name, angle in d.get("step_angle_max", {}).items():
        ret = next(ret for f, ret in zip(tr.problem.groupoid.factors, tr.scheme.retractions)
                   if f.velocity == name)
        if ret.name == "first_order" and angle > FIRST_ORDER_RANGE:
            failures.append(f"{name} turns {angle:.3g} rad in one step, beyond the accurate "
                            f"range of the first_order rule ({FIRST_ORDER_RANGE} rad: its "
                            "read-out lets a long step turn further than it pays for): "
                            f"increase N to {suggested_N(tr.N, angle / FIRST_ORDER_RANGE, 1)}"
                            " or use the cayley retraction")
        elif angle > 0.5 * ret.step_limit:
            failures.append(f"{name} turns {angle:.3g} rad in one step (more than half of "
                            f"{ret.step_limit:.2f}, where {tr.scheme.retraction} is singular): "
                            "increase N to "
                            f"{suggested_N(tr.N, angle / (0.25 * ret.step_limit), order)}")
    return failures
