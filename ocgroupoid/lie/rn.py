"""R^n as an abelian Lie group under addition (the group of the pair groupoid's fibres).

An element is its vector; its matrix is the translation ``[[I, s], [0, 1]]`` and
``hat(x) = [[0, x], [0, 0]]``, so exp, log, cay and their inverses are the identity, every
trivialised derivative is I, Ad = I and ad = 0.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ._backend import dual, is_symbolic
from .group import Array, LieGroup, Side, Steps


class Rn(LieGroup):
    """(R^n, +)."""

    kind = "vector"
    meaning = "vector (one number per component)"

    def __init__(self, n: int) -> None:
        if n < 1:
            raise ValueError(f"R^n needs n >= 1, got {n}")
        self.dim = self.size = n
        self.name = f"R{n}"
        self.manifold = f"R^{n}"
        self.matrix_shape = (n,)

    def _eye(self, like: Array) -> Array:
        return ca.DM.eye(self.dim) if is_symbolic(like) else np.eye(self.dim)

    def identity(self) -> np.ndarray:
        return np.zeros(self.dim)

    def compose(self, a: Array, b: Array) -> Array:
        return a + b

    def inverse(self, a: Array) -> Array:
        return -a

    def exp(self, x: Array) -> Array:
        return x

    def log(self, s: Array) -> Array:
        return s

    def cay(self, x: Array) -> Array:
        return x

    def cay_inv(self, s: Array) -> Array:
        return s

    @dual
    def hat(self, x: Array) -> Array:
        """``[[0, x], [0, 0]]``."""
        return ca.vertcat(ca.horzcat(ca.DM.zeros(self.dim, self.dim), x),
                          ca.DM.zeros(1, self.dim + 1))

    @dual
    def vee(self, X: Array) -> Array:
        return X[: self.dim, self.dim]

    def Ad(self, s: Array) -> Array:
        return np.eye(self.dim)

    def ad(self, x: Array) -> Array:
        return ca.DM.zeros(self.dim, self.dim) if is_symbolic(x) else np.zeros((self.dim,) * 2)

    def dexp(self, x: Array) -> Array:
        return self._eye(x)

    def dexp_inv(self, x: Array) -> Array:
        return self._eye(x)

    def dcay(self, x: Array) -> Array:
        return self._eye(x)

    def dcay_inv(self, x: Array) -> Array:
        return self._eye(x)

    def body_rate(self, s: Array, y: Array) -> Array:
        return y

    def spatial_rate(self, s: Array, y: Array) -> Array:
        return y

    def chart(self, e: Array) -> Array:
        return e

    def normalise(self, x: Array) -> Array:
        return x

    def invalid(self, x: Array) -> Array:
        return ca.DM(0)

    @dual
    def matrix(self, s: Array) -> Array:
        """``[[I, s], [0, 1]]``."""
        return ca.DM.eye(self.dim + 1) + self.hat(s)

    def of_matrix(self, M: Any) -> np.ndarray:
        return np.asarray(M, dtype=float)[: self.dim, self.dim]

    def parse(self, value: Any) -> np.ndarray:
        v = np.asarray(value, dtype=float).reshape(-1)
        if v.shape != (self.dim,):
            raise ConfigError(f"an element of {self.manifold} is {self.dim} numbers, got {v.size}")
        return v

    def as_matrix(self, s: Array) -> Array:
        """The vector itself."""
        return s

    def detours(self, delta: Array, v: Array, N: int, side: Side) -> Steps:
        """None: the straight line is the only path."""
        return []

    def sample(self, rng: np.random.Generator) -> np.ndarray:
        return rng.normal(size=self.dim)

    def distance_from_group(self, M: Any) -> Any:
        return np.zeros(np.shape(M)[:-2]) if np.ndim(M) > 2 else 0.0

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Rn) and other.dim == self.dim

    def __hash__(self) -> int:
        return hash(("Rn", self.dim))
