"""The action groupoid S^2 x SO(3) => S^2 of the heavy top (seed 000, §3.1.3, §3.3.5).

SO(3) acts on the sphere from the right by ``Gamma . W = W^T Gamma``; an element
``(Gamma_k, W_k)`` goes from ``Gamma_k`` to ``W_k^T Gamma_k``, so composable pairs satisfy
``Gamma_{k+1} = W_k^T Gamma_k``. Its Lie algebroid is ``S^2 x so(3)`` with anchor
``rho(Gamma, Omega) = Gamma x Omega`` and the bracket of so(3).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..lie._backend import dual, is_symbolic, safe_if
from ..lie.group import Array
from ..lie.retraction import Retraction
from ..lie.so3 import SO3
from .base import BoundaryMask, Factor, Labelled


def _cross(a: Array, b: Array) -> Array:
    return ca.cross(a, b) if is_symbolic(a, b) else np.cross(a, b)


@dual
def stereographic(s: Array, target: Array) -> Array:
    """``(t_i . Gamma)/(1 + Gamma_T . Gamma)``, i = 1, 2, for target = (Gamma_T, t_1, t_2).

    On the far hemisphere (``Gamma_T . Gamma < 0``) the same value is computed as
    ``tan(theta/2) (t_i . Gamma)/sin(theta)``, ``theta = atan2(sin, cos)``: near the antipode
    both ``t_i . Gamma`` and ``1 + Gamma_T . Gamma`` round to nothing, and their quotient
    turned the pole into a spurious root (IPOPT converged to ``Gamma(T) = -Gamma_T``).
    """
    g, t1, t2 = target[0:3], target[3:6], target[6:9]
    a = ca.vertcat(ca.dot(t1, s), ca.dot(t2, s))
    cos = ca.dot(g, s)
    far = cos < 0
    sin = ca.sqrt(ca.if_else(far, ca.sumsqr(a), 1.0))  # the near branch never takes the root
    return a * ca.if_else(far, ca.tan(ca.atan2(sin, cos) / 2) / sin, 1 / (1 + cos))


@dual
def tangent_basis(n: Array) -> tuple[Array, Array]:
    """An orthonormal basis (t1, t2) of the plane orthogonal to the unit vector n:
    ``t1 = n x e / |n x e|`` with e the axis of the smallest ``|n_i|`` (the first one on
    ties), ``t2 = n x t1``."""
    a = ca.fabs(n)
    e = ca.if_else(ca.logic_and(a[0] <= a[1], a[0] <= a[2]), ca.DM([1, 0, 0]),  # type: ignore[index]  # Array = Any (lie/group.py)
                   ca.if_else(a[1] <= a[2], ca.DM([0, 1, 0]), ca.DM([0, 0, 1])))  # type: ignore[index]  # Array = Any (lie/group.py)
    t1 = ca.cross(n, e)
    t1 = t1 / ca.norm_2(t1)
    return t1, ca.cross(n, t1)


class SphereAction(Factor):
    """Node states Gamma_k on the unit sphere, velocities Omega_k in so(3), body convention."""

    group = SO3
    side = "right"
    state_size = 3
    state_dim = 2
    manifold = "S^2"
    base_size = 3
    target_size = 9  # Gamma_T and an orthonormal basis (t1, t2) of its tangent plane
    value_kind = "direction"
    value_meaning = "unit 3-vector (|v| = 1 to 1e-6)"

    def __init__(self, state: str = "Gamma", velocity: str = "Omega") -> None:
        self.state, self.velocity = state, velocity

    def step(self, s: Array, ret: Retraction, a: Array) -> Array:
        return self.group.matrix(ret.tau(a)).T @ s

    def base(self, s: Array) -> Array:
        return s

    def variation(self, s: Array, eta: Array) -> Array:
        """``Gamma -> exp(-t hat(eta)) Gamma``: dGamma = Gamma x eta."""
        return _cross(s, eta)

    def chart(self, s: Array, target: Array) -> Array:
        """Stereographic coordinates from the antipode of Gamma_T (see :func:`stereographic`).
        Two equations, zero only at Gamma_T; the antipode is a pole."""
        return stereographic(s, target)

    def rplus(self, s: Array, v: Array) -> Array:
        """The direction s rotated by the rotation vector v: ``exp(hat(v)) s``."""
        return SO3.matrix(SO3.exp(v)) @ s

    def rminus(self, s: Array, goal: Array) -> Array:
        """The rotation vector, orthogonal to both, that turns the goal into s/|s|."""
        return _great_circle(goal, s)

    def pack_target(self, x: Array) -> Array:
        return _direction_target(x)

    def invalid(self, x: Array) -> Array:
        return ca.fabs(ca.norm_2(x) - 1) > 1e-6

    def anchor(self, q: Array, y: Array) -> Array:
        return _cross(q, y)

    def ad(self, y: Array) -> Array:
        return SO3.hat(y)

    def state_rate(self, s: Array, y: Array) -> Array:
        return _cross(s, y)

    def guesses(self, ret: Retraction, start: Array, end: Array, V0: Array, VN: Array,
                T: Array, N: int, mask: BoundaryMask) -> Labelled:
        """Great circle from Gamma_0 to Gamma_T, both ways round; rest when Gamma_T is free.
        ``W^T`` turns Gamma by 1/N of the arc per step."""
        if not mask.end_state.all():
            return [("rest", type(start).zeros(3, N))]
        v = _great_circle(start[:3], end[:3])
        angle = ca.norm_2(v)
        turns = angle > 1e-12
        axis = ca.if_else(turns, v / safe_if(turns, angle, 1.0), tangent_basis(start[:3])[0])
        h = T / N
        return [(name, ca.repmat(ret.tau_inv(SO3.exp(-axis * phi / N)) / h, 1, N))
                for name, phi in (("great circle", angle),
                                  ("great circle, long way", angle - 2 * np.pi))]

    def parse_state(self, value: Any) -> np.ndarray:
        v = np.asarray(value, dtype=float).reshape(-1)
        if v.shape != (3,) or not np.all(np.isfinite(v)):
            raise ConfigError(f"{self.state} is a unit 3-vector, got {np.asarray(value).tolist()}")
        n = np.linalg.norm(v)
        if abs(n - 1.0) > 1e-6:
            raise ConfigError(
                f"{self.state} must be a unit vector (|{self.state}| = {n:.6g}); normalise it"
            )
        return v / n

    def distance(self, s: np.ndarray) -> float:
        return abs(float(np.linalg.norm(s)) - 1.0)

    def sample_state(self, rng: np.random.Generator) -> np.ndarray:
        v = rng.normal(size=3)
        return v / np.linalg.norm(v)

    # -- groupoid structure maps --------------------------------------------------------

    def source(self, g: Any) -> np.ndarray:
        return np.asarray(g[0])

    def target(self, g: Any) -> np.ndarray:
        return np.asarray(g[1]).T @ np.asarray(g[0])

    def identity(self, x: Any) -> tuple[np.ndarray, np.ndarray]:
        return (np.asarray(x), np.eye(3))

    def inverse(self, g: Any) -> tuple[np.ndarray, np.ndarray]:
        return (self.target(g), np.asarray(g[1]).T)

    def multiply(self, g: Any, k: Any) -> tuple[np.ndarray, np.ndarray]:
        return (np.asarray(g[0]), np.asarray(g[1]) @ np.asarray(k[1]))

    def element(self, s: np.ndarray, w: Any) -> tuple[np.ndarray, np.ndarray]:
        """``(Gamma, W)``, W the rotation matrix of the rotation w."""
        return (np.asarray(s), np.asarray(SO3.matrix(w)))


@dual
def _great_circle(a: Array, b: Array) -> Array:
    """The rotation vector ``angle * (a x b)/|a x b|`` that turns the direction a into b/|b|
    (zero when they agree; at the antipode the axis is the first tangent of a)."""
    b = b / ca.norm_2(b)
    axis = ca.cross(a, b)
    sin, cos = ca.norm_2(axis), ca.dot(a, b)
    turns = sin > 1e-12
    axis = ca.if_else(turns, axis / safe_if(turns, sin, 1.0), tangent_basis(a)[0])
    return ca.atan2(sin, cos) * axis


@dual
def _direction_target(x: Array) -> Array:
    n = ca.norm_2(x)
    g = x / safe_if(n > 0, n, 1.0)
    return ca.vertcat(g, *tangent_basis(g))
