"""Retractions tau: g -> G with tau(0) = e and tau(a) tau(-a) = e.

Each retraction has ``tau``, ``tau_inv`` and the right-trivialised derivative ``dtau`` with
its inverse ``dtau_inv`` (seed 000, Appendix D, eq. 64; seed 001, §6.1):

    d/ds tau(a + s b)|_{s=0} = hat(dtau(a) b) tau(a).

The left-trivialised ones follow from tau(-a) = tau(a)^{-1}:
``tau(a)^{-1} d tau(a)[b] = hat(dtau(-a) b)``, exposed as ``dtau_left``/``dtau_inv_left``.
Group elements are the group's parameters (:mod:`ocgroupoid.lie.group`): a unit quaternion
on SO(3), quaternion and position on SE(3), ...

The Cayley map and the exponential are written once over every
:class:`~ocgroupoid.lie.group.LieGroup`, which supplies their formulas; the seeds'
first-order rule is SO(3)'s alone.

Singularities are reported, not hidden: on NumPy input ``tau_inv`` raises
:class:`SingularityError` with the fix (a smaller step, i.e. a larger N).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import casadi as ca
import numpy as np

from ..errors import ConfigError, SingularityError
from ._backend import dual, guarded, is_symbolic
from .group import Array, LieGroup
from .rn import Rn
from .so3 import SO3, SO3Group

RETRACTION_NAMES = ("cayley", "exp", "first_order")


class Retraction(ABC):
    """A local diffeomorphism tau: g -> G around 0, with trivialised derivatives."""

    name: str
    group: LieGroup
    #: the rotation angle of one step near which the retraction degenerates (quoted by
    #: hints), as :meth:`step_norm` measures it
    step_limit: float = float("inf")

    @abstractmethod
    def tau(self, a: Array) -> Array:
        """The group element tau(a) (its parameters)."""

    @abstractmethod
    def tau_inv(self, s: Array) -> Array:
        """The algebra element a with tau(a) = s (either sign of a quaternion), on graphs
        too."""

    @abstractmethod
    def dtau(self, a: Array) -> Array:
        """Right-trivialised derivative (dim x dim matrix)."""

    @abstractmethod
    def dtau_inv(self, a: Array) -> Array:
        """Inverse of ``dtau(a)``."""

    def dtau_left(self, a: Array) -> Array:
        """Left-trivialised derivative: ``tau(a)^{-1} d tau(a)[b] = hat(dtau(-a) b)``."""
        return self.dtau(-a)

    def dtau_inv_left(self, a: Array) -> Array:
        """Inverse of ``dtau_left(a)``."""
        return self.dtau_inv(-a)

    def step_norm(self, a: Any) -> np.ndarray:
        """The rotation angle of numeric steps (one per row of a), which ``step_limit``
        refers to: |a| on SO(3) and R^n, |omega| on SE(n)."""
        return np.linalg.norm(np.asarray(a, dtype=float)[..., self.group.angular], axis=-1)

    def __repr__(self) -> str:
        return f"{self.name}({self.group.name})"


# ----------------------------------------------------------------- SO(3), SE(3), SE(2)


class Cayley(Retraction):
    """cay(a) = (I - hat(a)/2)^{-1} (I + hat(a)/2); rational, singular only at a rotation of
    pi (eq. 63 on SO(3); Kobilarov & Marsden 2011 on SE(3))."""

    name = "cayley"
    step_limit = float(np.pi)

    def __init__(self, group: LieGroup = SO3) -> None:
        self.group = group

    def tau(self, a: Array) -> Array:
        """E.g. ``(1, a/2)/sqrt(1 + |a|^2/4)`` on SO(3)."""
        return self.group.cay(a)

    def tau_inv(self, s: Array) -> Array:
        """E.g. ``2 q_v / q_w`` on SO(3); undefined for a rotation of pi (a
        SingularityError on NumPy input)."""
        return self.group.cay_inv(s)

    def dtau(self, a: Array) -> Array:
        return self.group.dcay(a)

    def dtau_inv(self, a: Array) -> Array:
        return self.group.dcay_inv(a)


class Exp(Retraction):
    """The exponential map; ``dtau`` is the group's left Jacobian."""

    name = "exp"
    step_limit = float(np.pi)

    def __init__(self, group: LieGroup = SO3) -> None:
        self.group = group

    def tau(self, a: Array) -> Array:
        """E.g. ``(cos(t/2), sin(t/2) a/t)``, t = |a|, on SO(3)."""
        return self.group.exp(a)

    def tau_inv(self, s: Array) -> Array:
        return self.group.log(s)

    def dtau(self, a: Array) -> Array:
        return self.group.dexp(a)

    def dtau_inv(self, a: Array) -> Array:
        return self.group.dexp_inv(a)


# -------------------------------------------------------------- SO(3): the seeds' rule


