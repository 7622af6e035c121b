"""SE(2), its elements held as ``(w, z, x, y)``, and the planar pose constructors used by
problem files.

``(w, z) = (cos(theta/2), sin(theta/2))`` is the unit complex number of the half angle -- the
unit quaternion ``(w, 0, 0, z)`` of the rotation about z -- and ``(x, y)`` the position; the
group matrix is ``[[R(theta), p], [0, 1]]``. As for quaternions, the product of half-angle
numbers is the rotation product, their sign is free, and the Cayley coordinates ``2 z/w =
2 tan(theta/2)`` of the rotation are rational with a pole, not a root, at theta = pi; the
full-angle number ``(cos theta, sin theta)`` would need ``2 sin/(1 + cos)``, which rounding
turns into 0/0 there.

Twists are ordered angular first, ``xi = (omega, vx, vy)``,
``hat(xi) = [[omega K, v], [0, 0]]`` with ``K = [[0, -1], [1, 0]]``, and the body convention
is ``dg/dt = g hat(xi)``: ``dtheta/dt = omega``, ``dp/dt = R(theta) v``. Everything here is
the restriction of :mod:`ocgroupoid.lie.se3` to rotations about z and translations in the
xy-plane.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import ConfigError, SingularityError
from . import so3
from ._backend import dual, guarded, is_symbolic, safe_if, to_numpy
from .group import Array, LieGroup, Side, Steps

K = np.array([[0.0, -1.0], [1.0, 0.0]])  # hat of the unit rotation rate: K v = e_z x v


def _homogeneous(R: Array, p: Array) -> Array:
    """``[[R, p], [0, 1]]``."""
    return ca.vertcat(ca.horzcat(R, p), ca.horzcat(ca.DM.zeros(1, 2), 1))


def _blocks(a: Array, b: Array, C: Array, D: Array) -> Array:
    """The 3 x 3 matrix ``[[a, b], [C, D]]`` (a 1 x 1, b 1 x 2, C 2 x 1, D 2 x 2)."""
    return ca.vertcat(ca.horzcat(a, b), ca.horzcat(C, D))


def _rotation(c: Array, s: Array) -> Array:
    """``[[c, -s], [s, c]]``."""
    return ca.vertcat(ca.horzcat(c, -s), ca.horzcat(s, c))


def _spin(r: Array) -> Array:
    """The rotation matrix of the half-angle number r = (w, z): ``[[w^2 - z^2, -2 w z],
    [2 w z, w^2 - z^2]]`` (scaled by |r|^2: drift stays visible)."""
    return _rotation(r[0] ** 2 - r[1] ** 2, 2 * r[0] * r[1])


def _times(a: Array, b: Array) -> Array:
    """Complex product of (w, z) pairs."""
    return ca.vertcat(a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0])


# Taylor coefficients in t^2 (exact to 1e-16 below _SERIES)
_A = (1.0, -1 / 6, 1 / 120, -1 / 5040, 1 / 362880, -1 / 39916800,
      1 / 6227020800)  # sin t/t = sum (-1)^k t^2k/(2k + 1)!
_B = (1 / 2, -1 / 24, 1 / 720, -1 / 40320, 1 / 3628800, -1 / 479001600,
      1 / 87178291200)  # (1 - cos t)/t^2 = sum (-1)^k t^2k/(2k + 2)!
_C = (1 / 6, -1 / 120, 1 / 5040, -1 / 362880, 1 / 39916800, -1 / 6227020800,
      1 / 1307674368000)  # (t - sin t)/t^3 = sum (-1)^k t^2k/(2k + 3)!
_COT = (1.0, -1 / 12, -1 / 720, -1 / 30240, -1 / 1209600, -1 / 47900160,
        -691 / 1307674368000, -1 / 74724249600)  # (t/2) cot(t/2) = 1 - sum |B_2k| t^2k/(2k)!
_SERIES = 0.3


def _sinc(t2: Array) -> Array:
    """``sin t/t``, NaN-free at 0 (series below t^2 = 0.3, where exact forms cancel)."""
    return guarded(t2, _SERIES, _A, lambda t, t2: ca.sin(t) / t)


def _one_minus_cos(t2: Array) -> Array:
    """``(1 - cos t)/t^2``, NaN-free at 0."""
    return guarded(t2, _SERIES, _B, lambda t, t2: 2 * ca.sin(t / 2) ** 2 / t2)


def _t_minus_sin(t2: Array) -> Array:
    """``(t - sin t)/t^3``, NaN-free at 0."""
    return guarded(t2, _SERIES, _C, lambda t, t2: (t - ca.sin(t)) / (t * t2))


def _half_cot(t2: Array) -> Array:
    """``(t/2) cot(t/2) = t sin t / (4 sin(t/2)^2)``, NaN-free at 0."""
    return guarded(t2, _SERIES, _COT, lambda t, t2: t * ca.sin(t) / (4 * ca.sin(t / 2) ** 2))


def _cay_scale(w: Array) -> Array:
    """``d = 1 + omega^2/4``, the squared norm of the Cayley number (1, omega/2)."""
    return 1 + w * w / 4


@dual
def V(w: Array) -> Array:
    """``V(omega) = sin(omega)/omega I + (1 - cos omega)/omega K``: ``exp`` carries v to the
    translation ``V(omega) v`` (the left Jacobian of SO(2) acting on the plane)."""
    return _sinc(w * w) * ca.DM.eye(2) + w * _one_minus_cos(w * w) * ca.DM(K)


@dual
def V_inv(w: Array) -> Array:
    """``V(omega)^{-1} = (omega/2) cot(omega/2) I - omega/2 K``."""
    return _half_cot(w * w) * ca.DM.eye(2) - w / 2 * ca.DM(K)


@dual
def _dexp_column(x: Array) -> Array:
    """``(omega - sin omega)/omega^2 v - (1 - cos omega)/omega^2 K v``: how the translation
    of exp moves, right-trivialised, when omega does."""
    w, v = x[0], x[1:3]
    return w * _t_minus_sin(w * w) * v - _one_minus_cos(w * w) * ca.mtimes(ca.DM(K), v)


class SE2Group(LieGroup):
    """The planar rigid motions on (w, z, x, y): 4 numbers for 3 degrees of freedom (module
    docstring), shown as the 3 x 3 matrix."""

    name = "SE2"
    dim = 3
    size = 4
    angular = slice(0, 1)
    manifold = "SE(2)"
    kind = "pose"
    meaning = ("cos(a/2) sin(a/2) x y: heading a as the unit complex number of its half "
               "angle (normalised; sign free), then the position")
    matrix_shape = (3, 3)

    def identity(self) -> np.ndarray:
        return np.array([1.0, 0.0, 0.0, 0.0])

    @dual
    def compose(self, a: Array, b: Array) -> Array:
        """``(r1 r2, p1 + R(r1) p2)``, r1 r2 the complex product."""
        return ca.vertcat(_times(a, b), a[2:4] + ca.mtimes(_spin(a), b[2:4]))

    @dual
    def inverse(self, a: Array) -> Array:
        """``(conj r, -R(r)^T p)``."""
        return ca.vertcat(a[0], -a[1], -ca.mtimes(_spin(a).T, a[2:4]))

    @dual
    def exp(self, x: Array) -> Array:
        """``(cos(omega/2), sin(omega/2), V(omega) v)``."""
        return ca.vertcat(ca.cos(x[0] / 2), ca.sin(x[0] / 2), ca.mtimes(V(x[0]), x[1:3]))

    @dual
    def log(self, s: Array) -> Array:
        """``(theta, V(theta)^{-1} p)``, ``theta = 2 atan2(z, w)`` taken with w >= 0, in
        (-pi, pi]."""
        r = ca.if_else(s[0] < 0, -s[0:2], s[0:2])
        theta = 2 * ca.atan2(r[1], r[0])
        return ca.vertcat(theta, ca.mtimes(V_inv(theta), s[2:4]))

    @dual
    def cay(self, x: Array) -> Array:
        """``((1, omega/2)/sqrt(d), (I + omega K/2) v/d)``, ``d = 1 + omega^2/4``: the blocks
        of ``(I - hat(xi)/2)^{-1} (I + hat(xi)/2)``."""
        w, d = x[0], _cay_scale(x[0])
        return ca.vertcat(ca.vertcat(1, w / 2) / ca.sqrt(d),
                          ca.mtimes(ca.DM.eye(2) + w / 2 * ca.DM(K), x[1:3]) / d)

    def cay_inv(self, s: Array) -> Array:
        """``omega = 2 z/w``, ``v = (I - omega K/2) p``; at theta = pi (``2 + tr R =
        4 w^2/|r|^2 = 0``) a SingularityError on NumPy input."""
        if not is_symbolic(s):
            s = np.asarray(s, dtype=float)
            if 4 * s[0] ** 2 < 1e-10 * (s[0] ** 2 + s[1] ** 2):
                raise SingularityError("Cayley map singular: rotation of pi in one step; "
                                       "increase N")
        return self._cay_inv(s)

    @dual
    def _cay_inv(self, s: Array) -> Array:
        w = 2 * s[1] / s[0]
        return ca.vertcat(w, ca.mtimes(ca.DM.eye(2) - w / 2 * ca.DM(K), s[2:4]))

    @dual
    def hat(self, x: Array) -> Array:
        """``[[0, -omega, vx], [omega, 0, vy], [0, 0, 0]]``."""
        return ca.vertcat(ca.horzcat(0, -x[0], x[1]), ca.horzcat(x[0], 0, x[2]),
                          ca.DM.zeros(1, 3))

    @dual
    def vee(self, X: Array) -> Array:
        """Inverse of ``hat``: (X[1, 0], X[0, 2], X[1, 2])."""
        return ca.vertcat(X[1, 0], X[0, 2], X[1, 2])

    @dual
    def Ad(self, s: Array) -> Array:
        """``Ad_g = [[1, 0], [-K p, R]]``: ``g hat(xi) g^{-1} = hat(Ad_g xi)``."""
        return _blocks(1, ca.DM.zeros(1, 2), -ca.mtimes(ca.DM(K), s[2:4]), _spin(s))

    @dual
    def ad(self, x: Array) -> Array:
        """``ad_(omega, v) = [[0, 0], [-K v, omega K]]``: the bracket
        ``[xi, eta] = (0, omega K eta_v - eta_w K v)``."""
        return _blocks(0, ca.DM.zeros(1, 2), -ca.mtimes(ca.DM(K), x[1:3]), x[0] * ca.DM(K))

    @dual
    def dexp(self, x: Array) -> Array:
        """Left Jacobian ``[[1, 0], [c, V(omega)]]``, c = :func:`_dexp_column` (Sola et al.,
        A micro Lie theory for state estimation in robotics, reordered to omega first)."""
        return _blocks(1, ca.DM.zeros(1, 2), _dexp_column(x), V(x[0]))

    @dual
    def dexp_inv(self, x: Array) -> Array:
        """Its inverse ``[[1, 0], [-V^{-1} c, V^{-1}]]``."""
        Vi = V_inv(x[0])
        return _blocks(1, ca.DM.zeros(1, 2), -ca.mtimes(Vi, _dexp_column(x)), Vi)  # type: ignore[operator]  # Array = Any (lie/group.py)

    @dual
    def dcay(self, x: Array) -> Array:
        """``[[1/d, 0], [-K v/(2 d), (I + omega K/2)/d]]``, the inverse of :meth:`dcay_inv`."""
        w, d = x[0], _cay_scale(x[0])
        return _blocks(1 / d, ca.DM.zeros(1, 2), -ca.mtimes(ca.DM(K), x[1:3]) / (2 * d),
                       (ca.DM.eye(2) + w / 2 * ca.DM(K)) / d)

    @dual
    def dcay_inv(self, x: Array) -> Array:
        """``[[d, 0], [(I - omega K/2) K v/2, I - omega K/2]]``: the vee of
        ``(I - hat(xi)/2) hat(eta) (I + hat(xi)/2)`` (the SE(3) formula of Kobilarov & Marsden
        restricted to the plane)."""
        M = ca.DM.eye(2) - x[0] / 2 * ca.DM(K)
        return _blocks(_cay_scale(x[0]), ca.DM.zeros(1, 2),
                       ca.mtimes(M, ca.mtimes(ca.DM(K), x[1:3])) / 2, M)

    @dual
    def body_rate(self, s: Array, y: Array) -> Array:
        """``(r (0, omega/2), R(r) v)`` (complex product)."""
        return ca.vertcat(-s[1] * y[0] / 2, s[0] * y[0] / 2, ca.mtimes(_spin(s), y[1:3]))

    @dual
    def spatial_rate(self, s: Array, y: Array) -> Array:
        """``((0, omega/2) r, omega K p + v)``."""
        return ca.vertcat(-s[1] * y[0] / 2, s[0] * y[0] / 2,
                          y[0] * ca.mtimes(ca.DM(K), s[2:4]) + y[1:3])

    @dual
    def chart(self, e: Array) -> Array:
        """``(2 e_z/e_w, e_p)``: zero only at the identity; theta = pi is a pole."""
        return ca.vertcat(2 * e[1] / e[0], e[2:4])

    @dual
    def normalise(self, x: Array) -> Array:
        n = ca.norm_2(x[0:2])
        r = x[0:2] / safe_if(n < 1e-12, 1.0, n) * ca.if_else(x[0] < 0, -1, 1)
        return ca.vertcat(r, x[2:4])

    def invalid(self, x: Array) -> Array:
        return ca.norm_2(x[0:2]) < 1e-12

    @dual
    def matrix(self, s: Array) -> Array:
        return _homogeneous(_spin(s), s[2:4])

    def of_matrix(self, M: Any) -> np.ndarray:
        M = np.asarray(M, dtype=float)
        half = np.arctan2(M[1, 0], M[0, 0]) / 2  # in (-pi/2, pi/2]: w >= 0
        return np.array([np.cos(half), np.sin(half), M[0, 2], M[1, 2]])

    def parse(self, value: Any) -> np.ndarray:
        """A planar pose in any form of :func:`from_spec` -> (w, z, x, y) with w >= 0."""
        return self.of_matrix(from_spec(value))

    def detours(self, delta: Array, v: Array, N: int, side: Side) -> Steps:
        """The long way round: the heading turns the other way at a constant rate while the
        relative position moves along the straight line to its end (the steps
        ``between(P_k, P_{k+1})`` of the partial products ``P_k = (exp(k theta'/N), k p/N)``,
        ``theta' = theta -+ 2 pi``)."""
        back = v[0] - ca.if_else(v[0] < 0, -2 * np.pi, 2 * np.pi)
        P = [ca.vertcat(ca.cos(back * k / (2 * N)), ca.sin(back * k / (2 * N)),
                        delta[2:4] * k / N) for k in range(N + 1)]
        return [("long way round", [self.between(P[k], P[k + 1], side) for k in range(N)])]

    def sample(self, rng: np.random.Generator) -> np.ndarray:
        """A uniform heading and a standard normal position."""
        half = float(rng.uniform(-np.pi, np.pi)) / 2
        return np.array([np.cos(half), np.sin(half), *rng.normal(size=2)])

    def distance_from_group(self, M: Any) -> Any:
        """``|R^T R - I| + |last row - (0, 0, 1)|`` (of each matrix of a stack)."""
        g = np.asarray(to_numpy(M), dtype=float)
        R = g[..., 0:2, 0:2]
        d = (np.linalg.norm(np.swapaxes(R, -1, -2) @ R - np.eye(2), axis=(-2, -1))
             + np.linalg.norm(g[..., 2, :] - [0.0, 0.0, 1.0], axis=-1))
        return float(d) if d.ndim == 0 else d


SE2 = SE2Group()

# ----------------------------------------------------------------- constructors (NumPy)


def from_angle(angle: float, position: Any) -> np.ndarray:
    """The pose matrix with heading ``angle`` (radians) and ``position``."""
    return np.asarray(_homogeneous(_rotation(np.cos(angle), np.sin(angle)),
                                   np.asarray(position, dtype=float)))


def from_matrix(M: Any, tol: float = 1e-6) -> np.ndarray:
    """A given 3 x 3 matrix, checked to be a planar pose (rotation block, last row 0 0 1)."""
    M = np.asarray(M, dtype=float)
    if M.shape != (3, 3) or not np.all(np.isfinite(M)):
        raise ConfigError(f"a planar pose matrix is 3 x 3 finite numbers, got shape {M.shape}")
    R = M[0:2, 0:2]
    err = float(np.linalg.norm(R.T @ R - np.eye(2)))
    if err > tol or np.linalg.det(R) <= 0 or np.linalg.norm(M[2] - [0.0, 0.0, 1.0]) > tol:
        raise ConfigError(f"matrix is not a planar pose (|R^T R - I| = {err:.2e}, det R = "
                          f"{np.linalg.det(R):.3f}, last row {M[2].tolist()}); give "
                          "[[cos a, -sin a, x], [sin a, cos a, y], [0, 0, 1]]")
    return from_angle(float(np.arctan2(M[1, 0], M[0, 0])), M[0:2, 2])


POSE_FORMS = ("identity, {angle: a, position: [x, y]} (either key may be left out), a 3 x 3 "
              "matrix, or 4 numbers cos(a/2) sin(a/2) x y")
_KEYS = ("angle", "position")


def from_spec(v: Any) -> np.ndarray:
    """A planar pose written in any documented form (:data:`POSE_FORMS`), as a checked
    3 x 3 matrix."""
    if isinstance(v, str) and v == "identity":
        return np.eye(3)
    if isinstance(v, dict):
        so3.only_keys(v, _KEYS, f"a planar pose is {POSE_FORMS}")
        angle = v.get("angle", 0.0)
        if isinstance(angle, bool) or not isinstance(angle, (int, float)) or \
                not np.isfinite(angle):
            raise ConfigError(f"angle must be a finite number (radians), got {angle!r}")
        return from_angle(float(angle), so3.number_list(v.get("position", [0.0, 0.0]), 2,
                                                        "position"))
    try:
        M = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"a planar pose is {POSE_FORMS}; got {v!r}") from None
    if M.shape == (4,) and np.all(np.isfinite(M)):
        if np.hypot(M[0], M[1]) < 1e-12:
            raise ConfigError("the half-angle number (0, 0) is no rotation; give 1 0 for none")
        return from_angle(2 * float(np.arctan2(M[1], M[0])), M[2:])
    if M.shape == (3, 3):
        return from_matrix(M)
    raise ConfigError(f"a planar pose is {POSE_FORMS}; got {v!r}")
