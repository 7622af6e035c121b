"""SO(3), its elements held as unit quaternions (w, x, y, z), and the rotation constructors
used by problem files.

Conventions: ``hat(w) v = w x v``; ``R(p q) = R(p) R(q)``; vectors are CasADi columns or 1-D
NumPy arrays. Formulas with a removable singularity at angle 0 switch to a Taylor branch
built from a guarded argument, so neither value nor derivative is NaN.
"""

from __future__ import annotations

import difflib
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from ..errors import ConfigError, SingularityError
from ._backend import dual, guarded, is_symbolic, safe_if, series, to_numpy
from .group import Array, LieGroup, Side, Steps

_SMALL = 1e-2  # below this squared angle the Taylor branches are exact to 1e-16


def _one_minus_cos(t2: Array) -> Array:
    """``(1 - cos t)/t^2``, NaN-free at 0."""
    return guarded(t2, _SMALL, (0.5, -1 / 24, 1 / 720, -1 / 40320),
                   lambda t, t2: 2 * ca.sin(t / 2) ** 2 / t2)


def _t_minus_sin(t2: Array) -> Array:
    """``(t - sin t)/t^3``, NaN-free at 0."""
    return guarded(t2, _SMALL, (1 / 6, -1 / 120, 1 / 5040, -1 / 362880),
                   lambda t, t2: (t - ca.sin(t)) / (t * t2))


def _dexp_inv_coefficient(t2: Array) -> Array:
    """``1/t^2 - (1 + cos t)/(2 t sin t)``, NaN-free at 0 (singular at t = 2 pi)."""
    return guarded(t2, _SMALL, (1 / 12, 1 / 720, 1 / 30240, 1 / 1209600),
                   lambda t, t2: 1 / t2 - (1 + ca.cos(t)) / (2 * t * ca.sin(t)))


