"""SE(3): rigid motions as 4 x 4 homogeneous matrices ``[[R, p], [0, 1]]``.

Twists are ordered angular first, ``xi = (omega, v)``, ``hat(xi) = [[hat(omega), v], [0, 0]]``,
and the body convention is ``dg/dt = g hat(xi)``: ``dR/dt = R hat(omega)``, ``dp/dt = R v``.
Derivatives of maps f: se(3) -> SE(3) are right-trivialised, as in
:mod:`ocgroupoid.lie.retraction`: ``d/ds f(a + s b)|_0 = hat(df(a) b) f(a)``.

Node states store a pose as its unit quaternion and position (7 numbers,
:class:`QuaternionPose`). Formulas with a removable singularity at omega = 0 switch to a
Taylor branch built from a guarded argument (as in :mod:`ocgroupoid.lie.so3`), so neither
their value nor their derivative is NaN.
"""

from __future__ import annotations

import difflib
import sys
from typing import Any

import casadi as ca
import numpy as np

from ..errors import ConfigError
from . import so3
from ._backend import dual, safe_if, series, to_numpy
from .form import Side, StateForm, Steps
from .group import Array, MatrixGroup


def _homogeneous(R: Array, p: Array) -> Array:
    """``[[R, p], [0, 1]]``."""
    return ca.vertcat(ca.horzcat(R, p), ca.horzcat(ca.DM.zeros(1, 3), 1))


def _blocks(A: Array, B: Array, C: Array, D: Array) -> Array:
    """The 6 x 6 matrix ``[[A, B], [C, D]]`` of 3 x 3 blocks."""
    return ca.vertcat(ca.horzcat(A, B), ca.horzcat(C, D))


@dual
def hat(x: Array) -> Array:
    """``hat(omega, v) = [[hat(omega), v], [0, 0]]``."""
    return ca.vertcat(ca.horzcat(so3.hat(x[:3]), x[3:6]), ca.DM.zeros(1, 4))


@dual
def vee(X: Array) -> Array:
    """Inverse of ``hat``: (vee(X[:3, :3]), X[:3, 3])."""
    return ca.vertcat(so3.vee(X[:3, :3]), X[:3, 3])


@dual
def exp(x: Array) -> Array:
    """``exp(hat(omega, v)) = [[exp(hat(omega)), J(omega) v], [0, 1]]``, J the left Jacobian
    of SO(3) (:func:`ocgroupoid.lie.so3.dexp`)."""
    w = x[:3]
    return _homogeneous(so3.exp(w), ca.mtimes(so3.dexp(w), x[3:6]))


@dual
def _twist(w: Array, p: Array) -> Array:
    return ca.vertcat(w, ca.mtimes(so3.dexp_inv(w), p))


def log(g: Array) -> Array:
    """The principal logarithm ``(omega, v) = (log R, J(omega)^{-1} p)``, rotation angle in
    [0, pi] (every angle on NumPy input, below pi on graphs, as :func:`so3.log`)."""
    return _twist(so3.log(g[:3, :3]), g[:3, 3])


@dual
def inverse(g: Array) -> Array:
    """``[[R^T, -R^T p], [0, 1]]``."""
    Rt = g[:3, :3].T
    return _homogeneous(Rt, -ca.mtimes(Rt, g[:3, 3]))


@dual
def Ad(g: Array) -> Array:
    """``Ad_g = [[R, 0], [hat(p) R, R]]``: ``g hat(xi) g^{-1} = hat(Ad_g xi)``."""
    R = g[:3, :3]
    return _blocks(R, ca.DM.zeros(3, 3), ca.mtimes(so3.hat(g[:3, 3]), R), R)


@dual
def ad(x: Array) -> Array:
    """``ad_(omega, v) = [[hat(omega), 0], [hat(v), hat(omega)]]``: the bracket
    ``[xi, eta] = (omega x eta_w, omega x eta_v - eta_w x v)``."""
    W = so3.hat(x[:3])
    return _blocks(W, ca.DM.zeros(3, 3), so3.hat(x[3:6]), W)


# ------------------------------------------------------------ left Jacobian of exp


