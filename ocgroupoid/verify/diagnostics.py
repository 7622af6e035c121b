"""Checks of a discrete solution that do not trust the solver.

(a) The discrete (constrained) second-order Euler-Lagrange residual with the solver's
    multipliers of Phi_d (seed 000, eq. 13, 18): the gradient of ``S + sum_k lambda^k Phi_d``
    comes from CasADi's own AD of the NLP (not from the stage derivatives IPOPT used); the
    scheme turns it into the residual of its discrete equations
    (:meth:`~ocgroupoid.nlp.schemes.base.Scheme.euler_lagrange_residual`).
(b) Distance of every node state from its manifold (|R^T R - I|, ||Gamma| - 1|).
(c) Boundary residuals (each factor's distance to its target), the largest constraint
    residual, and for bounds the largest violation and where they are active.
(d) Replay (:mod:`ocgroupoid.verify.replay`): the plan driven through the continuous problem;
    the terminal error against the target, the largest violation of every bound along it
    (on a dense grid: the violation a Solution reports), and the cost recomputed along it.
(e) An a-posteriori estimate of the cost's error (:func:`estimate`): what the replay's miss
    and bound violations are worth by the solver's multipliers (the sensitivities of the
    optimal cost to the final values and the bounds), plus the difference between the
    reported cost and the one recomputed along the replay.
"""

from __future__ import annotations

from typing import Any, Callable

import casadi as ca
import numpy as np

from ..nlp import mesh
from ..nlp.assembly import Kind
from ..nlp.transcription import RawResult, Transcription
from .once import per_transcription
from .replay import Replay, terminal_errors


@per_transcription
def replay_of(tr: Transcription) -> Replay:
    """The Replay of a transcription, built once (its dynamics and compiled integrators)."""
    return Replay(tr)


@per_transcription
def _euler_lagrange(tr: Transcription) -> Callable[[np.ndarray, np.ndarray, np.ndarray],
                                                   np.ndarray]:
    """The scheme's residual map (:meth:`Scheme.euler_lagrange`) of the NLP's Lagrangian."""
    f, g = tr.nlp["f"], tr.nlp["g"]
    ls = ca.MX.sym("lam", tr.ng)
    lagrangian = ca.Function("lagrangian", [tr.nlp["x"], tr.nlp["p"], ls], [f + ca.dot(ls, g)])
    xs, ps = ca.MX.sym("x", tr.nx), ca.MX.sym("p", tr.np)
    reconstruct = ca.Function("reconstruct", [xs, ps], [tr.readout_function(
        xs, ps, ca.MX.zeros(tr.ng))[0]])
    return tr.scheme.euler_lagrange(lagrangian, reconstruct)


def euler_lagrange_residual(tr: Transcription, x: np.ndarray, p: np.ndarray,
                            lam_g: np.ndarray) -> np.ndarray:
    """The scheme's discrete Euler-Lagrange residuals (one row per interior node), with the
    multipliers of Phi_d and of the final conditions: the reconstruction's multipliers are
    never used (the variations keep the reconstruction satisfied). The scheme's map
    (:meth:`Scheme.euler_lagrange`) is built once per transcription: its symbolic gradient
    took 5 of the 36 ms of a cart-pole solve at N = 16."""
    lam = np.asarray(lam_g, dtype=float).copy()
    lam[tr.rows(Kind.RECONSTRUCTION).ravel()] = 0.0
    return _euler_lagrange(tr)(np.asarray(x, dtype=float).ravel(),
                               np.asarray(p, dtype=float).ravel(), lam)


def conserved_values(tr: Transcription, states: np.ndarray, velocities: np.ndarray,
                     p: np.ndarray) -> dict[str, np.ndarray]:
    """Every declared conserved quantity C(q, y) at the nodes, from the node states and the
    read-out's node velocities (second-order problems, where quantities are declared
    conserved, sample velocities at the nodes): its drift is the discretisation's."""
    pb, G = tr.problem, tr.problem.groupoid
    P = tr.part(p, "P")
    s = ca.SX.sym("s", G.state_size)
    out = {}
    for name, C in pb.invariants:
        fun = ca.Function("C", [s, pb.y, pb.P], [ca.substitute(C, pb.q, G.base(s))])
        out[name] = np.array(fun.map(len(velocities))(states.T, velocities.T, P)).T
    return out


