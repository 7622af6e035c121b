"""Retractions tau: g -> G with tau(0) = e and tau(a) tau(-a) = e.

Each retraction has ``tau``, ``tau_inv`` and the right-trivialised derivative ``dtau`` with
its inverse ``dtau_inv`` (seed 000, Appendix D, eq. 64; seed 001, §6.1):

    d/ds tau(a + s b)|_{s=0} = hat(dtau(a) b) tau(a).

The left-trivialised ones follow from tau(-a) = tau(a)^{-1}:
``tau(a)^{-1} d tau(a)[b] = hat(dtau(-a) b)``, exposed as ``dtau_left``/``dtau_inv_left``.

Singularities are reported, not hidden: on NumPy input ``tau_inv`` raises
:class:`SingularityError` with the fix (a smaller step, i.e. a larger N).
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import casadi as ca
import numpy as np

from ..errors import ConfigError, SingularityError
from . import so3
from ._backend import dual, is_symbolic, safe_if
from .group import Array, LieGroup
from .rn import Rn

RETRACTION_NAMES = ("cayley", "exp", "first_order")


class Retraction(ABC):
    """A local diffeomorphism tau: g -> G around 0, with trivialised derivatives."""

    name: str
    group: LieGroup
    #: the step norm |a| near which the retraction degenerates (quoted by hints)
    step_limit: float = float("inf")

    @abstractmethod
    def tau(self, a: Array) -> Array:
        """The group element tau(a)."""

    @abstractmethod
    def tau_inv(self, g: Array) -> Array:
        """The algebra element a with tau(a) = g."""

    def tau_quat(self, a: Array) -> Array:
        """The unit quaternion (w, x, y, z) of tau(a), for groups that have one (SO(3))."""
        raise NotImplementedError(f"{self.name} on {self.group.name} has no quaternion form")

    def tau_inv_quat(self, q: Array) -> Array:
        """``tau_inv`` of the rotation of a unit quaternion (either sign), on graphs too."""
        raise NotImplementedError(f"{self.name} on {self.group.name} has no quaternion form")

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

    def __repr__(self) -> str:
        return f"{self.name}({self.group.name})"


# ------------------------------------------------------------------------------- SO(3)


@dual
def cay(a: Array) -> Array:
    """Cayley map on so(3) (eq. 63): ``I + 4/(4 + |a|^2) (hat(a) + hat(a)^2/2)``."""
    A = so3.hat(a)
    return ca.DM.eye(3) + 4 / (4 + ca.dot(a, a)) * (A + ca.mtimes(A, A) / 2)


@dual
def _cay_quat(a: Array) -> Array:
    return ca.vertcat(1, a / 2) / ca.sqrt(1 + ca.dot(a, a) / 4)


@dual
def _cay_inv_quat(q: Array) -> Array:
    return 2 * q[1:4] / q[0]


@dual
def _cay_inv(R: Array) -> Array:
    return 2 * so3.vee_skew(R) * 2 / (1 + ca.trace(R))


@dual
def dcay(a: Array) -> Array:
    """Right-trivialised derivative of cay (eq. 64): ``2/(4 + |a|^2) (2 I + hat(a))``."""
    return 2 / (4 + ca.dot(a, a)) * (2 * ca.DM.eye(3) + so3.hat(a))


@dual
def dcay_inv(a: Array) -> Array:
    """Inverse of ``dcay`` (eq. 64): ``I - hat(a)/2 + a a^T/4``."""
    return ca.DM.eye(3) - so3.hat(a) / 2 + ca.mtimes(a, a.T) / 4


class Cayley(Retraction):
    """cay(a) = (I - hat(a)/2)^{-1} (I + hat(a)/2); rational, singular only at angle pi."""

    name = "cayley"
    group = so3.SO3
    step_limit = float(np.pi)

    def tau(self, a: Array) -> Array:
        return cay(a)

    def tau_inv(self, g: Array) -> Array:
        """``cay^{-1}(R) = 4 vee_skew(R) / (1 + tr R)``; undefined for a rotation of pi."""
        if not is_symbolic(g):
            g = np.asarray(g, dtype=float)
            if 1.0 + np.trace(g) < 1e-10:
                raise SingularityError(
                    "Cayley map singular: rotation of pi in one step; increase N "
                    f"(1 + tr R = {1.0 + np.trace(g):.2e})"
                )
        return _cay_inv(g)

    def tau_quat(self, a: Array) -> Array:
        """``(1, a/2)/sqrt(1 + |a|^2/4)``."""
        return _cay_quat(a)

    def tau_inv_quat(self, q: Array) -> Array:
        """``2 q_v / q_w``."""
        return _cay_inv_quat(q)

    def dtau(self, a: Array) -> Array:
        return dcay(a)

    def dtau_inv(self, a: Array) -> Array:
        return dcay_inv(a)


class Exp(Retraction):
    """The exponential map; ``dtau`` is the left Jacobian of SO(3)."""

    name = "exp"
    group = so3.SO3
    step_limit = float(np.pi)

    def tau(self, a: Array) -> Array:
        return so3.exp(a)

    def tau_inv(self, g: Array) -> Array:
        return so3.log(g)

    def tau_quat(self, a: Array) -> Array:
        """``(cos(t/2), sin(t/2) a/t)``, t = |a|."""
        return so3.quat_exp(a)

    def tau_inv_quat(self, q: Array) -> Array:
        return so3.quat_log(q)

    def dtau(self, a: Array) -> Array:
        return so3.dexp(a)

    def dtau_inv(self, a: Array) -> Array:
        return so3.dexp_inv(a)


def _asin_ratio(x2: Array) -> tuple[Array, Array]:
    """s = asin(x)/x and t = s'(x)/x at x^2 = x2 (x = |a| < 1), NaN-free at 0."""
    small = x2 < 1e-3
    safe = safe_if(small, 1.0, x2)
    x = ca.sqrt(safe)
    s_exact = ca.asin(x) / x
    s = safe_if(small, 1 + x2 / 6 + 3 * x2**2 / 40 + 5 * x2**3 / 112 + 35 * x2**4 / 1152, s_exact)
    t = safe_if(
        small,
        1 / 3 + 3 * x2 / 10 + 15 * x2**2 / 56 + 35 * x2**3 / 144 + 315 * x2**4 / 1408,
        (1 / ca.sqrt(1 - safe) - s_exact) / safe,
    )
    return s, t