# Taylor coefficients in t^2 (7 terms: exact to 1e-16 below _SERIES)
_C1 = (1 / 6, -1 / 120, 1 / 5040, -1 / 362880, 1 / 39916800, -1 / 6227020800,
       1 / 1307674368000)  # (t - sin t)/t^3 = sum (-1)^k t^2k/(2k + 3)!
_C2 = (1 / 24, -1 / 720, 1 / 40320, -1 / 3628800, 1 / 479001600, -1 / 87178291200,
       1 / 20922789888000)  # (t^2 + 2 cos t - 2)/(2 t^4) = sum (-1)^k t^2k/(2k + 4)!
_C3 = (1 / 120, -1 / 2520, 1 / 120960, -1 / 9979200, 1 / 1245404160, -1 / 217945728000,
       1 / 50812489728000)  # (2t - 3 sin t + t cos t)/(2 t^5) = sum (-1)^k (k+1)/(2k+5)! t^2k
_SERIES = 0.3


def _q_coefficients(theta2: Array) -> tuple[Array, Array, Array]:
    """``(t - sin t)/t^3``, ``(t^2 + 2 cos t - 2)/(2 t^4)`` and
    ``(2 t - 3 sin t + t cos t)/(2 t^5)`` at t^2 = theta2, NaN-free at 0. The exact forms
    cancel badly near 0, so the series take over up to t^2 = 0.3 (to 1e-13 everywhere)."""
    small = theta2 < _SERIES
    safe = safe_if(small, 1.0, theta2)
    t = ca.sqrt(safe)
    s, c = ca.sin(t), ca.cos(t)
    return (safe_if(small, series(theta2, _C1), (t - s) / (t * safe)),
            safe_if(small, series(theta2, _C2), (safe + 2 * c - 2) / (2 * safe**2)),
            safe_if(small, series(theta2, _C3), (2 * t - 3 * s + t * c) / (2 * t * safe**2)))


@dual
def q_matrix(x: Array) -> Array:
    """Barfoot's Q(omega, v), the lower-left block of the left Jacobian (Barfoot, State
    Estimation for Robotics, with rho = v, phi = omega):

        Q = V/2 + c1 (W V + V W + W V W) + c2 (W^2 V + V W^2 - 3 W V W)
            + c3 (W V W^2 + W^2 V W),        W = hat(omega), V = hat(v),

    c1..c3 of :func:`_q_coefficients`."""
    W, V = so3.hat(x[:3]), so3.hat(x[3:6])
    c1, c2, c3 = _q_coefficients(ca.dot(x[:3], x[:3]))
    WV, VW, W2 = ca.mtimes(W, V), ca.mtimes(V, W), ca.mtimes(W, W)
    WVW = ca.mtimes(WV, W)
    return (V / 2 + c1 * (WV + VW + WVW) + c2 * (ca.mtimes(W2, V) + ca.mtimes(V, W2) - 3 * WVW)  # type: ignore[operator]  # Array = Any (lie/group.py)
            + c3 * (ca.mtimes(WVW, W) + ca.mtimes(W2, VW)))


@dual
def dexp(x: Array) -> Array:
    """Left Jacobian ``[[J, 0], [Q, J]]`` (J = so3.dexp(omega), Q = :func:`q_matrix`)."""
    J = so3.dexp(x[:3])
    return _blocks(J, ca.DM.zeros(3, 3), q_matrix(x), J)


@dual
def dexp_inv(x: Array) -> Array:
    """Its inverse ``[[J^{-1}, 0], [-J^{-1} Q J^{-1}, J^{-1}]]``."""
    Ji = so3.dexp_inv(x[:3])
    return _blocks(Ji, ca.DM.zeros(3, 3), -ca.mtimes(Ji, ca.mtimes(q_matrix(x), Ji)), Ji)  # type: ignore[operator]  # Array = Any (lie/group.py)


# ------------------------------------------------------------------------ Cayley map


@dual
def cay(x: Array) -> Array:
    """``(I - hat(xi)/2)^{-1} (I + hat(xi)/2) = [[cay(omega), (I - hat(omega)/2)^{-1} v],
    [0, 1]]`` (Kobilarov & Marsden 2011)."""
    w = x[:3]
    return _homogeneous(so3.cay(w), ca.mtimes(so3.half_cay_inv(w), x[3:6]))


