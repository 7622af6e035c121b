"""Checks of a discrete solution that do not trust the solver.

(a) The discrete (constrained) second-order Euler-Lagrange residual at every interior node:
    the derivative of the action sum plus multiplier terms, ``S + sum_k lambda^k Phi_d``,
    along the admissible variation ``w_{j-1} -> w_{j-1} exp(t eta)``,
    ``w_j -> exp(-t eta) w_j`` (seed 000, eq. 11, 13, 18). The gradient comes from CasADi's
    own AD of the NLP (not from the stage derivatives IPOPT used), the variation from the
    retractions' ``dtau_inv`` formulas; the reconstruction constraints are invariant under
    it, so only Phi's multipliers enter.
(b) Distance of every node state from its manifold (|R^T R - I|, ||Gamma| - 1|).
(c) Boundary residuals in the factors' charts, and the largest constraint residual.
(d) Replay: the reported controls, linearly interpolated, integrated through the continuous
    dynamics with SciPy's DOP853, and the terminal error against the target.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from .groupoid.lie_group import LieGroupFactor
from .groupoid.pair import Pair
from .lie import so3

if TYPE_CHECKING:
    from .transcribe import Transcription


def node_controls(tr: "Transcription", x: np.ndarray, p: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Control samples and their times: nodes t_k (order 2) or midpoints (order 1).

    For order 1 the midpoint samples are extended linearly to t = 0 and t = T so that a
    linear interpolation covers the whole horizon at second order.
    """
    d = tr.unpack(x, p)
    N, T, h = tr.N, d["T"], d["T"] / tr.N
    XI = d["xi"].T
    if tr.problem.order == 2:
        prev = np.hstack([(2 * d["V0"] - XI[:, 0])[:, None], XI])
        nxt = np.hstack([XI, (2 * d["VN"] - XI[:, -1])[:, None]])
        u = np.array(tr.stages.node.map(N + 1)(d["s"].T, prev, nxt, T, d["P"])[2]).T
        return np.linspace(0.0, T, N + 1), u
    u = np.array(tr.stages.node.map(N)(d["s"][:-1].T, XI, T, d["P"])[2]).T
    t_mid = (np.arange(N) + 0.5) * h
    if u.shape[1] == 0:
        return t_mid, u
    u0 = u[0] - (u[1] - u[0]) / 2
    uT = u[-1] + (u[-1] - u[-2]) / 2
    return np.concatenate([[0.0], t_mid, [T]]), np.vstack([u0, u, uT])


