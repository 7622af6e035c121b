"""SE(3), its elements held as (q, p): a unit quaternion w x y z and a position x y z, and the
pose constructors used by problem files.

The group matrix is ``[[R(q), p], [0, 1]]``; ``(q1, p1)(q2, p2) = (q1 q2, p1 + R(q1) p2)``.
Twists are ordered angular first, ``xi = (omega, v)``, ``hat(xi) = [[hat(omega), v], [0, 0]]``,
and the body convention is ``dg/dt = g hat(xi)``: ``dR/dt = R hat(omega)``, ``dp/dt = R v``.
Formulas with a removable singularity at omega = 0 switch to a Taylor branch built from a
guarded argument (as in :mod:`ocgroupoid.lie.so3`), so neither their value nor their
derivative is NaN.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import ConfigError
from . import so3
from ._backend import dual, guarded, safe_if, to_numpy
from .group import Array, LieGroup, Side, Steps
from .so3 import SO3


def _homogeneous(R: Array, p: Array) -> Array:
    """``[[R, p], [0, 1]]``."""
    return ca.vertcat(ca.horzcat(R, p), ca.horzcat(ca.DM.zeros(1, 3), 1))


def _blocks(A: Array, B: Array, C: Array, D: Array) -> Array:
    """The 6 x 6 matrix ``[[A, B], [C, D]]`` of 3 x 3 blocks."""
    return ca.vertcat(ca.horzcat(A, B), ca.horzcat(C, D))


# Taylor coefficients in t^2 (7 terms: exact to 1e-16 below _SERIES)
_C1 = (1 / 6, -1 / 120, 1 / 5040, -1 / 362880, 1 / 39916800, -1 / 6227020800,
       1 / 1307674368000)  # (t - sin t)/t^3 = sum (-1)^k t^2k/(2k + 3)!
_C2 = (1 / 24, -1 / 720, 1 / 40320, -1 / 3628800, 1 / 479001600, -1 / 87178291200,
       1 / 20922789888000)  # (t^2 + 2 cos t - 2)/(2 t^4) = sum (-1)^k t^2k/(2k + 4)!
_C3 = (1 / 120, -1 / 2520, 1 / 120960, -1 / 9979200, 1 / 1245404160, -1 / 217945728000,
       1 / 50812489728000)  # (2t - 3 sin t + t cos t)/(2 t^5) = sum (-1)^k (k+1)/(2k+5)! t^2k
_SERIES = 0.3


def _q_coefficients(t2: Array) -> tuple[Array, Array, Array]:
    """``(t - sin t)/t^3``, ``(t^2 + 2 cos t - 2)/(2 t^4)`` and
    ``(2 t - 3 sin t + t cos t)/(2 t^5)`` at t^2 = t2, NaN-free at 0. The exact forms
    cancel badly near 0, so the series take over up to t^2 = 0.3 (to 1e-13 everywhere)."""
    return (guarded(t2, _SERIES, _C1, lambda t, t2: (t - ca.sin(t)) / (t * t2)),
            guarded(t2, _SERIES, _C2, lambda t, t2: (t2 + 2 * ca.cos(t) - 2) / (2 * t2**2)),
            guarded(t2, _SERIES, _C3,
                    lambda t, t2: (2 * t - 3 * ca.sin(t) + t * ca.cos(t)) / (2 * t * t2**2)))


@dual
def _half_cay_inv(a: Array) -> Array:
    """``(I - hat(a)/2)^{-1} = I + (B + B^2)/(1 + |a|^2/4)``, B = hat(a)/2 (as B^3 =
    -|a|^2/4 B): the factor that ``cay`` applies to the translation."""
    B = SO3.hat(a) / 2
    return ca.DM.eye(3) + (B + ca.mtimes(B, B)) / (1 + ca.dot(a, a) / 4)


class SE3Group(LieGroup):
    """The rigid motions on (q, p): 7 numbers for 6 degrees of freedom, shown as the 4 x 4
    matrix."""

    name = "SE3"
    dim = 6
    size = 7
    angular = slice(0, 3)
    manifold = "SE(3)"
    kind = "pose"
    meaning = "unit quaternion w x y z then position x y z (quaternion normalised; sign free)"
    matrix_shape = (4, 4)

    def identity(self) -> np.ndarray:
        return np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])

    @dual
    def compose(self, a: Array, b: Array) -> Array:
        """``(q1 q2, p1 + R(q1) p2)``."""
        return ca.vertcat(SO3.compose(a[:4], b[:4]), a[4:7] + ca.mtimes(SO3.matrix(a[:4]), b[4:7]))

    @dual
    def inverse(self, a: Array) -> Array:
        """``(q^*, -R(q)^T p)``."""
        return ca.vertcat(SO3.inverse(a[:4]), -ca.mtimes(SO3.matrix(a[:4]).T, a[4:7]))

    @dual
    def exp(self, x: Array) -> Array:
        """``(exp(omega), J(omega) v)``, J the left Jacobian of SO(3)."""
        w = x[:3]
        return ca.vertcat(SO3.exp(w), ca.mtimes(SO3.dexp(w), x[3:6]))

    @dual
    def log(self, s: Array) -> Array:
        """``(omega, J(omega)^{-1} p)``, omega = log q."""
        w = SO3.log(s[:4])
        return ca.vertcat(w, ca.mtimes(SO3.dexp_inv(w), s[4:7]))

    @dual
    def cay(self, x: Array) -> Array:
        """``(cay(omega), (I - hat(omega)/2)^{-1} v)``: the blocks of ``(I - hat(xi)/2)^{-1}
        (I + hat(xi)/2)`` (Kobilarov & Marsden 2011)."""
        w = x[:3]
        return ca.vertcat(SO3.cay(w), ca.mtimes(_half_cay_inv(w), x[3:6]))

    def cay_inv(self, s: Array) -> Array:
        """``omega = 2 q_v/q_w``, ``v = (I - hat(omega)/2) p``; a SingularityError on NumPy
        input at a rotation of pi."""
        return self._cay_inv(SO3.cay_inv(s[:4]), s[4:7])

    @dual
    def _cay_inv(self, w: Array, p: Array) -> Array:
        return ca.vertcat(w, p - ca.cross(w, p) / 2)

    @dual
    def hat(self, x: Array) -> Array:
        """``hat(omega, v) = [[hat(omega), v], [0, 0]]``."""
        return ca.vertcat(ca.horzcat(SO3.hat(x[:3]), x[3:6]), ca.DM.zeros(1, 4))

    @dual
    def vee(self, X: Array) -> Array:
        """Inverse of ``hat``: (vee(X[:3, :3]), X[:3, 3])."""
        return ca.vertcat(SO3.vee(X[:3, :3]), X[:3, 3])

    @dual
    def Ad(self, s: Array) -> Array:
        """``Ad_g = [[R, 0], [hat(p) R, R]]``: ``g hat(xi) g^{-1} = hat(Ad_g xi)``."""
        R = SO3.matrix(s[:4])
        return _blocks(R, ca.DM.zeros(3, 3), ca.mtimes(SO3.hat(s[4:7]), R), R)

    @dual
    def ad(self, x: Array) -> Array:
        """``ad_(omega, v) = [[hat(omega), 0], [hat(v), hat(omega)]]``: the bracket
        ``[xi, eta] = (omega x eta_w, omega x eta_v - eta_w x v)``."""
        W = SO3.hat(x[:3])
        return _blocks(W, ca.DM.zeros(3, 3), SO3.hat(x[3:6]), W)

    @dual
    def q_matrix(self, x: Array) -> Array:
        """Barfoot's Q(omega, v), the lower-left block of the left Jacobian (Barfoot, State
        Estimation for Robotics, with rho = v, phi = omega):

            Q = V/2 + c1 (W V + V W + W V W) + c2 (W^2 V + V W^2 - 3 W V W)
                + c3 (W V W^2 + W^2 V W),        W = hat(omega), V = hat(v),

        c1..c3 of :func:`_q_coefficients`."""
        W, V = SO3.hat(x[:3]), SO3.hat(x[3:6])
        c1, c2, c3 = _q_coefficients(ca.dot(x[:3], x[:3]))
        WV, VW, W2 = ca.mtimes(W, V), ca.mtimes(V, W), ca.mtimes(W, W)
        WVW = ca.mtimes(WV, W)
        return (V / 2 + c1 * (WV + VW + WVW) + c2 * (ca.mtimes(W2, V) + ca.mtimes(V, W2) - 3 * WVW)  # type: ignore[operator]  # Array = Any (lie/group.py)
                + c3 * (ca.mtimes(WVW, W) + ca.mtimes(W2, VW)))

    @dual
    def dexp(self, x: Array) -> Array:
        """Left Jacobian ``[[J, 0], [Q, J]]`` (J that of SO(3), Q = :meth:`q_matrix`)."""
        J = SO3.dexp(x[:3])
        return _blocks(J, ca.DM.zeros(3, 3), self.q_matrix(x), J)

    @dual
    def dexp_inv(self, x: Array) -> Array:
        """Its inverse ``[[J^{-1}, 0], [-J^{-1} Q J^{-1}, J^{-1}]]``."""
        Ji = SO3.dexp_inv(x[:3])
        return _blocks(Ji, ca.DM.zeros(3, 3), -ca.mtimes(Ji, ca.mtimes(self.q_matrix(x), Ji)), Ji)  # type: ignore[operator]  # Array = Any (lie/group.py)

    @dual
    def dcay(self, x: Array) -> Array:
        """``[[dcay(omega), 0], [hat(v) dcay(omega)/2, (I - hat(omega)/2)^{-1}]]``, the inverse
        of :meth:`dcay_inv`."""
        w = x[:3]
        D = SO3.dcay(w)
        return _blocks(D, ca.DM.zeros(3, 3), ca.mtimes(SO3.hat(x[3:6]), D) / 2,  # type: ignore[operator]  # Array = Any (lie/group.py)
                       _half_cay_inv(w))

    @dual
    def dcay_inv(self, x: Array) -> Array:
        """``[[I - W/2 + w w^T/4, 0], [-(I - W/2) hat(v)/2, I - W/2]]``, W = hat(omega)
        (Kobilarov & Marsden 2011, verified by hand and by tests): the vee of
        ``(I - hat(xi)/2) hat(eta) (I + hat(xi)/2)``."""
        w = x[:3]
        M = ca.DM.eye(3) - SO3.hat(w) / 2
        return _blocks(SO3.dcay_inv(w), ca.DM.zeros(3, 3), -ca.mtimes(M, SO3.hat(x[3:6])) / 2, M)

    @dual
    def body_rate(self, s: Array, y: Array) -> Array:
        """``(q (0, omega)/2, R(q) v)``."""
        return ca.vertcat(SO3.body_rate(s[:4], y[:3]), ca.mtimes(SO3.matrix(s[:4]), y[3:6]))

    @dual
    def spatial_rate(self, s: Array, y: Array) -> Array:
        """``((0, omega) q/2, omega x p + v)``."""
        return ca.vertcat(SO3.spatial_rate(s[:4], y[:3]), ca.cross(y[:3], s[4:7]) + y[3:6])

    @dual
    def chart(self, e: Array) -> Array:
        """``(2 e_v/e_w, e_p)``: Cayley coordinates of the relative rotation and the relative
        position, zero only at the identity."""
        return ca.vertcat(SO3.chart(e[:4]), e[4:7])

    @dual
    def normalise(self, x: Array) -> Array:
        return ca.vertcat(SO3.normalise(x[:4]), x[4:7])

    def invalid(self, x: Array) -> Array:
        return SO3.invalid(x[:4])

    @dual
    def matrix(self, s: Array) -> Array:
        return _homogeneous(SO3.matrix(s[:4]), s[4:7])

    def of_matrix(self, M: Any) -> np.ndarray:
        M = np.asarray(M, dtype=float)
        return np.concatenate([SO3.of_matrix(M[:3, :3]), M[:3, 3]])

    def parse(self, value: Any) -> np.ndarray:
        """A pose in any form of :func:`from_spec` -> (q, p) with w >= 0."""
        return self.of_matrix(from_spec(value))

    def detours(self, delta: Array, v: Array, N: int, side: Side) -> Steps:
        """The long way round: the rotation turns the other way about the same axis at a
        constant rate while the relative position moves along the straight line to its end,
        the steps ``between(P_k, P_{k+1})`` of the partial products ``P_k = (exp(k w'/N),
        k p/N)``, ``w' = axis (angle - 2 pi)``."""
        angle = ca.norm_2(v[:3])
        turns = angle > 1e-9
        axis = ca.if_else(turns, v[:3] / safe_if(turns, angle, 1.0), ca.DM([1.0, 0.0, 0.0]))
        back = axis * (angle - 2 * np.pi)
        P = [ca.vertcat(SO3.exp(back * k / N), delta[4:7] * k / N) for k in range(N + 1)]
        return [("long way round", [self.between(P[k], P[k + 1], side) for k in range(N)])]

    def sample(self, rng: np.random.Generator) -> np.ndarray:
        """A Haar-uniform rotation and a standard normal position."""
        return np.concatenate([SO3.sample(rng), rng.normal(size=3)])

    def distance_from_group(self, M: Any) -> Any:
        """``|R^T R - I| + |last row - (0, 0, 0, 1)|`` (of each matrix of a stack)."""
        g = np.asarray(to_numpy(M), dtype=float)
        return SO3.distance_from_group(g[..., :3, :3]) + np.linalg.norm(
            g[..., 3, :] - [0.0, 0.0, 0.0, 1.0], axis=-1)


SE3 = SE3Group()

# ----------------------------------------------------------------- constructors (NumPy)


def from_matrix(M: Any, tol: float = 1e-6) -> np.ndarray:
    """A given 4 x 4 matrix, checked to be a pose (rotation block, last row 0 0 0 1)."""
    M = np.asarray(M, dtype=float)
    if M.shape != (4, 4) or not np.all(np.isfinite(M)):
        raise ConfigError(f"a pose matrix is 4 x 4 finite numbers, got shape {M.shape}")
    if np.linalg.norm(M[3] - [0.0, 0.0, 0.0, 1.0]) > tol:
        raise ConfigError(f"the last row of a pose matrix is [0, 0, 0, 1], got {M[3].tolist()}")
    return np.asarray(_homogeneous(so3.from_matrix(M[:3, :3], tol), M[:3, 3]))


POSE_FORMS = ("identity, {rotation: <rotation>, position: [x, y, z]} (either key may be left "
              "out), a 4 x 4 matrix, or 7 numbers w x y z px py pz (a quaternion and a "
              f"position); a rotation is {so3.ROTATION_FORMS}")
_KEYS = ("rotation", "position")


def from_spec(v: Any) -> np.ndarray:
    """A pose written in any documented form (:data:`POSE_FORMS`), as a checked 4 x 4 matrix."""
    if isinstance(v, str) and v == "identity":
        return np.eye(4)
    if isinstance(v, dict):
        so3.only_keys(v, _KEYS, f"a pose is {POSE_FORMS}")
        R = so3.from_spec(v.get("rotation", "identity"))
        p = so3.number_list(v.get("position", [0.0, 0.0, 0.0]), 3, "position")
        return np.asarray(_homogeneous(R, p))
    try:
        M = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"a pose is {POSE_FORMS}; got {v!r}") from None
    if M.shape == (7,) and np.all(np.isfinite(M)):
        return np.asarray(_homogeneous(so3.from_quaternion(M[:4]), M[4:]))
    if M.shape == (4, 4):
        return from_matrix(M)
    raise ConfigError(f"a pose is {POSE_FORMS}; got {v!r}")
