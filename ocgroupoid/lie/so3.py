"""SO(3): hat, vee, exp, log, Ad, ad, the Cayley map, unit quaternions (the stored form of
node states, :class:`Quaternion`) and the rotation constructors used by problem files.

Conventions: ``hat(w) v = w x v``; vectors are CasADi columns or 1-D NumPy arrays; a
rotation is a 3 x 3 matrix. Formulas with a removable singularity at angle 0 switch to a
Taylor branch built from a guarded argument, so neither value nor derivative is NaN.
"""

from __future__ import annotations

import difflib
import sys
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from ..errors import ConfigError, SingularityError
from ._backend import dual, is_symbolic, safe_if, to_numpy
from .form import Side, StateForm, Steps, pure
from .group import Array, MatrixGroup

_SMALL = 1e-2  # below this squared angle the Taylor branches are exact to 1e-16


@dual
def hat(w: Array) -> Array:
    """The skew matrix of w: ``hat(w) v = w x v``."""
    return ca.vertcat(
        ca.horzcat(0, -w[2], w[1]),
        ca.horzcat(w[2], 0, -w[0]),
        ca.horzcat(-w[1], w[0], 0),
    )


@dual
def vee(M: Array) -> Array:
    """Inverse of ``hat`` on skew matrices: (M[2,1], M[0,2], M[1,0])."""
    return ca.vertcat(M[2, 1], M[0, 2], M[1, 0])


@dual
def vee_skew(M: Array) -> Array:
    """vee of the skew part: ``vee((M - M^T)/2)``."""
    return ca.vertcat(M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1]) / 2


def _exp_coefficients(theta2: Array) -> tuple[Array, Array]:
    """A = sin(t)/t and B = (1 - cos t)/t^2 at t^2 = theta2, NaN-free at 0."""
    small = theta2 < _SMALL
    safe = safe_if(small, 1.0, theta2)
    t = ca.sqrt(safe)
    A = safe_if(small, 1 - theta2 / 6 + theta2**2 / 120 - theta2**3 / 5040, ca.sin(t) / t)
    B = safe_if(
        small,
        0.5 - theta2 / 24 + theta2**2 / 720 - theta2**3 / 40320,
        2 * ca.sin(t / 2) ** 2 / safe,
    )
    return A, B


def _jacobian_coefficient(theta2: Array) -> Array:
    """C = (t - sin t)/t^3, NaN-free at 0."""
    small = theta2 < _SMALL
    safe = safe_if(small, 1.0, theta2)
    t = ca.sqrt(safe)
    return safe_if(
        small,
        1 / 6 - theta2 / 120 + theta2**2 / 5040 - theta2**3 / 362880,
        (t - ca.sin(t)) / (t * safe),
    )


def _jacobian_inverse_coefficient(theta2: Array) -> Array:
    """D = 1/t^2 - (1 + cos t)/(2 t sin t), NaN-free at 0 (singular at t = 2 pi)."""
    small = theta2 < _SMALL
    safe = safe_if(small, 1.0, theta2)
    t = ca.sqrt(safe)
    return safe_if(
        small,
        1 / 12 + theta2 / 720 + theta2**2 / 30240 + theta2**3 / 1209600,
        1 / safe - (1 + ca.cos(t)) / (2 * t * ca.sin(t)),
    )


@dual
def exp(w: Array) -> Array:
    """Rodrigues: ``exp(hat(w)) = I + A hat(w) + B hat(w)^2``."""
    W = hat(w)
    A, B = _exp_coefficients(ca.dot(w, w))
    return ca.DM.eye(3) + A * W + B * ca.mtimes(W, W)


@dual
def dexp(w: Array) -> Array:
    """Right-trivialised derivative of exp (the left Jacobian):
    ``d exp(w)[dw] = hat(dexp(w) dw) exp(w)``, ``dexp = I + B hat(w) + C hat(w)^2``."""
    W = hat(w)
    theta2 = ca.dot(w, w)
    _, B = _exp_coefficients(theta2)
    C = _jacobian_coefficient(theta2)
    return ca.DM.eye(3) + B * W + C * ca.mtimes(W, W)