def manifold_distance(tr: Transcription, states: np.ndarray) -> dict[str, float]:
    """Largest distance of the node states from each factor's manifold."""
    G = tr.problem.groupoid
    return {f.state: float(np.max(f.distances(states[:, ss])))
            for f, ss in zip(G.factors, G.state_layout.slices)}


def step_sizes(tr: Transcription, steps: np.ndarray) -> dict[str, float]:
    """Largest rotation angle of one step (``Retraction.step_norm``: |a_k|, |omega_k| on
    SE(n)) of every velocity whose retraction has a singular step (Cayley at pi, the
    first-order rule at pi/2): how close a grid comes to it."""
    G = tr.problem.groupoid
    if not tr.scheme.variational:  # a baseline steps by RK4, not by a retraction
        return {}
    return {f.velocity: float(np.max(ret.step_norm(steps[:, vs])))
            for f, ret, vs in zip(G.factors, tr.scheme.retractions, G.velocity_layout.slices)
            if np.isfinite(ret.step_limit)}


def bound_report(tr: Transcription, x: np.ndarray, p: np.ndarray, g: np.ndarray | None = None
                 ) -> dict[str, Any]:
    """The largest violation of any bound and, per bound row, at how many of its points it
    is active (at its lower or upper side). ``g``: the NLP's rows at (x, p), where the caller
    has them."""
    rows = tr.rows(Kind.INEQUALITY)
    if not rows.size:
        return {}
    rows_at = mesh.rows_of(tr, x, p, g)
    g, lbg, ubg = rows_at
    idx = rows.ravel()
    violation = float(np.max(np.maximum(0.0, np.maximum(lbg[idx] - g[idx], g[idx] - ubg[idx]))))
    _, side = mesh.active_sides(tr, RawResult("", x, p, np.zeros(tr.ng), 0.0, "", True, 0, 0.0),
                                rows_at)
    names = tr.scheme.stages.inequality_names
    active = {}
    for name, row in zip(names, side):
        sides = {k: int(np.sum(row == v)) for k, v in (("upper", 1), ("lower", -1))}
        if any(sides.values()):
            active[name] = {k: n for k, n in sides.items() if n}
    return {"bound_violation_max": violation, "bound_violation_points": violation,
            "bounds_active": active, "bound_points": int(side.shape[1])}


def diagnose(tr: Transcription, x: np.ndarray, p: np.ndarray, lam_g: np.ndarray,
             out: dict[str, np.ndarray], ppoly: dict[str, np.ndarray], replay: bool = True,
             solved: bool = True) -> dict[str, Any]:
    """All checks (a)-(d) as a JSON-friendly dict, for the read-out ``out`` of (x, p, lam_g)
    and its control polynomial ``ppoly``.
    The replay runs for solved points only: the controls of a failed solve can be huge or
    NaN, and integrating them can take hours."""
    g = np.array(tr.g_fun(x, p)).ravel()
    path = tr.rows(Kind.PATH).ravel()
    s = out["node_states"]
    d: dict[str, Any] = {}
    if tr.scheme.variational:  # a baseline has no discrete Euler-Lagrange equations
        r = euler_lagrange_residual(tr, x, p, lam_g)
        d["euler_lagrange_residual_max"] = float(np.max(np.abs(r))) if r.size else 0.0
        d["euler_lagrange_residual_per_node"] = np.max(np.abs(r), axis=1).tolist() \
            if r.size else []
    d |= {
        "manifold_distance": manifold_distance(tr, s),
        "final_residual": terminal_errors(tr, s[-1], None, p),
        "reconstruction_residual_max": float(np.max(np.abs(
            g[tr.rows(Kind.RECONSTRUCTION).ravel()]))),
        "constraint_residual_max": float(np.max(np.abs(g[path]))) if path.size else 0.0,
        "step_angle_max": step_sizes(tr, out["steps"]),
    }
    d.update(bound_report(tr, x, p, g))
    if tr.problem.invariants:
        values = conserved_values(tr, s, out["velocities"], p)
        d["conserved_drift"] = {name: float(np.max(np.abs(C - C[0])))
                                for name, C in values.items()}
    if replay and not solved:
        d["replay"] = {"available": False,
                       "reason": "not replayed: IPOPT did not solve, the controls are no answer"}
    elif replay:
        rep = d["replay"] = replay_of(tr).run(out, ppoly, p)
        if rep.get("available") and "bound_violation" in rep:  # the dense one is reported
            d["bound_violation"] = rep["bound_violation"]
            d["bound_violation_max"] = max(d["bound_violation_max"], rep["bound_violation_max"])
        if rep.get("available"):
            d["estimate"] = estimate(tr, x, p, lam_g, rep)
    return d


