"""RK4 multiple shooting on unit quaternions, written as a rockit/Opti user would: the
baseline our schemes are measured against (not part of the package; rockit is not needed).

One RK4 step per interval, piecewise-constant controls, the cost ``h sum |u_k|^2 / 2``,
IPOPT with our options (tol 1e-10). The final attitude is imposed by the vector part of the
relative quaternion (three equations). Replay: the piecewise-constant controls through the
continuous dynamics with DOP853 at tight tolerances, as for our schemes.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from ocgroupoid.lie import so3

IPOPT = {"ipopt.tol": 1e-10, "ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": False,
         "ipopt.max_iter": 500}


def quaternion(R: np.ndarray) -> np.ndarray:
    """A problem file's rotation (a matrix, or a quaternion from a custom model)."""
    R = np.asarray(R, dtype=float)
    return so3.to_quaternion(R) if R.shape == (3, 3) else R / np.linalg.norm(R)


def quat_mult(p: ca.SX, q: ca.SX) -> ca.SX:
    return ca.vertcat(p[0] * q[0] - ca.dot(p[1:], q[1:]),
                      p[0] * q[1:] + q[0] * p[1:] + ca.cross(p[1:], q[1:]))


@dataclass
class Shooting:
    """A built RK4 shooting NLP and how to read and replay its solution."""

    N: int
    T: float
    nx: int  # states per node
    nu: int
    solver: ca.Function
    p: np.ndarray
    x0: np.ndarray
    f: ca.Function  # continuous dynamics f(x, u)
    terminal_error: Callable[[np.ndarray], float]  # of a final state

    def solve(self) -> dict:
        t0 = time.perf_counter()
        r = self.solver(x0=self.x0, p=self.p, lbg=0, ubg=0)
        seconds = time.perf_counter() - t0
        st = self.solver.stats()
        w = np.array(r["x"]).ravel()
        U = w[self.nx * (self.N + 1):].reshape(self.N, self.nu)
        return {"cost": float(r["f"]), "seconds": seconds, "iterations": int(st["iter_count"]),
                "status": str(st["return_status"]), "success": bool(st["success"]),
                "controls": U, "x": w}

    def replay(self, U: np.ndarray, z0: np.ndarray) -> float:
        """Terminal error of the piecewise-constant controls through the true dynamics."""
        h, z = self.T / self.N, np.asarray(z0, dtype=float)
        for k in range(self.N):
            z = solve_ivp(lambda t, z: np.array(self.f(z, U[k])).ravel(),  # noqa: B023 (called here)
                          (k * h, (k + 1) * h), z, method="DOP853", rtol=1e-12, atol=1e-12).y[:, -1]
        return self.terminal_error(z)


def _nlp(f: ca.Function, nx: int, nu: int, N: int, T: float, initial: Callable, final: Callable,
         cost_weight: Callable[[ca.MX], ca.MX], npar: int) -> ca.Function:
    x, u = ca.SX.sym("x", nx), ca.SX.sym("u", nu)
    h = T / N
    k1 = f(x, u)
    k2 = f(x + h / 2 * k1, u)
    k3 = f(x + h / 2 * k2, u)
    k4 = f(x + h * k3, u)
    F = ca.Function("F", [x, u], [x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)])
    X, U, P = ca.MX.sym("X", nx, N + 1), ca.MX.sym("U", nu, N), ca.MX.sym("P", npar)
    g = [initial(X[:, 0], P), ca.vec(X[:, 1:] - F.map(N)(X[:, :N], U)), final(X[:, N], P)]
    nlp = {"x": ca.vertcat(ca.vec(X), ca.vec(U)), "p": P, "f": cost_weight(U) * h / 2,
           "g": ca.vertcat(*g)}
    return ca.nlpsol("rk4_shooting", "ipopt", nlp, IPOPT)


