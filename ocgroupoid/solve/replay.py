"""Replay: the reported controls driven through the continuous dynamics.

Second-order problems with mechanics integrate ``M(q, y) dy/dt = F(u) - c(q, y)`` with
``F_actuated = B u``; second-order problems whose controls are the accelerations integrate
``dy/dt = u``; first-order problems whose controls are velocities solve the constraints
``psi(q, y) = 0`` for the remaining velocities. States follow the reconstruction equations
(``dR/dt = R hat(Omega)``, ...). Any other problem has no replay. The controls are the
piecewise polynomial the scheme implies (``Solution.control_ppoly``): linear between node
samples for ``order2``, cubic (second-order problems) or linear within each interval
(first-order problems) for ``order4``. The integrator is RK4 compiled by CasADi and mapped
over the pieces, its substeps doubled until its own error is negligible (:meth:`Replay.run`):
a few milliseconds where SciPy's ``solve_ivp`` took seconds. A user replays a plan the same
way with ``scipy.interpolate.PPoly`` and ``solve_ivp`` (tests do, and agree).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..nlp.dynamics import Dynamics, rk4
from ..nlp.transcription import Transcription

#: RK4 substeps per piece: the first pair compared, and the most ever taken
SUBSTEPS = (1, 256)
REL_TOL, ABS_TOL = 1e-3, 1e-12  # the replay's own error, against what it reports


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
        self.tr = tr
        dynamics = Dynamics(tr.problem, tr.scheme.stages)
        #: ``rhs(z, u, P) -> dz/dt``, z the node state (and the velocity, second order)
        self.rhs: ca.Function | None = dynamics.rhs
        self.reason = dynamics.reason
        self._cache: dict[tuple[int, ...], ca.Function] = {}

    def run(self, out: dict[str, np.ndarray], ppoly: dict[str, np.ndarray], p: np.ndarray
            ) -> dict[str, Any]:
        """Integrate from the read-out's initial state, piece by piece of the control
        polynomial; return the final state's errors against the targets of p.

        RK4 with M substeps per piece, compiled and mapped over the pieces, M doubled until
        two successive results agree (their difference, /15, estimates the error of the
        finer one, which is then Richardson-extrapolated) to 1e-3 of the terminal error or
        :data:`ABS_TOL`: the replay's own error is never what it reports."""
        if self.rhs is None:
            return {"available": False, "reason": self.reason}
        tr = self.tr
        breaks, C = np.asarray(ppoly["x"], dtype=float), np.asarray(ppoly["c"], dtype=float)
        k, n, m = C.shape  # (k, pieces, m), highest power first
        P = tr.part(p, "P")
        ns = tr.problem.groupoid.state_size
        second = tr.problem.end_velocities  # the state carries the velocities too
        z0 = np.concatenate([out["node_states"][0], out["velocities"][0]]) if second else \
            out["node_states"][0].copy()
        coeffs = C.transpose(0, 2, 1).reshape(k * m, n)  # column j: piece j, m fastest
        args = (z0, coeffs, np.diff(breaks)[None, :], np.repeat(P[:, None], n, axis=1))
        M = SUBSTEPS[0]
        previous = np.asarray(self._pieces(k, m, M, n)(*args))[:, -1]
        while True:
            M *= 2
            z = np.asarray(self._pieces(k, m, M, n)(*args))[:, -1]
            estimate = float(np.max(np.abs(z - previous))) / 15.0
            z = z + (z - previous) / 15.0
            if not np.all(np.isfinite(z)):
                return {"available": False, "reason": "the replayed state diverged (not finite)"}
            errors = terminal_errors(tr, z[:ns], z[ns:] if second else None, p)
            worst = max(errors.values()) if errors else 0.0
            if estimate <= max(REL_TOL * worst, ABS_TOL) or M >= SUBSTEPS[1]:
                break
            previous = z
        return {"available": True, "terminal_error": errors, "max_terminal_error": worst,
                "integration_error": estimate, "substeps": M}

    def _pieces(self, k: int, m: int, M: int, n: int) -> ca.Function:
        """``(z0, coefficients (k m x n), steps (1 x n), P) -> z`` after every piece: M RK4
        substeps per piece, the control evaluated by Horner's rule in t - t_j."""
        key = (k, m, M, n)
        if key not in self._cache:
            assert self.rhs is not None
            nz = self.rhs.size1_in(0)
            z, c, h, P = (ca.SX.sym(n, d) for n, d in (("z", nz), ("c", k * m), ("h", 1),
                                                        ("P", self.rhs.size1_in(2))))
            cm = ca.reshape(c, m, k)

            def f(zz: ca.SX, t: ca.SX) -> ca.SX:
                u = cm[:, 0]
                for j in range(1, k):
                    u = u * t + cm[:, j]
                return self.rhs(zz, u, P)

            dt, zz = h / M, z
            for i in range(M):
                zz = rk4(lambda x, s, t=i * dt: f(x, t + s * dt), zz, dt)
            piece = ca.Function("piece", [z, c, h, P], [zz])
            self._cache[key] = piece.mapaccum(n)
        return self._cache[key]