def _asin_ratios(x2: Array) -> tuple[Array, Array]:
    """s = asin(x)/x and t = s'(x)/x at x^2 = x2 (x = |a| < 1), NaN-free at 0."""
    s = guarded(x2, 1e-3, (1, 1 / 6, 3 / 40, 5 / 112, 35 / 1152), lambda x, x2: ca.asin(x) / x)
    t = guarded(x2, 1e-3, (1 / 3, 3 / 10, 15 / 56, 35 / 144, 315 / 1408),
                lambda x, x2: (1 / ca.sqrt(1 - x2) - ca.asin(x) / x) / x2)
    return s, t


@dual
def _first_order_tau(a: Array) -> Array:
    w = ca.sqrt((1 + ca.sqrt(1 - ca.dot(a, a))) / 2)  # cos(angle/2), angle = asin|a|
    return ca.vertcat(w, a / (2 * w))


@dual
def _first_order_tau_inv(q: Array) -> Array:
    return 2 * q[0] * q[1:4] / ca.dot(q, q)


@dual
def _first_order_dtau(a: Array) -> Array:
    s, t = _asin_ratios(ca.dot(a, a))
    return ca.mtimes(SO3.dexp(s * a), s * ca.DM.eye(3) + t * ca.mtimes(a, a.T))


@dual
def _first_order_dtau_inv(a: Array) -> Array:
    x2 = ca.dot(a, a)
    s, t = _asin_ratios(x2)
    D_inv = (ca.DM.eye(3) - t / (s + t * x2) * ca.mtimes(a, a.T)) / s
    return ca.mtimes(D_inv, SO3.dexp_inv(s * a))


class FirstOrder(Retraction):
    """The seeds' first-order rule ``g ~ I + h xi`` read out by the skew part (seed 001, eq. 8).

    ``tau_inv(R) = vee((R - R^T)/2)`` (= sin(angle) * axis); its inverse is the rotation
    whose skew part is hat(a): ``tau(a) = c I + hat(a) + a a^T/(1 + c)``, ``c = sqrt(1 -
    |a|^2)``, whose unit quaternion is ``(w, a/(2w))``, ``w = cos(angle/2) = sqrt((1 + c)/2)``.
    Defined for steps below pi/2 (|a| < 1).
    """

    name = "first_order"
    group = SO3
    step_limit = float(np.pi / 2)

    def tau(self, a: Array) -> Array:
        if not is_symbolic(a) and float(np.dot(np.ravel(a), np.ravel(a))) >= 1.0:
            raise SingularityError(
                "first-order retraction undefined: |h xi| >= 1 (a rotation of pi/2 or more in "
                "one step); increase N"
            )
        return _first_order_tau(a)

    def tau_inv(self, q: Array) -> Array:
        """``vee_skew(R(q)) = 2 q_w q_v / |q|^2``; a SingularityError on NumPy input where
        ``tr R = (3 q_w^2 - |q_v|^2)/|q|^2 <= 1`` (a rotation of pi/2 or more)."""
        if not is_symbolic(q):
            q = np.asarray(q, dtype=float)
            if 3 * q[0] ** 2 - np.dot(q[1:4], q[1:4]) <= (1.0 + 1e-12) * np.dot(q, q):
                raise SingularityError(
                    "first-order retraction singular: rotation of pi/2 or more in one step; "
                    "increase N"
                )
        return _first_order_tau_inv(q)

    def dtau(self, a: Array) -> Array:
        return _first_order_dtau(a)

    def dtau_inv(self, a: Array) -> Array:
        return _first_order_dtau_inv(a)


# -------------------------------------------------------------------------------- R^n


class Translation(Retraction):
    """On (R^n, +) every retraction is the identity: tau(a) = a, dtau = I."""

    name = "translation"

    def __init__(self, group: Rn) -> None:
        self.group = group

    def tau(self, a: Array) -> Array:
        return a

    def tau_inv(self, s: Array) -> Array:
        return s

    def dtau(self, a: Array) -> Array:
        return self.group.dexp(a)

    def dtau_inv(self, a: Array) -> Array:
        return self.group.dexp_inv(a)


def retraction(name: str, group: LieGroup) -> Retraction:
    """The retraction called ``name`` (``cayley``, ``exp``, ``first_order``) on ``group``.

    On R^n all three coincide with the translation; ``first_order`` is the seeds' rule on
    SO(3) only.
    """
    if name not in RETRACTION_NAMES:
        raise ConfigError(
            f"unknown retraction {name!r}; choose one of {', '.join(RETRACTION_NAMES)}"
        )
    if isinstance(group, Rn):
        return Translation(group)
    if name == "first_order":
        if not isinstance(group, SO3Group):
            raise ConfigError(f"the first_order retraction is the seeds' rule on SO(3); on "
                              f"{group.name} choose cayley or exp")
        return FirstOrder()
    return Cayley(group) if name == "cayley" else Exp(group)


__all__ = ["Retraction", "Cayley", "Exp", "FirstOrder", "Translation", "retraction",
           "RETRACTION_NAMES"]
