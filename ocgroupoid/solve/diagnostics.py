"""Checks of a discrete solution that do not trust the solver.

(a) The discrete (constrained) second-order Euler-Lagrange residual with the solver's
    multipliers of Phi_d (seed 000, eq. 13, 18): the gradient of ``S + sum_k lambda^k Phi_d``
    comes from CasADi's own AD of the NLP (not from the stage derivatives IPOPT used); the
    scheme turns it into the residual of its discrete equations
    (:meth:`~ocgroupoid.nlp.schemes.base.Scheme.euler_lagrange_residual`).
(b) Distance of every node state from its manifold (|R^T R - I|, ||Gamma| - 1|).
(c) Boundary residuals (each factor's distance to its target), the largest constraint
    residual, and for bounds the largest violation and where they are active.
(d) Replay (:mod:`ocgroupoid.solve.replay`): the reported controls driven through the
    continuous dynamics with SciPy, and the terminal error against the target.
"""

from __future__ import annotations

from typing import Any
from weakref import WeakKeyDictionary

import casadi as ca
import numpy as np

from ..nlp.assembly import Kind
from ..nlp.transcription import RawResult, Transcription
from . import mesh
from .replay import Replay, terminal_errors

_replays: WeakKeyDictionary[Transcription, Replay] = WeakKeyDictionary()


def replay_of(tr: Transcription) -> Replay:
    """The Replay of a transcription, built once (its dynamics and compiled integrators)."""
    if tr not in _replays:
        _replays[tr] = Replay(tr)
    return _replays[tr]


def euler_lagrange_residual(tr: Transcription, x: np.ndarray, p: np.ndarray,
                            lam_g: np.ndarray) -> np.ndarray:
    """The scheme's discrete Euler-Lagrange residuals (one row per interior node), with the
    multipliers of Phi_d and of the final conditions: the reconstruction's multipliers are
    never used (the variations keep the reconstruction satisfied)."""
    lam = np.asarray(lam_g, dtype=float).copy()
    lam[tr.rows(Kind.RECONSTRUCTION).ravel()] = 0.0
    f, g = tr.nlp["f"], tr.nlp["g"]
    ls = ca.MX.sym("lam", tr.ng)
    lagrangian = ca.Function("lagrangian", [tr.nlp["x"], tr.nlp["p"], ls], [f + ca.dot(ls, g)])
    xs, ps = ca.MX.sym("x", tr.nx), ca.MX.sym("p", tr.np)
    reconstruct = ca.Function("reconstruct", [xs, ps], [tr.readout_function(
        xs, ps, ca.MX.zeros(tr.ng))[0]])
    return tr.scheme.euler_lagrange_residual(lagrangian, reconstruct,
                                             np.asarray(x, dtype=float).ravel(), p, lam)


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


def bound_report(tr: Transcription, x: np.ndarray, p: np.ndarray) -> dict[str, Any]:
    """The largest violation of any bound and, per bound row, at how many of its points it
    is active (at its lower or upper side)."""
    rows = tr.rows(Kind.INEQUALITY)
    if not rows.size:
        return {}
    g = np.array(tr.g_fun(x, p)).ravel()
    lbg, ubg, _, _ = (np.array(v).ravel() for v in tr.bounds_function(p))
    idx = rows.ravel()
    violation = float(np.max(np.maximum(0.0, np.maximum(lbg[idx] - g[idx], g[idx] - ubg[idx]))))
    _, side = mesh.active_sides(tr, RawResult("", x, p, np.zeros(tr.ng), 0.0, "", True, 0, 0.0))
    names = tr.scheme.stages.inequality_names
    active = {}
    for name, row in zip(names, side):
        sides = {k: int(np.sum(row == v)) for k, v in (("upper", 1), ("lower", -1))}
        if any(sides.values()):
            active[name] = {k: n for k, n in sides.items() if n}
    return {"bound_violation_max": violation, "bounds_active": active,
            "bound_points": int(side.shape[1])}


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
    d.update(bound_report(tr, x, p))
    if tr.problem.invariants:
        values = conserved_values(tr, s, out["velocities"], p)
        d["conserved_drift"] = {name: float(np.max(np.abs(C - C[0])))
                                for name, C in values.items()}
    if replay and not solved:
        d["replay"] = {"available": False,
                       "reason": "not replayed: IPOPT did not solve, the controls are no answer"}
    elif replay:
        d["replay"] = replay_of(tr).run(out, ppoly, p)
    return d
