"""R^n as an abelian Lie group under addition (the group of the pair groupoid's fibres)."""

from __future__ import annotations

import casadi as ca
import numpy as np

from ._backend import is_symbolic
from .group import Array, LieGroup


class Rn(LieGroup):
    """(R^n, +): exp and log are the identity, Ad = I and ad = 0."""

    def __init__(self, n: int) -> None:
        if n < 1:
            raise ValueError(f"R^n needs n >= 1, got {n}")
        self.dim = n
        self.name = f"R{n}"

    def identity(self) -> np.ndarray:
        return np.zeros(self.dim)

    def compose(self, a: Array, b: Array) -> Array:
        return a + b

    def inverse(self, a: Array) -> Array:
        return -a

    def exp(self, x: Array) -> Array:
        return x

    def log(self, g: Array) -> Array:
        return g

    def Ad(self, g: Array) -> Array:
        return np.eye(self.dim)

    def ad(self, x: Array) -> Array:
        return ca.DM.zeros(self.dim, self.dim) if is_symbolic(x) else np.zeros((self.dim,) * 2)

    def distance_from_group(self, g: Array) -> float:
        return 0.0

    def sample(self, rng: np.random.Generator) -> np.ndarray:
        return rng.normal(size=self.dim)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Rn) and other.dim == self.dim

    def __hash__(self) -> int:
        return hash(("Rn", self.dim))
