"""An independent quadrotor solver: plain CasADi Opti, quaternion Newton-Euler, Hermite-Simpson.

Nothing of ocgroupoid is used but the numbers of an instance: the state is the unit
quaternion q, the position p, the body angular velocity w and the body velocity v; the
dynamics are typed in (Lee, Leok & McClamroch 2010, body frame)

    dq/dt = 1/2 q (0, w),   dp/dt = R(q) v,
    J dw/dt = tau - w x J w,   m dv/dt = f e3 - m gravity R(q)^T e3 - m w x v,

and the optimal control problem is transcribed by the three-stage Gauss-Legendre Runge-Kutta
method (implicit stages, a control at every stage, the cost by the same Gauss quadrature):
sixth order for smooth solutions (Gauss methods keep their order in optimal control, Hager
2000; Hermite-Simpson with controls at the nodes does not: its end controls drift and its
cost converged at first order here), so that two grids extrapolate the cost. It starts from
a given trajectory (ours), to land on the same minimum.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np


@dataclass
class Instance:
    m: float
    J: np.ndarray
    gravity: float
    f_max: float
    tau_max: float
    q_T: np.ndarray  # target quaternion (w, x, y, z)
    p_T: np.ndarray
    T: float | None  # None: minimum time
    T_range: tuple[float, float] = (0.5, 10.0)
    effort: float = 1.0


def _quat_mul(a: Any, b: Any) -> Any:
    aw, av, bw, bv = a[0], a[1:], b[0], b[1:]
    return ca.vertcat(aw * bw - ca.dot(av, bv), aw * bv + bw * av + ca.cross(av, bv))


def _rotation(q: Any) -> Any:
    w, x, y, z = q[0], q[1], q[2], q[3]
    return ca.vertcat(
        ca.horzcat(1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        ca.horzcat(2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        ca.horzcat(2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)))


def rhs(inst: Instance) -> ca.Function:
    """(x, u) -> dx/dt, x = (q, p, w, v), u = (f, tau)."""
    x, u = ca.SX.sym("x", 13), ca.SX.sym("u", 4)
    q, w, v = x[:4], x[7:10], x[10:13]
    R = _rotation(q)
    J = ca.DM(inst.J)
    e3 = ca.DM([0, 0, 1])
    dq = 0.5 * _quat_mul(q, ca.vertcat(0, w))
    dp = ca.mtimes(R, v)
    dw = (u[1:] - ca.cross(w, J * w)) / J
    dv = u[0] / inst.m * e3 - inst.gravity * ca.mtimes(R.T, e3) - ca.cross(w, v)
    return ca.Function("rhs", [x, u], [ca.vertcat(dq, dp, dw, dv)])


#: the three-stage Gauss-Legendre method: nodes c, matrix A, weights b
_S15 = float(np.sqrt(15.0))
C = np.array([0.5 - _S15 / 10, 0.5, 0.5 + _S15 / 10])
A = np.array([[5 / 36, 2 / 9 - _S15 / 15, 5 / 36 - _S15 / 30],
              [5 / 36 + _S15 / 24, 2 / 9, 5 / 36 - _S15 / 24],
              [5 / 36 + _S15 / 30, 2 / 9 + _S15 / 15, 5 / 36]])
B = np.array([5 / 18, 4 / 9, 5 / 18])


def points(N: int, T: float) -> np.ndarray:
    """The times of the guesses: the N+1 nodes, then the 3N stages (interval by interval)."""
    nodes = np.linspace(0, T, N + 1)
    return np.concatenate([nodes, ((np.arange(N)[:, None] + C[None, :]) * T / N).ravel()])


def solve(inst: Instance, N: int, x_guess: np.ndarray, u_guess: np.ndarray,
          T_guess: float) -> dict[str, Any]:
    """Gauss-Legendre collocation on N intervals; guesses at :func:`points` (rows)."""
    f = rhs(inst)
    u = ca.SX.sym("u", 4)
    L = ca.Function("L", [u], [inst.effort * ((u[0] - inst.m * inst.gravity) ** 2
                                              + ca.sumsqr(u[1:]))])
    opti = ca.Opti()
    X = opti.variable(13, N + 1)  # node states
    Z = opti.variable(13, 3 * N)  # stage states
    U = opti.variable(4, 3 * N)  # stage controls
    T = opti.variable() if inst.T is None else inst.T
    h = T / N
    cost = 0
    for k in range(N):
        s = slice(3 * k, 3 * k + 3)
        F = [f(Z[:, 3 * k + j], U[:, 3 * k + j]) for j in range(3)]
        for i in range(3):
            opti.subject_to(Z[:, 3 * k + i] == X[:, k] + h * sum(A[i, j] * F[j]
                                                                  for j in range(3)))
        opti.subject_to(X[:, k + 1] == X[:, k] + h * sum(B[j] * F[j] for j in range(3)))
        cost += h * sum(B[j] * L(U[:, s][:, j]) for j in range(3))
    rest = np.zeros(6)
    opti.subject_to(X[:, 0] == np.concatenate([[1, 0, 0, 0], [0, 0, 0], rest]))
    opti.subject_to(X[:, -1] == np.concatenate([inst.q_T, inst.p_T, rest]))
    opti.subject_to(opti.bounded(0, U[0, :], inst.f_max))
    opti.subject_to(opti.bounded(-inst.tau_max, U[1:, :], inst.tau_max))
    if inst.T is None:
        opti.subject_to(opti.bounded(inst.T_range[0], T, inst.T_range[1]))
        opti.set_initial(T, T_guess)
        cost += T
    opti.minimize(cost)
    opti.set_initial(X, x_guess[:N + 1].T)
    opti.set_initial(Z, x_guess[N + 1:].T)
    opti.set_initial(U, u_guess[N + 1:].T)
    # converged to tol, never stopped at IPOPT's "acceptable" level: from a start 4e-11 away
    # (our solution with another scaling of our NLP) it once stopped there 0.6 % above the
    # minimum. The adaptive barrier: with the monotone one (mu from 0.1) the start's
    # bang-bang arcs are first pushed off their bounds, and from our minimum-time solution at
    # N = 128 it then crawled to its iteration limit (3000); adaptive converges from it in 158
    # iterations (from the solution of our earlier control variables in 117, monotone 80)
    opti.solver("ipopt", {"print_time": False},
                {"print_level": 0, "sb": "yes", "tol": 1e-10, "max_iter": 3000,
                 "bound_relax_factor": 0.0, "acceptable_iter": 0, "mu_strategy": "adaptive"})
    sol = opti.solve()
    return {"cost": float(sol.value(opti.f)), "T": float(sol.value(T)),
            "status": opti.stats()["return_status"], "X": np.array(sol.value(X)).T,
            "U": np.array(sol.value(U)).reshape(4, -1).T}


def guess_from(solution: Any, N: int) -> tuple[np.ndarray, np.ndarray, float]:
    """States and controls of one of our Solutions (a quadrotor) at :func:`points`: the pose
    from its node states, the twist and the controls interpolated."""
    T = solution.T
    t = points(N, T)
    g = solution.states["g"]
    quats = []
    for G in g:
        R = G[:3, :3]
        w = np.sqrt(max(1 + np.trace(R), 1e-12)) / 2
        quats.append([w, (R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w),
                      (R[1, 0] - R[0, 1]) / (4 * w)])
    quats = np.array(quats)
    for i in range(1, len(quats)):  # one hemisphere along the path
        if quats[i] @ quats[i - 1] < 0:
            quats[i] = -quats[i]
    node_t = solution.t
    interp = lambda tt, A: np.column_stack([np.interp(t, tt, A[:, j])  # noqa: E731
                                            for j in range(A.shape[1])])
    Q = interp(node_t, quats)
    Q /= np.linalg.norm(Q, axis=1)[:, None]
    P = interp(node_t, g[:, :3, 3])
    V = interp(solution.velocity_t, solution.velocities["xi"])
    U = np.column_stack([solution.control(t)])
    return np.hstack([Q, P, V]), U, T