@dual
def dexp_inv(w: Array) -> Array:
    """Inverse of ``dexp``: ``I - hat(w)/2 + D hat(w)^2``."""
    W = hat(w)
    D = _jacobian_inverse_coefficient(ca.dot(w, w))
    return ca.DM.eye(3) - W / 2 + D * ca.mtimes(W, W)


# ----------------------------------------------------------------------- Cayley map


@dual
def cay(a: Array) -> Array:
    """Cayley map on so(3) (seed 000, eq. 63): ``I + 4/(4 + |a|^2) (hat(a) + hat(a)^2/2)``."""
    A = hat(a)
    return ca.DM.eye(3) + 4 / (4 + ca.dot(a, a)) * (A + ca.mtimes(A, A) / 2)  # type: ignore[operator]  # Array = Any (lie/group.py)


@dual
def _cay_inv(R: Array) -> Array:
    return 2 * vee_skew(R) * 2 / (1 + ca.trace(R))


def cay_inv(R: Array) -> Array:
    """``cay^{-1}(R) = 4 vee_skew(R) / (1 + tr R)``; undefined for a rotation of pi (a
    :class:`SingularityError` on NumPy input, with the fix)."""
    if not is_symbolic(R):
        R = np.asarray(R, dtype=float)
        if 1.0 + np.trace(R) < 1e-10:
            raise SingularityError(
                "Cayley map singular: rotation of pi in one step; increase N "
                f"(1 + tr R = {1.0 + np.trace(R):.2e})"
            )
    return _cay_inv(R)


@dual
def dcay(a: Array) -> Array:
    """Right-trivialised derivative of cay (eq. 64): ``2/(4 + |a|^2) (2 I + hat(a))``."""
    return 2 / (4 + ca.dot(a, a)) * (2 * ca.DM.eye(3) + hat(a))


@dual
def dcay_inv(a: Array) -> Array:
    """Inverse of ``dcay`` (eq. 64): ``I - hat(a)/2 + a a^T/4``."""
    return ca.DM.eye(3) - hat(a) / 2 + ca.mtimes(a, a.T) / 4


@dual
def half_cay_inv(a: Array) -> Array:
    """``(I - hat(a)/2)^{-1} = I + (B + B^2)/(1 + |a|^2/4)``, B = hat(a)/2 (as B^3 =
    -|a|^2/4 B): the factor that ``cay`` on SE(3) applies to the translation."""
    B = hat(a) / 2
    return ca.DM.eye(3) + (B + ca.mtimes(B, B)) / (1 + ca.dot(a, a) / 4)


def _log_symbolic(R: Array) -> Array:
    """log on CasADi graphs: ``theta/sin(theta) * vee_skew(R)``, valid for angle < pi."""
    s_vec = vee_skew(R)
    c = (ca.trace(R) - 1) / 2
    s2 = ca.dot(s_vec, s_vec)
    small = ca.logic_and(s2 < _SMALL, c > 0)
    safe = safe_if(small, 1.0, s2)
    s = ca.sqrt(safe)
    factor = safe_if(small, 1 + s2 / 6 + 3 * s2**2 / 40 + 5 * s2**3 / 112, ca.atan2(s, c) / s)
    return factor * s_vec


def log(R: Array) -> Array:
    """The principal logarithm, as a rotation vector of angle in [0, pi].

    NumPy input is handled at every angle, pi included (the axis then comes from the
    symmetric part). On CasADi graphs the formula is valid for angles below pi.
    """
    if is_symbolic(R):
        return _log_symbolic(R)
    return quat_log(to_quaternion(R))


# ------------------------------------------------------------------ unit quaternions


@dual
def quat_multiply(p: Array, q: Array) -> Array:
    """Hamilton product p q of quaternions (w, x, y, z); R(p q) = R(p) R(q)."""
    pw, pv, qw, qv = p[0], p[1:4], q[0], q[1:4]
    return ca.vertcat(pw * qw - ca.dot(pv, qv), pw * qv + qw * pv + ca.cross(pv, qv))


