"""The pair groupoid Q x Q => Q on Q = R^n (seed 000, §3.1.1).

An element is a pair (q_k, q_{k+1}); its velocity is the difference quotient
``xi_k = (q_{k+1} - q_k)/h``, i.e. the step is the translation by ``h xi_k`` of (R^n, +).
Composable pairs (q_k, q_{k+1}), (q_{k+1}, q_{k+2}) give the three-point stencils of the
discrete second-order Euler-Lagrange equations (eq. 16).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..lie.group import Array
from ..lie.retraction import Retraction
from ..lie.rn import Rn
from .base import BoundaryMask, Factor, Labelled


def hermite_basis(N: int) -> np.ndarray:
    """The cubic Hermite basis (h00, h10, h01, h11) on the N + 1 nodes of [0, 1], as columns:
    rows times (s0, T v0, sT, T vT) give the cubic's node values."""
    t = np.linspace(0.0, 1.0, N + 1)[:, None]
    return np.hstack([2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t, -2 * t**3 + 3 * t**2,
                      t**3 - t**2])


def _pick(flags: np.ndarray, given: Array, other: Array) -> Array:
    """``given[i]`` where ``flags[i]``, else ``other[i]`` (flags are structural)."""
    return ca.vertcat(*[given[i] if on else other[i] for i, on in enumerate(flags)])


class Pair(Factor):
    """R^n x R^n => R^n with positions ``state`` and velocities ``velocity``."""

    side = "right"
    componentwise = True

    def __init__(self, n: int, state: str = "q", velocity: str = "v") -> None:
        self.group = Rn(n)
        self.state, self.velocity = state, velocity
        self.state_size = self.state_dim = self.base_size = self.target_size = n
        self.manifold, self.value_kind = self.group.manifold, self.group.kind
        self.value_meaning = self.group.meaning

    def step(self, s: Array, ret: Retraction, a: Array) -> Array:
        return s + a

    def base(self, s: Array) -> Array:
        return s

    def variation(self, s: Array, eta: Array) -> Array:
        return eta

    def chart(self, s: Array, target: Array) -> Array:
        return s - target

    def rplus(self, s: Array, v: Array) -> Array:
        return s + v

    def rminus(self, s: Array, goal: Array) -> Array:
        return s - goal

    def pack_target(self, x: Array) -> Array:
        return x

    def anchor(self, q: Array, y: Array) -> Array:
        return y

    def ad(self, y: Array) -> Array:
        return ca.DM.zeros(self.group.dim, self.group.dim)

    def state_rate(self, s: Array, y: Array) -> Array:
        return y

    def guesses(self, ret: Retraction, start: Array, end: Array, V0: Array, VN: Array,
                T: Array, N: int, mask: BoundaryMask) -> Labelled:
        """The cubic through the prescribed end positions and velocities, as difference
        quotients on the nodes. A free end position is reached by moving with the initial
        velocity (or resting); a free end velocity is the mean velocity."""
        n = self.group.dim
        zero = type(start).zeros(n, 1)
        goal = _pick(mask.end_state, end, start + T * _pick(mask.start_velocity, V0, zero))
        mean = (goal - start) / T
        v0 = _pick(mask.start_velocity, V0, mean)
        vT = _pick(mask.end_velocity, VN, mean)
        nodes = ca.mtimes(ca.DM(hermite_basis(N)), ca.horzcat(start, T * v0, goal, T * vT).T)
        return [("cubic", ((nodes[1:, :] - nodes[:-1, :]) / (T / N)).T)]

    def parse_state(self, value: Any) -> np.ndarray:
        v = np.asarray(value, dtype=float).reshape(-1)
        if v.shape != (self.group.dim,):
            raise ConfigError(f"{self.state} needs {self.group.dim} numbers, got {v.size}")
        return v

    def distance(self, s: np.ndarray) -> float:
        return 0.0

    def sample_state(self, rng: np.random.Generator) -> np.ndarray:
        return rng.normal(size=self.group.dim)

    # -- groupoid structure maps --------------------------------------------------------

    def source(self, g: Any) -> np.ndarray:
        return np.asarray(g[0])

    def target(self, g: Any) -> np.ndarray:
        return np.asarray(g[1])

    def identity(self, x: Any) -> tuple[np.ndarray, np.ndarray]:
        return (np.asarray(x), np.asarray(x))

    def inverse(self, g: Any) -> tuple[np.ndarray, np.ndarray]:
        return (np.asarray(g[1]), np.asarray(g[0]))

    def multiply(self, g: Any, k: Any) -> tuple[np.ndarray, np.ndarray]:
        return (np.asarray(g[0]), np.asarray(k[1]))

    def element(self, s: np.ndarray, w: Any) -> tuple[np.ndarray, np.ndarray]:
        return (np.asarray(s), np.asarray(s) + np.asarray(w))
