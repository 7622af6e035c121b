"""The interface every Lie group of ocgroupoid implements (jaxlie's shape, manif's words).

A group is one object whose methods act on arrays: NumPy arrays (NumPy back) or CasADi
SX/MX graphs (a graph back), through :func:`~ocgroupoid.lie._backend.dual`. An element is
held as its *parameters*, the numbers node states store (jaxlie's "parameters"): a unit
quaternion for SO(3) (4 numbers, 3 dof), a quaternion and a position for SE(3) (7 numbers,
6 dof), the half-angle unit complex number and a position for SE(2) (4 numbers, 3 dof),
the vector itself for R^n. The group matrix is only a view (:meth:`LieGroup.matrix`).
Algebra elements are vectors of R^dim; ``hat`` gives their matrix.

Every rotation is stored as a unit quaternion (or its restriction to the plane), so the
product of parameters is the group product, the sign of the quaternion is free, and the
Cayley coordinates ``2 q_v / q_w`` of a rotation are rational, with a pole (never a root)
at a rotation of pi.

Primitives are per group; the deduced operations are written once here (manif's "deduced"
section):

    between(a, b) = a^{-1} b,   rplus(a, v) = a exp(v),   rminus(a, b) = log(b^{-1} a)

(mirrored on the left side), so that ``rplus(b, rminus(a, b)) = a`` wherever log inverts
exp. Derivatives of maps f: g -> G are right-trivialised, as in
:mod:`ocgroupoid.lie.retraction`: ``d/ds f(a + s b)|_0 = hat(df(a) b) f(a)``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, Literal

import numpy as np

from ._backend import row_major

# numpy.ndarray | casadi.SX | casadi.MX | casadi.DM. mypy (2.4) resolves an overloaded call on
# a value of this alias with casadi's first overload (Sparsity), not as Any: the few lines that
# then fail to type-check say "type: ignore[...]  # Array = Any".
Array = Any
Side = Literal["right", "left"]
Steps = list[tuple[str, list[Array]]]


class LieGroup(ABC):
    """A Lie group G, its elements held as parameters, its algebra identified with R^dim.

    Sizes and the words parameter files and messages use are declared once per group.
    """

    name: str  # short name, e.g. "SE3"
    dim: int  # dimension of the Lie algebra (tangent space)
    size: int  # parameters per element
    #: the algebra components that rotate, to which retractions' step limits refer
    angular: slice = slice(None)
    manifold: str  # how messages name the group, e.g. "SE(3)"
    kind: str  # how a parameter file writes an element: "rotation", "pose", "vector"
    meaning: str  # one line for parameter-file documentation
    matrix_shape: tuple[int, ...]  # the matrix (or vector) users see

    # -- the group -------------------------------------------------------------------

    @abstractmethod
    def identity(self) -> np.ndarray:
        """The parameters of the identity e."""

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
    def log(self, s: Array) -> Array:
        """The principal logarithm G -> g (rotation angle in [0, pi]), on graphs too; either
        sign of a quaternion gives the same value."""

    @abstractmethod
    def cay(self, x: Array) -> Array:
        """The Cayley map ``(I - hat(x)/2)^{-1} (I + hat(x)/2)``."""

    @abstractmethod
    def cay_inv(self, s: Array) -> Array:
        """The algebra element x with cay(x) = s (either sign of a quaternion); a
        :class:`~ocgroupoid.errors.SingularityError` on NumPy input at a rotation of pi."""

    # -- the algebra -----------------------------------------------------------------

    @abstractmethod
    def hat(self, x: Array) -> Array:
        """The matrix of the algebra element x."""

    @abstractmethod
    def vee(self, X: Array) -> Array:
        """The algebra coordinates of a matrix of the algebra."""

    @abstractmethod
    def Ad(self, s: Array) -> Array:
        """The adjoint matrix: ``Ad_g x = vee(g hat(x) g^{-1})``."""

    @abstractmethod
    def ad(self, x: Array) -> Array:
        """The matrix of ad_x: ``ad_x y = [x, y]``."""

    @abstractmethod
    def dexp(self, x: Array) -> Array:
        """Right-trivialised derivative of exp: the left Jacobian (dim x dim)."""

    @abstractmethod
    def dexp_inv(self, x: Array) -> Array:
        """Inverse of ``dexp(x)``."""

    @abstractmethod
    def dcay(self, x: Array) -> Array:
        """Right-trivialised derivative of cay (dim x dim)."""

    @abstractmethod
    def dcay_inv(self, x: Array) -> Array:
        """Inverse of ``dcay(x)``."""

    # -- parameters: motion, charts, values --------------------------------------------

    @abstractmethod
    def body_rate(self, s: Array, y: Array) -> Array:
        """``d/dt (s exp(t y))`` at t = 0: ds/dt when ``s^{-1} ds/dt = hat(y)``."""

    @abstractmethod
    def spatial_rate(self, s: Array, y: Array) -> Array:
        """``d/dt (exp(t y) s)`` at t = 0: ds/dt when ``ds/dt s^{-1} = hat(y)``."""

    @abstractmethod
    def chart(self, e: Array) -> Array:
        """Local coordinates (one per degree of freedom) of a relative element e: the
        Cayley coordinates of its rotation and its position. Zero only at the identity; a
        rotation of pi is a pole."""

    @abstractmethod
    def normalise(self, x: Array) -> Array:
        """A value written in a parameter file -> the parameters (the quaternion
        normalised, with w >= 0; a zero quaternion stays zero and is :meth:`invalid`)."""

    @abstractmethod
    def invalid(self, x: Array) -> Array:
        """1 where a value cannot be normalised (a zero quaternion), else 0."""

    @abstractmethod
    def matrix(self, s: Array) -> Array:
        """The group matrix of parameters (not renormalised: drift stays visible)."""

    @abstractmethod
    def of_matrix(self, M: Any) -> np.ndarray:
        """The parameters (w >= 0) of a numeric group matrix."""

    @abstractmethod
    def parse(self, value: Any) -> np.ndarray:
        """A user's value in any documented form -> the parameters, validated."""

    @abstractmethod
    def detours(self, delta: Array, v: Array, N: int, side: Side) -> Steps:
        """The paths of :meth:`paths` besides the geodesic (``v = log(delta)``)."""

    @abstractmethod
    def sample(self, rng: np.random.Generator) -> np.ndarray:
        """A random element (uniform rotations; standard normal positions and vectors)."""

    @abstractmethod
    def distance_from_group(self, M: Any) -> Any:
        """How far a numeric matrix is from the group (0 for an exact element): a float, or
        for a stack of matrices ``(..., rows, columns)`` an array of their distances."""

    # -- deduced operations (written once) ---------------------------------------------

    def translate(self, s: Array, w: Array, side: Side = "right") -> Array:
        """``s w`` (right, body) or ``w s`` (left, spatial)."""
        return self.compose(s, w) if side == "right" else self.compose(w, s)

    def between(self, a: Array, b: Array, side: Side = "right") -> Array:
        """The element carrying a to b: ``a^{-1} b`` (right) or ``b a^{-1}`` (left), so that
        ``b = translate(a, between(a, b))``."""
        if side == "right":
            return self.compose(self.inverse(a), b)
        return self.compose(b, self.inverse(a))

    def rplus(self, a: Array, v: Array, side: Side = "right") -> Array:
        """``a exp(v)`` (right) or ``exp(v) a`` (left): a moved by the tangent vector v."""
        return self.translate(a, self.exp(v), side)

    def rminus(self, a: Array, b: Array, side: Side = "right") -> Array:
        """``log(between(b, a))``: the tangent vector from b to a; its norm is their
        distance."""
        return self.log(self.between(b, a, side))

    def paths(self, delta: Array, N: int, side: Side) -> Steps:
        """Labelled paths of N steps from the identity to ``delta`` (the preferred first),
        each as its step elements: one element when every step is the same, else N. A path
        is followed by ``translate``-ing N times on the given side. The first is the
        geodesic, the constant step ``exp(log(delta)/N)``; then the :meth:`detours`."""
        v = self.log(delta)
        return [("geodesic", [self.exp(v / N)]), *self.detours(delta, v, N, side)]

    def as_matrix(self, s: Array) -> Array:
        """The group matrix of parameters, flattened row-major."""
        return row_major(self.matrix)(s)

    def __repr__(self) -> str:
        return self.name