def estimate(tr: Transcription, x: np.ndarray, p: np.ndarray, lam_g: np.ndarray,
             rep: dict[str, Any]) -> dict[str, Any]:
    """An a-posteriori error estimate of the cost (and of a free T) from the replay (e):

    * ``landing``: ``|lambda_final . chart(replayed final state)| + |dL/dV_N . (replayed final
      velocity - V_N)|``, the change of the optimal cost if the targets were where the plan
      lands (first-order sensitivity: the multipliers of the final rows, the gradient of the
      Lagrangian in the prescribed final velocities);
    * ``bounds``: ``sum over bounds of (sum |mu| over its rows) * its largest violation
      along the replay``, what relaxing each bound that far is worth;
    * ``replay_cost``: the reported cost against the one recomputed along the replay.

    The plan is a feasible point of the continuous problem up to its miss and violations, so
    the optimum lies no further above the reported cost than these, to first order: a T
    below the true minimum by more than ``T`` is a contradiction the verdict catches."""
    pb, G, lay = tr.problem, tr.problem.groupoid, tr.layout
    ns = G.state_size
    z = np.asarray(rep["final_state"], dtype=float)
    s, y = z[:ns], z[ns:]
    lam = np.asarray(lam_g, dtype=float)
    landing = 0.0
    final = tr.rows(Kind.FINAL).ravel()
    if final.size:
        keep = np.concatenate(tr.masks.end_state)
        chart = np.array(tr.scheme.stages.chart(s, tr.part(p, "end"))).ravel()[keep]
        landing += abs(float(lam[final] @ chart))
    if pb.end_velocities and y.size and tr.masks.end_velocity.any():
        grad = _lagrangian_gradient_p(tr, x, p, lam)[lay.p_slices["VN"]]
        miss = (y - tr.part(p, "VN")) * tr.masks.end_velocity
        landing += abs(float(grad @ miss))
    bounds = 0.0
    rows = tr.rows(Kind.INEQUALITY)
    if rows.size and rep.get("bound_violation"):
        names = tr.scheme.stages.inequality_names
        per_row = np.abs(lam[rows]).sum(axis=1)  # one row per bound component
        bounds = float(sum(per_row[i] * rep["bound_violation"].get(n, 0.0)
                           for i, n in enumerate(names)))
    T = tr.horizon(x, p)
    J_replay = rep["running_cost"] + pb.weights["time"] * T  # the effort weight is in it
    if pb.terminal is not None:
        J_replay += _terminal(tr, s, y, p)
    J = float(tr.f_fun(x, p))
    out = {"cost": landing + bounds + abs(J - J_replay), "landing": landing, "bounds": bounds,
           "replay_cost": J_replay, "reported_cost": J}
    if pb.T_free and pb.weights["time"] > 0:
        out["T"] = out["cost"] / pb.weights["time"]
    return out


@per_transcription
def _gradient_p(tr: Transcription) -> ca.Function:
    """``(x, p, lam) -> d/dp (f + lam . g)``: built once (the symbolic gradient took 2.4 ms
    of every so3 solve at N = 256)."""
    ps, ls = ca.MX.sym("p", tr.np), ca.MX.sym("lam", tr.ng)
    fx = ca.substitute([tr.nlp["f"] + ca.dot(ls, tr.nlp["g"])], [tr.nlp["p"]], [ps])[0]
    return ca.Function("dL_dp", [tr.nlp["x"], ps, ls], [ca.gradient(fx, ps)])


def _lagrangian_gradient_p(tr: Transcription, x: np.ndarray, p: np.ndarray,
                           lam: np.ndarray) -> np.ndarray:
    """``d/dp (f + lam . g)`` at (x, p): the sensitivity of the optimal cost to p."""
    return np.array(_gradient_p(tr)(x, p, lam)).ravel()


def _terminal(tr: Transcription, s: np.ndarray, y: np.ndarray, p: np.ndarray) -> float:
    """The terminal cost at a final state (and velocity)."""
    pb, G = tr.problem, tr.problem.groupoid
    assert pb.terminal is not None
    yy = y if y.size else np.zeros(G.algebra_dim)
    f = ca.Function("terminal", [pb.s, pb.y, pb.P], [ca.substitute(
        pb.terminal, pb.q, G.base(pb.s))])
    return float(f(s, yy, tr.part(p, "P")))
