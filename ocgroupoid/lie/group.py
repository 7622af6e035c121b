"""The interface every Lie group of ocgroupoid implements (manif/Sophus vocabulary).

Primitives (identity, compose, inverse, exp, log, Ad, ad, sample) are per group; the
deduced operations ``between``, ``rplus`` and ``rminus`` are written once here on top of
them (manif's "deduced" section):

    between(a, b) = a^{-1} b,   rplus(a, v) = a exp(v),   rminus(a, b) = log(b^{-1} a),

so that ``rplus(b, rminus(a, b)) = a`` wherever log is the inverse of exp.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np

Array = Any  # numpy.ndarray | casadi.SX | casadi.MX | casadi.DM


class LieGroup(ABC):
    """A matrix Lie group G with Lie algebra identified with R^dim.

    Group elements are the matrices (or vectors, for R^n) that the formulas act on.
    """

    name: str
    dim: int  # dimension of the Lie algebra (tangent space)

    @abstractmethod
    def identity(self) -> Array:
        """The identity element e."""

    @abstractmethod
    def compose(self, a: Array, b: Array) -> Array:
        """The product a b."""

    @abstractmethod
    def inverse(self, a: Array) -> Array:
        """The inverse a^{-1}."""

    @abstractmethod
    def exp(self, x: Array) -> Array:
        """The exponential map g -> G."""

    @abstractmethod
    def log(self, g: Array) -> Array:
        """The principal logarithm G -> g."""

    @abstractmethod
    def Ad(self, g: Array) -> Array:
        """The adjoint matrix: Ad_g x = vee(g hat(x) g^{-1})."""

    @abstractmethod
    def ad(self, x: Array) -> Array:
        """The matrix of ad_x: ad_x y = [x, y]."""

    @abstractmethod
    def distance_from_group(self, g: Array) -> float:
        """How far a numeric matrix is from the group (0 for an exact element)."""

    @abstractmethod
    def sample(self, rng: np.random.Generator) -> np.ndarray:
        """A random element (uniform on compact groups, standard normal on R^n)."""

    # -- deduced operations (written once) ---------------------------------------------

    def between(self, a: Array, b: Array) -> Array:
        """``a^{-1} b``: the element that carries a to b from the right."""
        return self.compose(self.inverse(a), b)

    def rplus(self, a: Array, v: Array) -> Array:
        """``a exp(v)``: a moved by the tangent vector v (right trivialisation)."""
        return self.compose(a, self.exp(v))

    def rminus(self, a: Array, b: Array) -> Array:
        """``log(b^{-1} a)``: the tangent vector from b to a; its norm is their distance."""
        return self.log(self.between(b, a))

    def __repr__(self) -> str:
        return self.name