class SO3Group(LieGroup):
    """The rotation group on unit quaternions: 4 numbers for 3 degrees of freedom, shown as
    the rotation matrix."""

    name = "SO3"
    dim = 3
    size = 4
    manifold = "SO(3)"
    kind = "rotation"
    meaning = "unit quaternion w x y z (normalised; sign free)"
    matrix_shape = (3, 3)

    def identity(self) -> np.ndarray:
        return np.array([1.0, 0.0, 0.0, 0.0])

    @dual
    def compose(self, p: Array, q: Array) -> Array:
        """Hamilton product ``p q = (p_w q_w - p_v . q_v, p_w q_v + q_w p_v + p_v x q_v)``."""
        pw, pv, qw, qv = p[0], p[1:4], q[0], q[1:4]
        return ca.vertcat(pw * qw - ca.dot(pv, qv), pw * qv + qw * pv + ca.cross(pv, qv))

    @dual
    def inverse(self, q: Array) -> Array:
        """``q^* = (w, -v)``."""
        return ca.vertcat(q[0], -q[1:4])

    @dual
    def exp(self, a: Array) -> Array:
        """``(cos(t/2), sin(t/2) a/t)``, t = |a|; the Taylor branch keeps value and
        derivatives finite at a = 0."""
        x2 = ca.dot(a, a) / 4  # (angle/2)^2
        small = x2 < 1e-2
        x = ca.sqrt(safe_if(small, 1.0, x2))
        sinc = safe_if(small, series(x2, (1, -1 / 6, 1 / 120, -1 / 5040, 1 / 362880)),
                       ca.sin(x) / x)
        cos = safe_if(small, series(x2, (1, -1 / 2, 1 / 24, -1 / 720, 1 / 40320)), ca.cos(x))
        return ca.vertcat(cos, sinc * a / 2)

    @dual
    def log(self, q: Array) -> Array:
        """``2 atan2(|v|, w) v/|v|`` after normalising and choosing w >= 0 (``2 v / w`` to
        first order at the identity)."""
        e = q / ca.norm_2(q)
        e = ca.if_else(e[0] < 0, -e, e)
        n2 = ca.sumsqr(e[1:4])
        small = n2 < 1e-20
        n = ca.sqrt(safe_if(small, 1.0, n2))
        return safe_if(small, 2 / e[0], 2 * ca.atan2(n, e[0]) / n) * e[1:4]

    @dual
    def cay(self, a: Array) -> Array:
        """``(1, a/2)/sqrt(1 + |a|^2/4)`` (seed 000, eq. 63)."""
        return ca.vertcat(1, a / 2) / ca.sqrt(1 + ca.dot(a, a) / 4)

    def cay_inv(self, q: Array) -> Array:
        """``2 q_v / q_w`` (either sign); at a rotation of pi (``1 + tr R = 4 q_w^2/|q|^2 =
        0``) a SingularityError on NumPy input, with the fix."""
        if not is_symbolic(q):
            q = np.asarray(q, dtype=float)
            one_plus_trace = 4 * q[0] ** 2 / np.dot(q, q)
            if one_plus_trace < 1e-10:
                raise SingularityError("Cayley map singular: rotation of pi in one step; "
                                       f"increase N (1 + tr R = {one_plus_trace:.2e})")
        return 2 * q[1:4] / q[0]

    @dual
    def hat(self, w: Array) -> Array:
        """The skew matrix of w: ``hat(w) v = w x v``."""
        return ca.vertcat(ca.horzcat(0, -w[2], w[1]), ca.horzcat(w[2], 0, -w[0]),
                          ca.horzcat(-w[1], w[0], 0))

    @dual
    def vee(self, M: Array) -> Array:
        """Inverse of ``hat`` on skew matrices: (M[2,1], M[0,2], M[1,0])."""
        return ca.vertcat(M[2, 1], M[0, 2], M[1, 0])

    def Ad(self, q: Array) -> Array:
        """``Ad_R = R``."""
        return self.matrix(q)

    def ad(self, w: Array) -> Array:
        """``ad_w = hat(w)`` (the bracket is the cross product)."""
        return self.hat(w)

    @dual
    def dexp(self, w: Array) -> Array:
        """The left Jacobian ``I + (1 - cos t)/t^2 hat(w) + (t - sin t)/t^3 hat(w)^2``."""
        W, t2 = self.hat(w), ca.dot(w, w)
        return ca.DM.eye(3) + _one_minus_cos(t2) * W + _t_minus_sin(t2) * ca.mtimes(W, W)

    @dual
    def dexp_inv(self, w: Array) -> Array:
        """``I - hat(w)/2 + (1/t^2 - (1 + cos t)/(2 t sin t)) hat(w)^2``."""
        W = self.hat(w)
        return ca.DM.eye(3) - W / 2 + _dexp_inv_coefficient(ca.dot(w, w)) * ca.mtimes(W, W)

    @dual
    def dcay(self, a: Array) -> Array:
        """``2/(4 + |a|^2) (2 I + hat(a))`` (seed 000, eq. 64)."""
        return 2 / (4 + ca.dot(a, a)) * (2 * ca.DM.eye(3) + self.hat(a))

    @dual
    def dcay_inv(self, a: Array) -> Array:
        """``I - hat(a)/2 + a a^T/4`` (seed 000, eq. 64)."""
        return ca.DM.eye(3) - self.hat(a) / 2 + ca.mtimes(a, a.T) / 4

    @dual
    def body_rate(self, s: Array, y: Array) -> Array:
        """``q (0, y)/2``."""
        return self.compose(s, ca.vertcat(0, y)) / 2

    @dual
    def spatial_rate(self, s: Array, y: Array) -> Array:
        """``(0, y) q/2``."""
        return self.compose(ca.vertcat(0, y), s) / 2

    def chart(self, e: Array) -> Array:
        """Cayley coordinates ``2 e_v/e_w``: zero only at e = +-1. The rotation of pi that
        the skew part of R_T^T R alone would accept (e_w = 0) is a pole here, not a root."""
        return 2 * e[1:4] / e[0]

    @dual
    def normalise(self, x: Array) -> Array:
        """``x/|x|`` with w >= 0 (the sign of a quaternion is free); zero stays zero."""
        n = ca.norm_2(x)
        return x / safe_if(n < 1e-12, 1.0, n) * ca.if_else(x[0] < 0, -1, 1)

    def invalid(self, x: Array) -> Array:
        return ca.norm_2(x) < 1e-12

    @dual
    def matrix(self, q: Array) -> Array:
        """``R(q) = (w^2 - |v|^2) I + 2 v v^T + 2 w hat(v)``, orthogonal when |q| = 1."""
        w, v = q[0], q[1:4]
        return (w**2 - ca.dot(v, v)) * ca.DM.eye(3) + 2 * ca.mtimes(v, v.T) + 2 * w * self.hat(v)

    def of_matrix(self, R: Any) -> np.ndarray:
        """Shepperd's unit quaternion (w >= 0) of a numeric rotation."""
        R = np.asarray(R, dtype=float)
        tr = np.trace(R)
        i = int(np.argmax([tr, R[0, 0], R[1, 1], R[2, 2]]))
        if i == 0:
            w = 0.5 * np.sqrt(max(1.0 + tr, 0.0))
            q = np.array([w, (R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w),
                          (R[1, 0] - R[0, 1]) / (4 * w)])
        else:
            j, k = (i % 3) + 1, ((i + 1) % 3) + 1  # cyclic successors among 1, 2, 3
            a, b, c = i - 1, j - 1, k - 1
            x = 0.5 * np.sqrt(max(1.0 + R[a, a] - R[b, b] - R[c, c], 0.0))
            q = np.zeros(4)
            q[i] = x
            q[0] = (R[c, b] - R[b, c]) / (4 * x)
            q[j] = (R[b, a] + R[a, b]) / (4 * x)
            q[k] = (R[c, a] + R[a, c]) / (4 * x)
        q /= np.linalg.norm(q)
        return -q if q[0] < 0 else q

    def parse(self, value: Any) -> np.ndarray:
        """A rotation matrix, a quaternion (4 numbers) or any form of :func:`from_spec` ->
        unit quaternion with w >= 0."""
        if isinstance(value, (str, dict)):
            return self.of_matrix(from_spec(value))
        M = np.asarray(value, dtype=float)
        if M.shape == (4,):
            return self.of_matrix(from_quaternion(M))
        return self.of_matrix(from_matrix(M))

    def detours(self, delta: Array, v: Array, N: int, side: Side) -> Steps:
        """The long way round about the axis of the geodesic (about x when delta = 1), in
        constant steps; it lands on delta exactly, on either side (the steps commute)."""
        angle = ca.norm_2(v)
        turns = angle > 1e-9
        axis = ca.if_else(turns, v / safe_if(turns, angle, 1.0), ca.DM([1.0, 0.0, 0.0]))
        return [("long way round", [self.exp(axis * (angle - 2 * np.pi) / N)])]

    def sample(self, rng: np.random.Generator) -> np.ndarray:
        """Haar-uniform: a normalised Gaussian quaternion."""
        return np.asarray(self.normalise(rng.normal(size=4)))

    def distance_from_group(self, M: Any) -> Any:
        """``|R^T R - I|`` (of each matrix of a stack)."""
        R = np.asarray(to_numpy(M), dtype=float)
        d = np.linalg.norm(np.swapaxes(R, -1, -2) @ R - np.eye(3), axis=(-2, -1))
        return float(d) if d.ndim == 0 else d