@dual
def _cay_inv_translation(w: Array, p: Array) -> Array:
    return ca.vertcat(w, p - ca.cross(w, p) / 2)


def cay_inv(g: Array) -> Array:
    """``omega = cay^{-1}(R)``, ``v = (I - hat(omega)/2) p``; a SingularityError on NumPy
    input at a rotation of pi."""
    return _cay_inv_translation(so3.cay_inv(g[:3, :3]), g[:3, 3])


@dual
def dcay(x: Array) -> Array:
    """``[[dcay(omega), 0], [hat(v) dcay(omega)/2, (I - hat(omega)/2)^{-1}]]``, the inverse
    of :func:`dcay_inv`."""
    w = x[:3]
    D = so3.dcay(w)
    return _blocks(D, ca.DM.zeros(3, 3), ca.mtimes(so3.hat(x[3:6]), D) / 2,  # type: ignore[operator]  # Array = Any (lie/group.py)
                   so3.half_cay_inv(w))


@dual
def dcay_inv(x: Array) -> Array:
    """``[[I - W/2 + w w^T/4, 0], [-(I - W/2) hat(v)/2, I - W/2]]``, W = hat(omega)
    (Kobilarov & Marsden 2011, verified by hand and by tests): the vee of
    ``(I - hat(xi)/2) hat(eta) (I + hat(xi)/2)``."""
    w = x[:3]
    M = ca.DM.eye(3) - so3.hat(w) / 2
    return _blocks(so3.dcay_inv(w), ca.DM.zeros(3, 3), -ca.mtimes(M, so3.hat(x[3:6])) / 2, M)


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
        wrong = [k for k in v if k not in _KEYS]
        if wrong or not v:
            close = difflib.get_close_matches(str(wrong[0]), _KEYS, 1) if wrong else []
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ConfigError(f"a pose is {POSE_FORMS}; got {v!r}{hint}")
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


# ------------------------------------------------------------------- stored poses


@dual
def _compose(a: Array, b: Array) -> Array:
    return ca.vertcat(so3.quat_multiply(a[:4], b[:4]),
                      a[4:7] + ca.mtimes(so3.quat_to_matrix(a[:4]), b[4:7]))


@dual
def _inverse(a: Array) -> Array:
    return ca.vertcat(so3.quat_conjugate(a[:4]),
                      -ca.mtimes(so3.quat_to_matrix(a[:4]).T, a[4:7]))


@dual
def _exp(x: Array) -> Array:
    w = x[:3]
    return ca.vertcat(so3.quat_exp(w), ca.mtimes(so3.dexp(w), x[3:6]))


@dual
def _log(s: Array) -> Array:
    return _twist(so3.quat_log(s[:4]), s[4:7])


@dual
def _cay(x: Array) -> Array:
    w = x[:3]
    return ca.vertcat(so3.quat_cay(w), ca.mtimes(so3.half_cay_inv(w), x[3:6]))


@dual
def _cay_inv(s: Array) -> Array:
    return _cay_inv_translation(so3.quat_cay_inv(s[:4]), s[4:7])


@dual
def _body_rate(s: Array, y: Array) -> Array:
    return ca.vertcat(so3.quat_multiply(s[:4], ca.vertcat(0, y[:3])) / 2,
                      ca.mtimes(so3.quat_to_matrix(s[:4]), y[3:6]))


@dual
def _spatial_rate(s: Array, y: Array) -> Array:
    return ca.vertcat(so3.quat_multiply(ca.vertcat(0, y[:3]), s[:4]) / 2,
                      ca.cross(y[:3], s[4:7]) + y[3:6])


@dual
def _chart(e: Array) -> Array:
    return ca.vertcat(2 * e[1:4] / e[0], e[4:7])


@dual
def _normalise(x: Array) -> Array:
    return ca.vertcat(so3.quat_normalise(x[:4]), x[4:7])


@dual
def _matrix(s: Array) -> Array:
    return _homogeneous(so3.quat_to_matrix(s[:4]), s[4:7])


