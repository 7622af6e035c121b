"""Replay: the reported controls driven through the continuous dynamics (SciPy's DOP853).

Second-order problems with mechanics integrate ``M(q, y) dy/dt = F(u) - c(q, y)`` with
``F_actuated = B u``; second-order problems whose controls are the accelerations integrate
``dy/dt = u``; first-order problems whose controls are velocities solve the constraints
``psi(q, y) = 0`` for the remaining velocities. States follow the reconstruction equations
(``dR/dt = R hat(Omega)``, ...). Any other problem has no replay. The controls are the
piecewise polynomial the scheme implies (``Solution.control_ppoly``): linear between node
samples for ``order2``, cubic (second-order problems) or linear within each interval
(first-order problems) for ``order4``. A user replays a plan the same way with
``scipy.interpolate.PPoly`` and ``solve_ivp``.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from ..nlp.transcription import Transcription


def terminal_errors(tr: Transcription, s: np.ndarray, y: np.ndarray | None, p: np.ndarray
                    ) -> dict[str, float]:
    """Errors of a final state (and velocity) against the prescribed targets: each factor's
    :meth:`~ocgroupoid.groupoid.base.Factor.terminal_error` (an angle for rotations and
    directions, a norm over the prescribed components on R^n); velocities: the norm over
    the prescribed components."""
    G, m = tr.problem.groupoid, tr.masks
    target = tr.part(p, "end")
    out: dict[str, float] = {}
    for f, ss, ts, mask in zip(G.factors, G.state_layout.slices, G.target_layout.slices,
                               m.end_state):
        if mask.any():
            out[f.state] = f.terminal_error(s[ss], f.state_of_target(target[ts]), mask)
    if y is not None and tr.problem.end_velocities:
        VT = tr.part(p, "VN")
        for f, vs in zip(G.factors, G.velocity_layout.slices):
            mask = m.end_velocity[vs]
            if mask.any():
                out[f.velocity] = float(np.linalg.norm((y[vs] - VT[vs])[mask]))
    return out


class Replay:
    """Continuous dynamics of a problem, driven by sampled controls (module docstring)."""

    def __init__(self, tr: Transcription) -> None:
        pb, G = tr.problem, tr.problem.groupoid
        self.tr = tr
        s, y, u = ca.SX.sym("s", G.state_size), ca.SX.sym("y", G.algebra_dim), \
            ca.SX.sym("u", len(pb.controls))
        q = G.base(s)
        sdot = G.state_rate(s, y)
        self.reason = ""
        self.rhs: ca.Function | None = None
        ctrl = tr.scheme.stages.controls
        if pb.order == 2 and pb.dynamics is not None:
            mech = pb.dynamics
            EL = ca.substitute(ca.substitute(mech.EL, pb.q, q), pb.y, y)
            M = ca.jacobian(EL, pb.dy)
            c = ca.substitute(EL, pb.dy, ca.DM.zeros(G.algebra_dim))
            F = ca.SX.zeros(G.algebra_dim)
            F[list(mech.actuated)] = ca.mtimes(ca.substitute(mech.input_matrix, pb.q, q), u)
            self.rhs = ca.Function("rhs", [s, y, u, pb.P], [sdot, ca.solve(M, F - c)])
        elif pb.order == 2 and ca.depends_on(ctrl, pb.dy) and ca.is_equal(ctrl, pb.dy, 2):
            self.rhs = ca.Function("rhs", [s, y, u, pb.P], [sdot, u])
        elif pb.order == 1:
            self._first_order(s, q, y, u, sdot, ctrl)
        else:
            self.reason = "no dynamics: the controls are neither mechanics nor accelerations"

    def _first_order(self, s: ca.SX, q: ca.SX, y: ca.SX, u: ca.SX, sdot: ca.SX,
                     ctrl: ca.SX) -> None:
        pb = self.tr.problem
        ctrl_idx = []
        for k in range(ctrl.numel()):
            hits = [i for i in range(pb.y.numel()) if ca.is_equal(ctrl[k], pb.y[i])]
            if not hits:
                self.reason = "first-order controls must be velocity components"
                return
            ctrl_idx.append(hits[0])
        dep = [i for i in range(pb.y.numel()) if i not in ctrl_idx]
        psi = self.tr.scheme.stages.constraints
        if psi.numel() != len(dep):
            self.reason = (f"{len(dep)} velocities are not controls but {psi.numel()} "
                           "constraints determine them")
            return
        yfull = ca.SX.zeros(pb.y.numel())
        yfull[ctrl_idx] = u
        ydep = ca.SX.sym("ydep", len(dep))
        yfull[dep] = ydep
        res = ca.substitute(ca.substitute(psi, pb.q, q), pb.y, yfull)
        J = ca.jacobian(res, ydep)
        r0 = ca.substitute(res, ydep, ca.DM.zeros(len(dep)))
        ysol = ca.substitute(yfull, ydep, -ca.solve(J, r0))  # exact for affine psi
        self.rhs = ca.Function("rhs", [s, u, pb.P], [ca.substitute(sdot, y, ysol)])

    def run(self, out: dict[str, np.ndarray], ppoly: dict[str, np.ndarray], p: np.ndarray,
            rtol: float = 1e-12, atol: float = 1e-12) -> dict[str, Any]:
        """Integrate from the read-out's initial state, piece by piece of the control
        polynomial; return the final state and its errors against the targets of p."""
        if self.rhs is None:
            return {"available": False, "reason": self.reason}
        tr = self.tr
        breaks, C = ppoly["x"], ppoly["c"]  # C: (k, pieces, m), highest power first
        P = tr.part(p, "P")
        ns = tr.problem.groupoid.state_size
        second = tr.problem.end_velocities  # the state carries the velocities too
        z = np.concatenate([out["node_states"][0], out["velocities"][0]]) if second else \
            out["node_states"][0].copy()
        rhs = self.rhs

        def f(t: float, z: np.ndarray, a: float, coeffs: np.ndarray) -> np.ndarray:
            u = coeffs[0].copy()
            for c in coeffs[1:]:  # Horner in t - a
                u = u * (t - a) + c
            if second:
                sd, yd = rhs(z[:ns], z[ns:], u, P)
                return np.concatenate([sd.full().ravel(), yd.full().ravel()])
            return rhs(z, u, P).full().ravel()

        for j in range(len(breaks) - 1):
            a, b = breaks[j], breaks[j + 1]
            sol = solve_ivp(f, (a, b), z, method="DOP853", rtol=rtol, atol=atol,
                            args=(a, C[:, j, :]))
            if not sol.success:
                return {"available": False, "reason": f"solve_ivp failed: {sol.message}"}
            z = sol.y[:, -1]
        errors = terminal_errors(tr, z[:ns], z[ns:] if second else None, p)
        return {"available": True, "terminal_error": errors,
                "max_terminal_error": max(errors.values()) if errors else 0.0}