SO3 = SO3Group()

# ----------------------------------------------------------------- constructors (NumPy)


def from_quaternion(q: ArrayLike) -> np.ndarray:
    """Rotation matrix of the quaternion (w, x, y, z); normalised, zero rejected."""
    q = np.asarray(q, dtype=float)
    if q.shape != (4,) or not np.all(np.isfinite(q)):
        raise ConfigError(f"a quaternion is 4 finite numbers [w, x, y, z], got {q.tolist()}")
    with np.errstate(over="ignore"):
        n = np.linalg.norm(q)
    if not np.isfinite(n):  # e.g. [1e300, 1e300, 1e300, 1e300]: q / inf would be identity
        raise ConfigError(f"the quaternion's norm overflows (|q| beyond 1.8e+308), got "
                          f"{q.tolist()}; scale it down, e.g. divide by its largest component")
    if n < 1e-12:
        raise ConfigError("the zero quaternion is not a rotation; give [1, 0, 0, 0] for none")
    w, x, y, z = q / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


ANGLE_MAX = 1e6  # rad: beyond, an angle has lost the digits that place it on the circle


def from_rotvec(v: ArrayLike) -> np.ndarray:
    """Rotation matrix ``exp(hat(v))`` of a rotation vector (axis times angle)."""
    v = np.asarray(v, dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ConfigError(f"a rotation vector is 3 finite numbers, got {np.asarray(v).tolist()}")
    with np.errstate(over="ignore"):
        angle = float(np.linalg.norm(v))
    if not angle <= ANGLE_MAX:  # also an overflowing norm: sin, cos of it mean nothing
        raise ConfigError(f"the rotation angle {angle:g} rad is beyond {ANGLE_MAX:g} rad, "
                          "where its sine and cosine are meaningless; reduce it modulo "
                          "2 pi")
    return np.asarray(SO3.matrix(SO3.exp(v)))


def from_axis_angle(axis: ArrayLike, angle: float) -> np.ndarray:
    """Rotation by ``angle`` (radians) about ``axis`` (normalised; zero rejected)."""
    axis = np.asarray(axis, dtype=float)
    if axis.shape != (3,) or not np.all(np.isfinite(axis)) or not np.isfinite(angle):
        raise ConfigError("axis_angle needs a 3-vector axis and a finite angle")
    scale = float(np.max(np.abs(axis)))  # the norm of a huge axis without overflow
    n = scale * float(np.linalg.norm(axis / scale)) if scale > 0 else 0.0
    if n < 1e-12:
        raise ConfigError("the rotation axis is zero; give a nonzero axis such as [0, 0, 1]")
    return from_rotvec(axis / n * float(angle))


def from_matrix(M: Any, tol: float = 1e-6) -> np.ndarray:
    """A given 3 x 3 matrix, checked to be a rotation (R^T R = I, det R = +1) to ``tol``."""
    M = np.asarray(M, dtype=float)
    if M.shape != (3, 3) or not np.all(np.isfinite(M)):
        raise ConfigError(f"a rotation matrix is 3 x 3 finite numbers, got shape {M.shape}")
    err = float(np.linalg.norm(M.T @ M - np.eye(3)))
    if err > tol or np.linalg.det(M) <= 0:
        raise ConfigError(
            f"matrix is not a rotation (|R^T R - I| = {err:.2e}, det = {np.linalg.det(M):.3f});"
            " give an orthonormal matrix with det +1, or use rotvec/quaternion instead"
        )
    u, _, vt = np.linalg.svd(M)
    return u @ vt  # nearest rotation, exact to machine precision


ROTATION_FORMS = ("identity, {rotvec: [x, y, z]}, {axis_angle: {axis: [x, y, z], angle: a}}, "
                  "{quaternion: [w, x, y, z]} or {matrix: [[..], [..], [..]]}")
_FORMS = ("rotvec", "axis_angle", "quaternion", "matrix")


def number_list(v: Any, n: int, what: str) -> np.ndarray:
    """n numbers (no booleans), or a ConfigError naming ``what``."""
    if not isinstance(v, (list, tuple, np.ndarray)) or len(v) != n or any(
            isinstance(c, bool) or not isinstance(c, (int, float, np.floating)) for c in v):
        raise ConfigError(f"{what} needs a list of {n} numbers, got {v!r}")
    return np.asarray(v, dtype=float)


def did_you_mean(word: Any, choices: tuple[str, ...]) -> str:
    """``"; did you mean 'x'?"`` for the choice x closest to word, else ``""``."""
    close = difflib.get_close_matches(str(word), choices, 1)
    return f"; did you mean {close[0]!r}?" if close else ""


def only_keys(v: dict[Any, Any], keys: tuple[str, ...], forms: str) -> None:
    """A ConfigError ``forms; got v`` (with the closest key) unless v is a non-empty dict
    of ``keys``."""
    wrong = [k for k in v if k not in keys]
    if wrong or not v:
        raise ConfigError(f"{forms}; got {v!r}{did_you_mean(wrong[0], keys) if wrong else ''}")


def from_spec(v: Any) -> np.ndarray:
    """A rotation written in any documented form (:data:`ROTATION_FORMS`) or given as a
    3 x 3 NumPy array, as a checked 3 x 3 matrix."""
    if isinstance(v, str) and v == "identity":
        return np.eye(3)
    if isinstance(v, np.ndarray) and v.shape == (3, 3):
        return from_matrix(v)
    if not isinstance(v, dict) or len(v) != 1:
        raise ConfigError(f"a rotation is {ROTATION_FORMS}; got {v!r}")
    (kind, val), = v.items()
    if kind == "rotvec":
        return from_rotvec(number_list(val, 3, "rotvec"))
    if kind == "axis_angle":
        if not isinstance(val, dict) or set(val) != {"axis", "angle"}:
            raise ConfigError("axis_angle needs exactly the keys axis and angle")
        angle = val["angle"]
        if isinstance(angle, bool) or not isinstance(angle, (int, float)):
            raise ConfigError(f"angle must be a number, got {angle!r}")
        return from_axis_angle(number_list(val["axis"], 3, "axis"), float(angle))
    if kind == "quaternion":
        return from_quaternion(number_list(val, 4, "quaternion"))
    if kind == "matrix":
        if not isinstance(val, list) or len(val) != 3:
            raise ConfigError("matrix needs 3 rows of 3 numbers")
        return from_matrix(np.vstack([number_list(r, 3, "a matrix row") for r in val]))
    raise ConfigError(f"unknown rotation form {kind!r}{did_you_mean(kind, _FORMS)} A rotation "
                      f"is {ROTATION_FORMS}")