@dual
def _first_order_tau(a: Array) -> Array:
    c = ca.sqrt(1 - ca.dot(a, a))
    return c * ca.DM.eye(3) + so3.hat(a) + ca.mtimes(a, a.T) / (1 + c)


@dual
def _first_order_quat(a: Array) -> Array:
    w = ca.sqrt((1 + ca.sqrt(1 - ca.dot(a, a))) / 2)  # cos(angle/2), angle = asin|a|
    return ca.vertcat(w, a / (2 * w))


@dual
def _first_order_inv_quat(q: Array) -> Array:
    return 2 * q[0] * q[1:4] / ca.dot(q, q)


@dual
def _first_order_dtau(a: Array) -> Array:
    s, t = _asin_ratio(ca.dot(a, a))
    return ca.mtimes(so3.dexp(s * a), s * ca.DM.eye(3) + t * ca.mtimes(a, a.T))


@dual
def _first_order_dtau_inv(a: Array) -> Array:
    x2 = ca.dot(a, a)
    s, t = _asin_ratio(x2)
    D_inv = (ca.DM.eye(3) - t / (s + t * x2) * ca.mtimes(a, a.T)) / s
    return ca.mtimes(D_inv, so3.dexp_inv(s * a))


class FirstOrder(Retraction):
    """The seeds' first-order rule ``g ~ I + h xi`` read out by the skew part (seed 001, eq. 8).

    ``tau_inv(R) = vee_skew(R)`` (= sin(angle) * axis); its inverse is the rotation whose
    skew part is hat(a): ``tau(a) = c I + hat(a) + a a^T/(1 + c)``, ``c = sqrt(1 - |a|^2)``.
    Defined for steps below pi/2 (|a| < 1).
    """

    name = "first_order"
    group = so3.SO3
    step_limit = float(np.pi / 2)

    def tau(self, a: Array) -> Array:
        if not is_symbolic(a) and float(np.dot(np.ravel(a), np.ravel(a))) >= 1.0:
            raise SingularityError(
                "first-order retraction undefined: |h xi| >= 1 (a rotation of pi/2 or more in "
                "one step); increase N"
            )
        return _first_order_tau(a)

    def tau_inv(self, g: Array) -> Array:
        if not is_symbolic(g):
            g = np.asarray(g, dtype=float)
            if np.trace(g) <= 1.0 + 1e-12:
                raise SingularityError(
                    "first-order retraction singular: rotation of pi/2 or more in one step; "
                    "increase N"
                )
        return so3.vee_skew(g)

    def tau_quat(self, a: Array) -> Array:
        """``(w, a/(2w))`` with ``w = cos(angle/2) = sqrt((1 + sqrt(1 - |a|^2))/2)``."""
        return _first_order_quat(a)

    def tau_inv_quat(self, q: Array) -> Array:
        """``vee_skew(R(q)) = 2 q_w q_v / |q|^2`` (sin(angle) times the axis)."""
        return _first_order_inv_quat(q)

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

    def tau_inv(self, g: Array) -> Array:
        return g

    def dtau(self, a: Array) -> Array:
        return ca.DM.eye(self.group.dim) if is_symbolic(a) else np.eye(self.group.dim)

    def dtau_inv(self, a: Array) -> Array:
        return self.dtau(a)


def retraction(name: str, group: LieGroup) -> Retraction:
    """The retraction called ``name`` (``cayley``, ``exp``, ``first_order``) on ``group``.

    On R^n all three coincide with the translation.
    """
    if name not in RETRACTION_NAMES:
        raise ConfigError(
            f"unknown retraction {name!r}; choose one of {', '.join(RETRACTION_NAMES)}"
        )
    if isinstance(group, Rn):
        return Translation(group)
    if group is not so3.SO3:
        raise ConfigError(f"no retraction {name!r} is implemented for {group.name}")
    return {"cayley": Cayley, "exp": Exp, "first_order": FirstOrder}[name]()


__all__ = ["Retraction", "Cayley", "Exp", "FirstOrder", "Translation", "retraction", "cay",
           "dcay", "dcay_inv", "RETRACTION_NAMES"]