def rigid_body(N: int, inertia=(1.0, 2.0, 3.0), T: float = 5.0, RT=None) -> Shooting:
    """The rest-to-rest slew: states (q, Omega), controls u with I dOmega/dt + Omega x I Omega
    = I u. Start: the slerp geodesic at its constant rate, zero controls."""
    I = ca.DM(inertia)
    x, u = ca.SX.sym("x", 7), ca.SX.sym("u", 3)
    q, w = x[:4], x[4:]
    f = ca.Function("f", [x, u], [ca.vertcat(0.5 * quat_mult(q, ca.vertcat(0, w)),
                                             u - ca.cross(w, I * w) / I)])
    qT = quaternion(RT)
    solver = _nlp(f, 7, 3, N, T,
                  lambda x0, P: ca.vertcat(x0[:4] - P[:4], x0[4:]),
                  lambda xN, P: ca.vertcat(quat_mult(ca.vertcat(P[4], -P[5:8]), xN[:4])[1:],
                                           xN[4:]),
                  lambda U: ca.sumsqr(U), 8)
    v = so3.quat_log(qT)
    X0 = np.vstack([np.array([so3.quat_exp(v * a) for a in np.linspace(0, 1, N + 1)]).T,
                    np.tile(v[:, None] / T, (1, N + 1))])
    x0 = np.concatenate([X0.ravel(order="F"), np.zeros(3 * N)])

    def error(z: np.ndarray) -> float:
        R = so3.quat_to_matrix(z[:4] / np.linalg.norm(z[:4]))
        return float(np.linalg.norm(so3.log(so3.quat_to_matrix(qT).T @ R)))

    return Shooting(N, T, 7, 3, solver, np.concatenate([[1, 0, 0, 0], qT]), x0, f, error)


def plate_ball(N: int, r: float = 1.0, Omega_p: float = 1.0, c: float = 0.0, T: float = 1.0,
               xyT=(1.0, 0.5), RT=None, start: np.ndarray | None = None) -> Shooting:
    """The plate-ball: states (x, y, q), controls v = (dx/dt, dy/dt); the rolling constraints
    give the spatial angular velocity w(x, y, v), dq/dt = (0, w) q / 2. Start: ``start`` (a
    path of positions, N+1 x 2, e.g. our solution's, so that both methods meet the same
    minimum) with the rolling attitudes along it, or the straight line."""
    x, u = ca.SX.sym("x", 6), ca.SX.sym("u", 2)
    w = ca.vertcat((Omega_p * x[0] - u[1]) / r, (u[0] + Omega_p * x[1]) / r, c)
    f = ca.Function("f", [x, u], [ca.vertcat(u, 0.5 * quat_mult(ca.vertcat(0, w), x[2:6]))])
    qT = quaternion(RT)
    solver = _nlp(f, 6, 2, N, T,
                  lambda x0, P: x0 - ca.vertcat(0, 0, 1, 0, 0, 0),
                  lambda xN, P: ca.vertcat(xN[:2] - P[:2],
                                           quat_mult(ca.vertcat(P[2], -P[3:6]), xN[2:6])[1:]),
                  lambda U: ca.sumsqr(U), 6)
    path = start if start is not None else np.linspace([0.0, 0.0], xyT, N + 1)
    V = np.diff(path, axis=0) / (T / N)
    z, X = np.array([0, 0, 1.0, 0, 0, 0]), [np.array([0, 0, 1.0, 0, 0, 0])]
    for k in range(N):  # roll along the guessed path
        z = np.array(solve_ivp(lambda t, z: np.array(f(z, V[k])).ravel(),  # noqa: B023 (called here)
                               (0, T / N), z, rtol=1e-10, atol=1e-10).y[:, -1])
        X.append(z)
    x0 = np.concatenate([np.array(X).T.ravel(order="F"), V.ravel()])

    def error(z: np.ndarray) -> float:
        R = so3.quat_to_matrix(z[2:6] / np.linalg.norm(z[2:6]))
        return max(float(np.linalg.norm(z[:2] - np.asarray(xyT))),
                   float(np.linalg.norm(so3.log(so3.quat_to_matrix(qT).T @ R))))

    return Shooting(N, T, 6, 2, solver, np.concatenate([xyT, qT]), x0, f, error)
