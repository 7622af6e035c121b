"""Test oracles: the groups' maps written on their matrices, in NumPy.

The package holds group elements as parameters (quaternions, half-angle numbers); these are
the closed forms on matrices it used to evaluate (Rodrigues, the Cayley map of seed 000
eq. 63 and of Kobilarov & Marsden 2011, the left Jacobians), kept to check the classes
against, beside the definitions themselves (``expm``, ``(I - X/2)^{-1} (I + X/2)``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

Map = Callable[[np.ndarray], np.ndarray]
K = np.array([[0.0, -1.0], [1.0, 0.0]])


def hat3(w: np.ndarray) -> np.ndarray:
    """``hat(w) v = w x v``."""
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def vee_skew(M: np.ndarray) -> np.ndarray:
    """vee of the skew part: ``vee((M - M^T)/2)``."""
    return np.array([M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1]]) / 2


def _homogeneous(R: np.ndarray, p: np.ndarray) -> np.ndarray:
    n = len(p)
    g = np.eye(n + 1)
    g[:n, :n], g[:n, n] = R, p
    return g


def _abc(w: np.ndarray) -> tuple[float, float, float]:
    """sin t/t, (1 - cos t)/t^2, (t - sin t)/t^3 at t = |w| (t > 0)."""
    t = float(np.linalg.norm(w))
    if t < 1e-6:
        return 1.0, 0.5, 1 / 6
    return np.sin(t) / t, (1 - np.cos(t)) / t**2, (t - np.sin(t)) / t**3


# -- SO(3) ------------------------------------------------------------------------------


def so3_exp(w: np.ndarray) -> np.ndarray:
    """Rodrigues: ``I + A hat(w) + B hat(w)^2``."""
    W, (A, B, _) = hat3(w), _abc(w)
    return np.eye(3) + A * W + B * W @ W


def so3_jacobian(w: np.ndarray) -> np.ndarray:
    """The left Jacobian ``I + B hat(w) + C hat(w)^2``."""
    W, (_, B, C) = hat3(w), _abc(w)
    return np.eye(3) + B * W + C * W @ W


def so3_log(R: np.ndarray) -> np.ndarray:
    """``theta/sin(theta) vee_skew(R)`` (rotations below pi)."""
    s = vee_skew(R)
    n = float(np.linalg.norm(s))
    theta = np.arctan2(n, (np.trace(R) - 1) / 2)
    return s * (theta / n if n > 1e-12 else 1.0)


def so3_cay(a: np.ndarray) -> np.ndarray:
    """Seed 000, eq. 63: ``I + 4/(4 + |a|^2) (hat(a) + hat(a)^2/2)``."""
    A = hat3(a)
    return np.eye(3) + 4 / (4 + a @ a) * (A + A @ A / 2)


def so3_cay_inv(R: np.ndarray) -> np.ndarray:
    """``4 vee_skew(R)/(1 + tr R)``."""
    return 4 * vee_skew(R) / (1 + np.trace(R))


def first_order_tau(a: np.ndarray) -> np.ndarray:
    """The rotation whose skew part is hat(a): ``c I + hat(a) + a a^T/(1 + c)``."""
    c = np.sqrt(1 - a @ a)
    return c * np.eye(3) + hat3(a) + np.outer(a, a) / (1 + c)


# -- SE(3) ------------------------------------------------------------------------------


def se3_exp(x: np.ndarray) -> np.ndarray:
    return _homogeneous(so3_exp(x[:3]), so3_jacobian(x[:3]) @ x[3:])


def se3_log(g: np.ndarray) -> np.ndarray:
    w = so3_log(g[:3, :3])
    return np.concatenate([w, np.linalg.solve(so3_jacobian(w), g[:3, 3])])


def se3_cay(x: np.ndarray) -> np.ndarray:
    """``[[cay(omega), (I - hat(omega)/2)^{-1} v], [0, 1]]``."""
    return _homogeneous(so3_cay(x[:3]), np.linalg.solve(np.eye(3) - hat3(x[:3]) / 2, x[3:]))


def se3_cay_inv(g: np.ndarray) -> np.ndarray:
    w = so3_cay_inv(g[:3, :3])
    return np.concatenate([w, (np.eye(3) - hat3(w) / 2) @ g[:3, 3]])


def se3_Ad(g: np.ndarray) -> np.ndarray:
    """``[[R, 0], [hat(p) R, R]]``."""
    R = g[:3, :3]
    return np.block([[R, np.zeros((3, 3))], [hat3(g[:3, 3]) @ R, R]])


# -- SE(2) ------------------------------------------------------------------------------


def _rotation(theta: float) -> np.ndarray:
    return np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])


def _V(w: float) -> np.ndarray:
    """``sin(w)/w I + (1 - cos w)/w K``."""
    A, B, _ = _abc(np.array([w]))
    return A * np.eye(2) + w * B * K


def se2_exp(x: np.ndarray) -> np.ndarray:
    return _homogeneous(_rotation(x[0]), _V(x[0]) @ x[1:])


def se2_log(g: np.ndarray) -> np.ndarray:
    theta = np.arctan2(g[1, 0], g[0, 0])
    return np.concatenate([[theta], np.linalg.solve(_V(theta), g[:2, 2])])


def se2_cay(x: np.ndarray) -> np.ndarray:
    """``[[R, (I + omega K/2) v/d], [0, 1]]``, ``R = [[1 - w^2/4, -w], [w, 1 - w^2/4]]/d``."""
    w, d = x[0], 1 + x[0] ** 2 / 4
    R = np.array([[1 - w * w / 4, -w], [w, 1 - w * w / 4]]) / d
    return _homogeneous(R, (np.eye(2) + w / 2 * K) @ x[1:] / d)


def se2_cay_inv(g: np.ndarray) -> np.ndarray:
    """``omega = 2 (R10 - R01)/(2 + tr R)``, ``v = (I - omega K/2) p``."""
    w = 2 * (g[1, 0] - g[0, 1]) / (2 + g[0, 0] + g[1, 1])
    return np.concatenate([[w], (np.eye(2) - w / 2 * K) @ g[:2, 2]])


def se2_Ad(g: np.ndarray) -> np.ndarray:
    """``[[1, 0], [-K p, R]]``."""
    out = np.eye(3)
    out[1:, 0], out[1:, 1:] = -K @ g[:2, 2], g[:2, :2]
    return out


# -- R^n ---------------------------------------------------------------------------------


def rn_exp(x: np.ndarray) -> np.ndarray:
    return _homogeneous(np.eye(len(x)), x)


def rn_log(g: np.ndarray) -> np.ndarray:
    return g[:-1, -1]


@dataclass(frozen=True)
class Oracle:
    """A group's maps on matrices."""

    exp: Map
    log: Map
    cay: Map
    cay_inv: Map
    Ad: Map


ORACLES = {
    "SO3": Oracle(so3_exp, so3_log, so3_cay, so3_cay_inv, lambda R: R),
    "SE3": Oracle(se3_exp, se3_log, se3_cay, se3_cay_inv, se3_Ad),
    "SE2": Oracle(se2_exp, se2_log, se2_cay, se2_cay_inv, se2_Ad),
    "R4": Oracle(rn_exp, rn_log, rn_exp, rn_log, lambda g: np.eye(len(g) - 1)),
}