def node_velocities(tr: "Transcription", x: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Velocities at the nodes (order 2: V_0, midpoint averages, V_N) or intervals (order 1)."""
    d = tr.unpack(x, p)
    if tr.problem.order == 1:
        return d["xi"]
    mid = (d["xi"][1:] + d["xi"][:-1]) / 2
    return np.vstack([d["V0"], mid, d["VN"]])


def euler_lagrange_residual(tr: "Transcription", x: np.ndarray, p: np.ndarray,
                            lam_g: np.ndarray) -> np.ndarray:
    """(N-1) x dim(y) residuals of eq. 13/18 at the interior nodes j = 1..N-1."""
    G = tr.problem.groupoid
    lam = np.zeros(tr.ng)
    rows = tr.phi_rows()
    lam[rows.ravel()] = lam_g[rows.ravel()]
    xs, ps, ls = ca.MX.sym("x", tr.nx), ca.MX.sym("p", tr.np), ca.MX.sym("lam", tr.ng)
    f, g = tr.nlp["f"], tr.nlp["g"]
    ext = ca.substitute([f + ca.dot(ls, g)], [tr.nlp["x"], tr.nlp["p"]], [xs, ps])[0]
    grad = np.array(ca.Function("grad", [xs, ps, ls], [ca.gradient(ext, xs)])(x, p, lam)).ravel()
    # variation matrices per node, from the retractions
    dg, ds = G.algebra_dim, G.state_size
    xp, xn, s, T = ca.SX.sym("xp", dg), ca.SX.sym("xn", dg), ca.SX.sym("s", ds), ca.SX.sym("T")
    h = T / tr.N
    Dp, Dn, Ds = ca.SX.zeros(dg, dg), ca.SX.zeros(dg, dg), ca.SX.zeros(ds, dg)
    for f_, r, vs, ss in zip(G.factors, tr.stages.retractions, G.velocity_layout.slices,
                             G.state_layout.slices):
        for a in range(f_.algebra_dim):
            eta = ca.SX.zeros(f_.algebra_dim)
            eta[a] = 1.0
            dprev, dnext = f_.dxi(r, h, xp[vs], xn[vs], eta)
            Dp[vs, vs.start + a] = dprev
            Dn[vs, vs.start + a] = dnext
            Ds[ss, vs.start + a] = f_.variation(s[ss], eta)
    var = ca.Function("variation", [xp, xn, s, T], [Dp, Dn, Ds])
    d = tr.unpack(x, p)
    N = tr.N
    Dps, Dns, Dss = var.map(N - 1)(d["xi"][:-1].T, d["xi"][1:].T, d["s"][1:N].T, d["T"])
    # mapped outputs are [D_1 | D_2 | ...]; as (rows, dim y, node) arrays:
    Dps, Dns, Dss = (np.array(M).reshape(M.shape[0], dg, N - 1, order="F")
                     for M in (Dps, Dns, Dss))
    g_prev = grad[tr.iw_xi[:, :-1]]
    g_next = grad[tr.iw_xi[:, 1:]]
    g_s = grad[tr.iw_s[:, 1:N]]
    return (np.einsum("abj,aj->jb", Dps, g_prev) + np.einsum("abj,aj->jb", Dns, g_next)
            + np.einsum("abj,aj->jb", Dss, g_s))


def conserved_values(tr: "Transcription", x: np.ndarray, p: np.ndarray
                     ) -> dict[str, np.ndarray]:
    """Every declared conserved quantity C(q_k, y_k) at the nodes (node velocities as in
    :func:`node_velocities`): its drift is the discretisation's, the dynamics keep C fixed."""
    pb, G = tr.problem, tr.problem.groupoid
    d = tr.unpack(x, p)
    y = node_velocities(tr, x, p)
    s = ca.SX.sym("s", G.state_size)
    out = {}
    for name, C in pb.invariants:
        fun = ca.Function("C", [s, pb.y, pb.P], [ca.substitute(C, pb.q, G.base(s))])
        out[name] = np.array(fun.map(len(y))(d["s"].T, y.T, d["P"])).T
    return out


def manifold_distance(tr: "Transcription", states: np.ndarray) -> dict[str, float]:
    """Largest distance of the node states from each factor's manifold."""
    G = tr.problem.groupoid
    return {f.state: max(f.distance(row[ss]) for row in states)
            for f, ss in zip(G.factors, G.state_layout.slices)}


def step_angles(tr: "Transcription", xi: np.ndarray, T: float) -> dict[str, float]:
    """Largest rotation per step |h xi| of every SO(3) velocity (Cayley is singular at pi)."""
    G = tr.problem.groupoid
    return {f.velocity: float(np.max(np.linalg.norm(xi[:, vs], axis=1)) * T / tr.N)
            for f, vs in zip(G.factors, G.velocity_layout.slices) if f.group.dim == 3
            and not isinstance(f, Pair)}


def terminal_errors(tr: "Transcription", s: np.ndarray, y: np.ndarray | None, p: np.ndarray
                    ) -> dict[str, float]:
    """Errors of a final state (and velocity) against the prescribed targets.

    Rotations: the angle of R_T^T R in radians; points of S^2: the angle to the target;
    R^n and velocities: the Euclidean norm over the prescribed components.
    """
    G, m = tr.problem.groupoid, tr.masks
    target = p[tr.p_layout["end"]]
    out: dict[str, float] = {}
    for f, ss, ts, mask in zip(G.factors, G.state_layout.slices, G.target_layout.slices,
                               m.end_state):
        if not mask.any():
            continue
        goal = f.state_of_target(target[ts])
        if isinstance(f, LieGroupFactor):
            out[f.state] = float(np.linalg.norm(so3.log(f.matrix(goal).T @ _project(f.matrix(s[ss])))))
        elif isinstance(f, Pair):
            out[f.state] = float(np.linalg.norm((s[ss] - goal)[mask]))
        else:
            v = s[ss] / np.linalg.norm(s[ss])
            out[f.state] = float(np.arctan2(np.linalg.norm(np.cross(v, goal)), np.dot(v, goal)))
    if y is not None and tr.problem.order == 2:
        VT = p[tr.p_layout["VN"]]
        for f, vs in zip(G.factors, G.velocity_layout.slices):
            mask = m.end_velocity[vs]
            if mask.any():
                out[f.velocity] = float(np.linalg.norm((y[vs] - VT[vs])[mask]))
    return out


def _project(M: np.ndarray) -> np.ndarray:
    u, _, vt = np.linalg.svd(M)
    return u @ vt


class Replay:
    """Continuous dynamics of a problem, driven by sampled controls (linear interpolation).

    Second-order problems with mechanics integrate ``M(q, y) dy/dt = F(u) - c(q, y)`` with
    ``F_actuated = B u``; second-order problems whose controls are the accelerations integrate
    ``dy/dt = u``; first-order problems whose controls are velocities solve the constraints
    ``psi(q, y) = 0`` for the remaining velocities. States follow the reconstruction
    equations (``dR/dt = R hat(Omega)``, ...). Any other problem has no replay.
    """

    def __init__(self, tr: "Transcription") -> None:
        pb, G = tr.problem, tr.problem.groupoid
        self.tr = tr
        s, y, u = ca.SX.sym("s", G.state_size), ca.SX.sym("y", G.algebra_dim), \
            ca.SX.sym("u", len(pb.controls))
        q = G.base(s)
        sdot = ca.vertcat(*[f.state_rate(s[ss], y[vs]) for f, ss, vs in
                            zip(G.factors, G.state_layout.slices, G.velocity_layout.slices)])
        self.reason = ""
        self.rhs: ca.Function | None = None
        self.velocity: ca.Function | None = None
        ctrl = ca.vertcat(*[c for _, c in pb.controls]) if pb.controls else ca.SX(0, 1)
        if pb.order == 2 and pb.dynamics is not None:
            mech = pb.dynamics
            EL = ca.substitute(mech.EL, pb.q, q)
            EL = ca.substitute(EL, pb.y, y)
            M = ca.jacobian(EL, pb.dy)
            c = ca.substitute(EL, pb.dy, ca.DM.zeros(G.algebra_dim))
            F = ca.SX.zeros(G.algebra_dim)
            F[list(mech.actuated)] = ca.mtimes(ca.substitute(mech.input_matrix, pb.q, q), u)
            ydot = ca.solve(M, F - c)
            self.rhs = ca.Function("rhs", [s, y, u, pb.P], [sdot, ydot])
        elif pb.order == 2 and ca.depends_on(ctrl, pb.dy) and \
                ca.is_equal(ctrl, pb.dy, 2):
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
        psi = ca.vertcat(*[c for _, c in pb.constraints]) if pb.constraints else ca.SX(0, 1)
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
        self.velocity = ca.Function("velocity", [s, u, pb.P], [ysol])
        sd = ca.substitute(sdot, y, ysol)
        self.rhs = ca.Function("rhs", [s, u, pb.P], [sd])

    def run(self, x: np.ndarray, p: np.ndarray, rtol: float = 1e-12, atol: float = 1e-12
            ) -> dict[str, Any]:
        """Integrate interval by interval; return the final state and errors."""
        if self.rhs is None:
            return {"available": False, "reason": self.reason}
        tr = self.tr
        d = tr.unpack(x, p)
        t_u, U = node_controls(tr, x, p)
        P = d["P"]
        s0 = d["s"][0]
        G = tr.problem.groupoid
        ns = G.state_size
        if tr.problem.order == 2:
            z = np.concatenate([s0, d["V0"]])

            def f(t: float, z: np.ndarray, a: float, b: float, ua: np.ndarray, ub: np.ndarray
                  ) -> np.ndarray:
                u = ua + (t - a) / (b - a) * (ub - ua)
                sd, yd = self.rhs(z[:ns], z[ns:], u, P)
                return np.concatenate([sd.full().ravel(), yd.full().ravel()])
        else:
            z = s0.copy()

            def f(t: float, z: np.ndarray, a: float, b: float, ua: np.ndarray, ub: np.ndarray
                  ) -> np.ndarray:
                u = ua + (t - a) / (b - a) * (ub - ua)
                return self.rhs(z, u, P).full().ravel()
        for k in range(len(t_u) - 1):
            a, b = t_u[k], t_u[k + 1]
            sol = solve_ivp(f, (a, b), z, method="DOP853", rtol=rtol, atol=atol,
                            args=(a, b, U[k], U[k + 1]))
            if not sol.success:
                return {"available": False, "reason": f"solve_ivp failed: {sol.message}"}
            z = sol.y[:, -1]
        sT = z[:ns]
        yT = z[ns:] if tr.problem.order == 2 else None
        errors = terminal_errors(tr, sT, yT, p)
        return {"available": True, "terminal_error": errors,
                "max_terminal_error": max(errors.values()) if errors else 0.0}


def diagnose(tr: "Transcription", x: np.ndarray, p: np.ndarray, lam_g: np.ndarray,
             replay: bool = True, solved: bool = True) -> dict[str, Any]:
    """All checks (a)-(d) as a JSON-friendly dict. The replay runs for solved points only:
    the controls of a failed solve can be huge or NaN, and integrating them can take hours."""
    d = tr.unpack(x, p)
    g = np.array(tr.g_fun(x, p)).ravel()
    r = euler_lagrange_residual(tr, x, p, lam_g)
    out: dict[str, Any] = {
        "euler_lagrange_residual_max": float(np.max(np.abs(r))) if r.size else 0.0,
        "euler_lagrange_residual_per_node": np.max(np.abs(r), axis=1).tolist() if r.size else [],
        "manifold_distance": manifold_distance(tr, d["s"]),
        "final_residual": terminal_errors(tr, d["s"][-1], None, p),
        "reconstruction_residual_max": float(np.max(np.abs(g[tr.rows("recon").ravel()]))),
        "constraint_residual_max": float(np.max(np.abs(g[tr.phi_rows().ravel()])))
        if tr.phi_rows().size else 0.0,
        "step_angle_max": step_angles(tr, d["xi"], d["T"]),
    }
    if tr.problem.invariants:
        out["conserved_drift"] = {name: float(np.max(np.abs(C - C[0])))
                                  for name, C in conserved_values(tr, x, p).items()}
    if replay and not solved:
        out["replay"] = {"available": False,
                         "reason": "not replayed: IPOPT did not solve, the controls are no answer"}
    elif replay:
        out["replay"] = Replay(tr).run(x, p)
    return out
