"""A Lie group written on the numbers its elements are stored as in node states.

Groups act on matrices; node states store fewer numbers (jaxlie's "parameters"): a unit
quaternion for SO(3) (4 numbers, 3 dof), a quaternion and a position for SE(3) (7 numbers,
6 dof), the half-angle unit complex number and a position for SE(2) (4 numbers, 3 dof).
A :class:`StateForm` implements the group on those numbers, for NumPy and CasADi graphs
alike; the deduced operations (``translate``, ``between``, ``shown``) are written once here.

Every form stores the rotation as a unit quaternion (or its restriction to the plane),
so the product of stored elements is the group product, the sign of the quaternion is
free, and the Cayley coordinates ``2 q_v / q_w`` of a rotation are rational, with a pole
(never a root) at a rotation of pi.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, Callable, Literal

import casadi as ca
import numpy as np

from ._backend import dual, is_symbolic
from .group import Array

Side = Literal["right", "left"]
Steps = list[tuple[str, list[Array]]]


def pure(v: Array) -> Array:
    """The pure quaternion (0, v) (a graph or NumPy, like v)."""
    return ca.vertcat(0, v) if is_symbolic(v) else np.concatenate([[0.0], np.ravel(v)])


def row_major(matrix: Callable[[Array], Array]) -> Callable[[Array], Array]:
    """``s -> vec(matrix(s)^T)``: the matrix of a stored element flattened row-major."""
    return dual(lambda s: ca.vec(matrix(s).T))


class StateForm(ABC):
    """The group on its stored numbers (see the module docstring).

    Sizes and the words parameter files and messages use are declared once per form.
    """

    size: int  # numbers stored per element
    manifold: str  # how messages name the group, e.g. "SE(3)"
    kind: str  # how a parameter file writes an element: "rotation", "pose"
    meaning: str  # one line for parameter-file documentation
    shown_shape: tuple[int, int]  # the matrix users see

    # -- primitives ---------------------------------------------------------------------

    @abstractmethod
    def compose(self, a: Array, b: Array) -> Array:
        """The stored product a b."""

    @abstractmethod
    def inverse(self, a: Array) -> Array:
        """The stored inverse a^{-1}."""

    @abstractmethod
    def exp(self, x: Array) -> Array:
        """exp(x), stored."""

    @abstractmethod
    def log(self, s: Array) -> Array:
        """The principal logarithm of a stored element (rotation angle in [0, pi]),
        on graphs too; either sign of the quaternion gives the same value."""

    @abstractmethod
    def cay(self, x: Array) -> Array:
        """The Cayley map cay(x), stored."""

    @abstractmethod
    def cay_inv(self, s: Array) -> Array:
        """The algebra element x with cay(x) = s (either sign of the quaternion)."""

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
        """A value written in a parameter file -> the stored element (the quaternion
        normalised, with w >= 0; a zero quaternion stays zero and is :meth:`invalid`)."""

    @abstractmethod
    def invalid(self, x: Array) -> Array:
        """1 where a value cannot be normalised (a zero quaternion), else 0."""

    @abstractmethod
    def matrix(self, s: Array) -> Array:
        """The group matrix of a stored element (not renormalised: drift stays visible)."""

    @abstractmethod
    def of_matrix(self, M: Any) -> np.ndarray:
        """The stored element (w >= 0) of a numeric group matrix."""

    @abstractmethod
    def parse(self, value: Any) -> np.ndarray:
        """A user's value in any documented form -> the stored element, validated."""

    @abstractmethod
    def paths(self, delta: Array, N: int, side: Side) -> Steps:
        """Labelled paths of N steps from the identity to ``delta`` (the preferred first),
        each as its step elements: one element when every step is the same, else N. A
        path is followed by ``translate``-ing N times on the given side."""

    # -- deduced operations (written once) ----------------------------------------------

    def translate(self, s: Array, w: Array, side: Side) -> Array:
        """``s w`` (right, body) or ``w s`` (left, spatial)."""
        return self.compose(s, w) if side == "right" else self.compose(w, s)

    def between(self, a: Array, b: Array, side: Side) -> Array:
        """The element carrying a to b: ``a^{-1} b`` (right) or ``b a^{-1}`` (left), so that
        ``b = translate(a, between(a, b))``."""
        if side == "right":
            return self.compose(self.inverse(a), b)
        return self.compose(b, self.inverse(a))

    def shown(self, s: Array) -> Array:
        """The group matrix of a stored element, flattened row-major."""
        return row_major(self.matrix)(s)