@dual
def quat_exp(a: Array) -> Array:
    """Unit quaternion of exp(hat(a)): ``(cos(t/2), sin(t/2) a/t)``, t = |a|; the Taylor
    branch keeps value and derivatives finite at a = 0."""
    x2 = ca.dot(a, a) / 4  # (angle/2)^2
    small = x2 < 1e-2
    safe = safe_if(small, 1.0, x2)
    x = ca.sqrt(safe)
    sinc = safe_if(small, 1 - x2 / 6 + x2**2 / 120 - x2**3 / 5040 + x2**4 / 362880,
                   ca.sin(x) / x)
    cos = safe_if(small, 1 - x2 / 2 + x2**2 / 24 - x2**3 / 720 + x2**4 / 40320, ca.cos(x))
    return ca.vertcat(cos, sinc * a / 2)


@dual
def quat_conjugate(q: Array) -> Array:
    """q^* = (w, -v): the inverse of a unit quaternion."""
    return ca.vertcat(q[0], -q[1:4])


@dual
def quat_log(q: Array) -> Array:
    """Rotation vector (angle in [0, pi]) of a quaternion: ``2 atan2(|v|, w) v/|v|`` after
    normalising and choosing w >= 0 (``2 v / w`` to first order at the identity)."""
    e = q / ca.norm_2(q)
    e = ca.if_else(e[0] < 0, -e, e)
    n2 = ca.sumsqr(e[1:4])
    small = n2 < 1e-20
    n = ca.sqrt(safe_if(small, 1.0, n2))
    return safe_if(small, 2 / e[0], 2 * ca.atan2(n, e[0]) / n) * e[1:4]


@dual
def quat_to_matrix(q: Array) -> Array:
    """R(q) = (w^2 - |v|^2) I + 2 v v^T + 2 w hat(v); orthogonal exactly when |q| = 1."""
    w, v = q[0], q[1:4]
    return (w**2 - ca.dot(v, v)) * ca.DM.eye(3) + 2 * ca.mtimes(v, v.T) + 2 * w * hat(v)


@dual
def quat_cay(a: Array) -> Array:
    """Unit quaternion of cay(a): ``(1, a/2)/sqrt(1 + |a|^2/4)``."""
    return ca.vertcat(1, a / 2) / ca.sqrt(1 + ca.dot(a, a) / 4)


@dual
def quat_cay_inv(q: Array) -> Array:
    """``cay^{-1}`` of the rotation of a quaternion: ``2 q_v / q_w`` (either sign)."""
    return 2 * q[1:4] / q[0]


@dual
def quat_normalise(x: Array) -> Array:
    """``x/|x|`` with w >= 0 (the sign of a quaternion is free); zero stays zero."""
    n = ca.norm_2(x)
    return x / safe_if(n < 1e-12, 1.0, n) * ca.if_else(x[0] < 0, -1, 1)


def Ad(R: Array) -> Array:
    """Adjoint of SO(3) on R^3: ``Ad_R = R``."""
    return R


def ad(w: Array) -> Array:
    """Adjoint of so(3): ``ad_w = hat(w)`` (the bracket is the cross product)."""
    return hat(w)


# ----------------------------------------------------------------- constructors (NumPy)


def to_quaternion(R: Any) -> np.ndarray:
    """Unit quaternion (w, x, y, z) with w >= 0 of a numeric rotation (Shepperd)."""
    R = np.asarray(R, dtype=float)
    tr = np.trace(R)
    cands = [tr, R[0, 0], R[1, 1], R[2, 2]]
    i = int(np.argmax(cands))
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


