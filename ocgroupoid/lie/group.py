"""The interface every Lie group of ocgroupoid implements (manif/Sophus vocabulary)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

Array = Any  # numpy.ndarray | casadi.SX | casadi.MX | casadi.DM


class LieGroup(ABC):
    """A matrix Lie group G with Lie algebra identified with R^dim.

    Group elements are the matrices (or vectors, for R^n) that the formulas act on;
    ``flatten``/``unflatten`` pack them into the column vectors of an NLP.
    """

    name: str
    dim: int  # dimension of the Lie algebra (tangent space)
    size: int  # length of a flattened group element

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
    def flatten(self, g: Array) -> Array:
        """A group element as a column of length ``size``."""

    @abstractmethod
    def unflatten(self, v: Array) -> Array:
        """Inverse of ``flatten``."""

    @abstractmethod
    def distance_from_group(self, g: Array) -> float:
        """How far a numeric matrix is from the group (0 for an exact element)."""

    def __repr__(self) -> str:
        return self.name