class QuaternionPose(StateForm):
    """SE(3) stored as (q, p): unit quaternion w x y z and position x y z, 7 numbers for 6
    degrees of freedom; ``(q1, p1)(q2, p2) = (q1 q2, p1 + R(q1) p2)``. Shown as the 4 x 4
    matrix."""

    size = 7
    manifold = "SE(3)"
    kind = "pose"
    meaning = "unit quaternion w x y z then position x y z (quaternion normalised; sign free)"
    shown_shape = (4, 4)

    def compose(self, a: Array, b: Array) -> Array:
        return _compose(a, b)

    def inverse(self, a: Array) -> Array:
        """``(q^*, -R(q)^T p)``."""
        return _inverse(a)

    def exp(self, x: Array) -> Array:
        """``(quat_exp(omega), J(omega) v)``."""
        return _exp(x)

    def log(self, s: Array) -> Array:
        """``(quat_log(q), J(omega)^{-1} p)``."""
        return _log(s)

    def cay(self, x: Array) -> Array:
        """``((1, omega/2)/sqrt(1 + |omega|^2/4), (I - hat(omega)/2)^{-1} v)``."""
        return _cay(x)

    def cay_inv(self, s: Array) -> Array:
        """``omega = 2 q_v/q_w``, ``v = (I - hat(omega)/2) p``."""
        return _cay_inv(s)

    def body_rate(self, s: Array, y: Array) -> Array:
        """``(q (0, omega)/2, R(q) v)``."""
        return _body_rate(s, y)

    def spatial_rate(self, s: Array, y: Array) -> Array:
        """``((0, omega) q/2, omega x p + v)``."""
        return _spatial_rate(s, y)

    def chart(self, e: Array) -> Array:
        """``(2 e_v/e_w, e_p)``: Cayley coordinates of the relative rotation and the relative
        position, zero only at the identity."""
        return _chart(e)

    def normalise(self, x: Array) -> Array:
        return _normalise(x)

    def invalid(self, x: Array) -> Array:
        return ca.norm_2(x[:4]) < 1e-12

    def matrix(self, s: Array) -> Array:
        return _matrix(s)

    def of_matrix(self, M: Any) -> np.ndarray:
        M = np.asarray(M, dtype=float)
        return np.concatenate([so3.to_quaternion(M[:3, :3]), M[:3, 3]])

    def parse(self, value: Any) -> np.ndarray:
        """A pose in any form of :func:`from_spec` -> (q, p) with w >= 0."""
        return self.of_matrix(from_spec(value))

    def paths(self, delta: Array, N: int, side: Side) -> Steps:
        """The constant twist ``log(delta)/N`` per step (a screw motion), and the long way
        round: the rotation turns the other way about the same axis at a constant rate
        while the relative position moves along the straight line to its end, the steps
        ``between(P_k, P_{k+1})`` of the partial products ``P_k = (quat_exp(k w'/N),
        k p/N)``, ``w' = axis (angle - 2 pi)``."""
        v = self.log(delta)
        angle = ca.norm_2(v[:3])
        turns = angle > 1e-9
        axis = ca.if_else(turns, v[:3] / safe_if(turns, angle, 1.0), ca.DM([1.0, 0.0, 0.0]))
        back = axis * (angle - 2 * np.pi)
        P = [ca.vertcat(so3.quat_exp(back * k / N), delta[4:7] * k / N) for k in range(N + 1)]
        return [("geodesic", [self.exp(v / N)]),
                ("long way round", [self.between(P[k], P[k + 1], side) for k in range(N)])]


class _SE3(MatrixGroup):
    """The rigid motions; elements are 4 x 4 matrices, stored as quaternion and position."""

    name = "SE3"
    dim = 6
    turning = slice(0, 3)
    formulas = sys.modules[__name__]
    form = QuaternionPose()

    def identity(self) -> np.ndarray:
        return np.eye(4)

    def distance_from_group(self, g: Array) -> float:
        """``|R^T R - I| + |last row - (0, 0, 0, 1)|``."""
        g = np.asarray(to_numpy(g), dtype=float)
        R = g[:3, :3]
        return float(np.linalg.norm(R.T @ R - np.eye(3))
                     + np.linalg.norm(g[3] - [0.0, 0.0, 0.0, 1.0]))

    def sample(self, rng: np.random.Generator) -> np.ndarray:
        """A Haar-uniform rotation and a standard normal position."""
        return np.asarray(_homogeneous(so3.SO3.sample(rng), rng.normal(size=3)))


SE3 = _SE3()
