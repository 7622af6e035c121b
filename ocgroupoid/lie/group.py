"""The interface every Lie group of ocgroupoid implements (manif/Sophus vocabulary).

Primitives (identity, compose, inverse, exp, log, Ad, ad, sample) are per group; the
deduced operations ``between``, ``rplus`` and ``rminus`` are written once here on top of
them (manif's "deduced" section):

    between(a, b) = a^{-1} b,   rplus(a, v) = a exp(v),   rminus(a, b) = log(b^{-1} a),

so that ``rplus(b, rminus(a, b)) = a`` wherever log is the inverse of exp.

:class:`MatrixGroup` adds what node states on the group need: the Cayley map and the left
Jacobian in closed form, and the stored form of elements (:mod:`ocgroupoid.lie.form`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from types import ModuleType
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from ._backend import is_symbolic

if TYPE_CHECKING:
    from .form import StateForm

# numpy.ndarray | casadi.SX | casadi.MX | casadi.DM. mypy (2.4) resolves an overloaded call on
# a value of this alias with casadi's first overload (Sparsity), not as Any: the few lines that
# then fail to type-check say "type: ignore[...]  # Array = Any".
Array = Any


class LieGroup(ABC):
    """A matrix Lie group G with Lie algebra identified with R^dim.

    Group elements are the matrices (or vectors, for R^n) that the formulas act on.
    """

    name: str
    dim: int  # dimension of the Lie algebra (tangent space)
    #: the algebra components that rotate, to which retractions' step limits refer
    turning: slice = slice(None)
    #: how node states store an element (None: not a node state of LieGroupFactor)
    form: "StateForm | None" = None

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


class MatrixGroup(LieGroup):
    """A matrix group whose elements can be node states: the Cayley map and the exponential
    with their right-trivialised derivatives in closed form (the retractions ``cayley`` and
    ``exp``), and the :class:`~ocgroupoid.lie.form.StateForm` its elements are stored as.

    Derivatives follow the convention of :mod:`ocgroupoid.lie.retraction`:
    ``d/ds f(a + s b)|_0 = hat(df(a) b) f(a)`` for f = cay (``dcay``) and f = exp
    (``dexp``, the left Jacobian).
    """

    form: "StateForm"
    #: the module whose functions (``inverse``, ``exp``, ``log``, ``hat``, ``vee``, ``Ad``,
    #: ``ad``, ``cay``, ``cay_inv``, ``dcay``, ``dcay_inv``, ``dexp``, ``dexp_inv``) are the
    #: group's formulas, written once for NumPy and CasADi
    formulas: ModuleType

    def compose(self, a: Array, b: Array) -> Array:
        return a @ b if not is_symbolic(a, b) else ca.mtimes(a, b)

    def inverse(self, a: Array) -> Array:
        return self.formulas.inverse(a)

    def exp(self, x: Array) -> Array:
        return self.formulas.exp(x)

    def log(self, g: Array) -> Array:
        return self.formulas.log(g)

    def hat(self, x: Array) -> Array:
        """The matrix of the algebra element x."""
        return self.formulas.hat(x)

    def vee(self, X: Array) -> Array:
        """The algebra coordinates of a matrix of the algebra."""
        return self.formulas.vee(X)

    def Ad(self, g: Array) -> Array:
        return self.formulas.Ad(g)

    def ad(self, x: Array) -> Array:
        return self.formulas.ad(x)

    def cay(self, x: Array) -> Array:
        """The Cayley map ``(I - hat(x)/2)^{-1} (I + hat(x)/2)``."""
        return self.formulas.cay(x)

    def cay_inv(self, g: Array) -> Array:
        """Its inverse; a SingularityError on NumPy input at a rotation of pi."""
        return self.formulas.cay_inv(g)

    def dcay(self, x: Array) -> Array:
        """Right-trivialised derivative of cay (dim x dim)."""
        return self.formulas.dcay(x)

    def dcay_inv(self, x: Array) -> Array:
        """Inverse of ``dcay(x)``."""
        return self.formulas.dcay_inv(x)

    def dexp(self, x: Array) -> Array:
        """Right-trivialised derivative of exp: the left Jacobian (dim x dim)."""
        return self.formulas.dexp(x)

    def dexp_inv(self, x: Array) -> Array:
        """Inverse of ``dexp(x)``."""
        return self.formulas.dexp_inv(x)