def from_quaternion(q: ArrayLike) -> np.ndarray:
    """Rotation of the quaternion (w, x, y, z); normalised, zero rejected."""
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
    """exp(hat(v)) of a rotation vector (axis times angle)."""
    v = np.asarray(v, dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ConfigError(f"a rotation vector is 3 finite numbers, got {np.asarray(v).tolist()}")
    with np.errstate(over="ignore"):
        angle = float(np.linalg.norm(v))
    if not angle <= ANGLE_MAX:  # also an overflowing norm: sin, cos of it mean nothing
        raise ConfigError(f"the rotation angle {angle:g} rad is beyond {ANGLE_MAX:g} rad, "
                          "where its sine and cosine are meaningless; reduce it modulo "
                          "2 pi")
    return np.asarray(exp(v))


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
    close = difflib.get_close_matches(str(kind), _FORMS, 1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise ConfigError(f"unknown rotation form {kind!r}{hint} A rotation is {ROTATION_FORMS}")


class Quaternion(StateForm):
    """SO(3) stored as unit quaternions (w, x, y, z): ``R(p q) = R(p) R(q)``, 4 numbers for
    3 degrees of freedom, shown as the rotation matrix."""

    size = 4
    manifold = "SO(3)"
    kind = "rotation"
    meaning = "unit quaternion w x y z (normalised; sign free)"
    shown_shape = (3, 3)

    def compose(self, a: Array, b: Array) -> Array:
        return quat_multiply(a, b)

    def inverse(self, a: Array) -> Array:
        return quat_conjugate(a)

    def exp(self, x: Array) -> Array:
        return quat_exp(x)

    def log(self, s: Array) -> Array:
        return quat_log(s)

    def cay(self, x: Array) -> Array:
        return quat_cay(x)

    def cay_inv(self, s: Array) -> Array:
        return quat_cay_inv(s)

    def body_rate(self, s: Array, y: Array) -> Array:
        """``q (0, y)/2``."""
        return quat_multiply(s, pure(y)) / 2

    def spatial_rate(self, s: Array, y: Array) -> Array:
        """``(0, y) q/2``."""
        return quat_multiply(pure(y), s) / 2

    def chart(self, e: Array) -> Array:
        """Cayley coordinates ``2 e_v/e_w``: zero only at e = +-1. The rotation of pi that
        the skew part of R_T^T R alone would accept (e_w = 0) is a pole here, not a root."""
        return 2 * e[1:4] / e[0]

    def normalise(self, x: Array) -> Array:
        return quat_normalise(x)

    def invalid(self, x: Array) -> Array:
        return ca.norm_2(x) < 1e-12

    def matrix(self, s: Array) -> Array:
        return quat_to_matrix(s)

    def of_matrix(self, M: Any) -> np.ndarray:
        return to_quaternion(M)

    def parse(self, value: Any) -> np.ndarray:
        """A rotation matrix, a quaternion (4 numbers) or any form of :func:`from_spec` ->
        unit quaternion with w >= 0."""
        if isinstance(value, (str, dict)):
            return to_quaternion(from_spec(value))
        M = np.asarray(value, dtype=float)
        if M.shape == (4,):
            return to_quaternion(from_quaternion(M))
        return to_quaternion(from_matrix(M))

    def paths(self, delta: Array, N: int, side: Side) -> Steps:
        """Constant steps ``exp(w/N)``: the short geodesic ``w = log(delta)`` and the long way
        round about the same axis (about x when delta = 1). Each lands on delta exactly,
        on either side (the steps commute)."""
        v = quat_log(delta)
        angle = ca.norm_2(v)
        turns = angle > 1e-9
        axis = ca.if_else(turns, v / safe_if(turns, angle, 1.0), ca.DM([1.0, 0.0, 0.0]))
        return [(name, [quat_exp(w / N)])
                for name, w in (("geodesic", v), ("long way round", axis * (angle - 2 * np.pi)))]


@dual
def inverse(R: Array) -> Array:
    """R^{-1} = R^T."""
    return R.T


class _SO3(MatrixGroup):
    """The rotation group; elements are 3 x 3 matrices, stored as unit quaternions."""

    name = "SO3"
    dim = 3
    formulas = sys.modules[__name__]
    form = Quaternion()

    def identity(self) -> np.ndarray:
        return np.eye(3)

    def distance_from_group(self, g: Array) -> float:
        g = np.asarray(to_numpy(g), dtype=float)
        return float(np.linalg.norm(g.T @ g - np.eye(3)))

    def sample(self, rng: np.random.Generator) -> np.ndarray:
        """Haar-uniform: the rotation of a normalised Gaussian quaternion."""
        return from_quaternion(rng.normal(size=4))


SO3 = _SO3()
