"""A Lie group G as a groupoid over a point: body (right) or spatial (left) convention."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..lie import so3
from ..lie._backend import dual, is_symbolic, safe_if
from ..lie.group import Array, LieGroup
from ..lie.retraction import Retraction
from ..lie.so3 import SO3
from .base import BoundaryMask, Factor, Labelled, Side


def _empty(like: Array) -> Array:
    return type(like).zeros(0, 1) if is_symbolic(like) else np.zeros(0)


def _pure(v: Array) -> Array:
    return ca.vertcat(0, v) if is_symbolic(v) else np.concatenate([[0.0], np.ravel(v)])


@dual
def _unit_quaternion(x: Array) -> Array:
    """``x/|x|`` with w >= 0 (the sign of a quaternion is free); zero stays zero."""
    n = ca.norm_2(x)
    return x / safe_if(n < 1e-12, 1.0, n) * ca.if_else(x[0] < 0, -1, 1)


class LieGroupFactor(Factor):
    """SO(3) => {e}. Body convention ``R_{k+1} = R_k w_k`` (``dR/dt = R hat(Omega)``) or
    spatial ``R_{k+1} = w_k R_k`` (``dR/dt = hat(w) R``), ``w_k = tau(h xi_k)``.

    Node states are stored as unit quaternions (4 numbers for 3 degrees of freedom; the
    product of unit quaternions is the rotation product, ``R(p q) = R(p) R(q)``), and shown to
    users as rotation matrices. The Lagrangian is reduced: it sees the velocity, never R.
    """

    base_size = 0
    state_size = target_size = 4
    state_dim = 3
    manifold = "SO(3)"
    value_kind = "rotation"
    value_meaning = "unit quaternion w x y z (normalised; sign free)"

    def __init__(self, group: LieGroup = SO3, state: str = "R", velocity: str = "Omega",
                 side: Side = "right") -> None:
        if group is not SO3:
            raise ConfigError("LieGroupFactor is implemented for SO(3); use Pair for R^n")
        if side not in ("right", "left"):
            raise ConfigError(f"side must be 'right' (body) or 'left' (spatial), got {side!r}")
        self.group = group
        self.state, self.velocity, self.side = state, velocity, side

    def _translate(self, q: Array, w: Array) -> Array:
        """q w (right) or w q (left), as quaternions."""
        return so3.quat_multiply(q, w) if self.side == "right" else so3.quat_multiply(w, q)

    def between(self, a: Array, b: Array) -> Array:
        """The element carrying a to b: ``a^* b`` (right) or ``b a^*`` (left), so that
        ``b = translate(a, between(a, b))``. Every relative rotation is this one."""
        if self.side == "right":
            return so3.quat_multiply(so3.quat_conjugate(a), b)
        return so3.quat_multiply(b, so3.quat_conjugate(a))

    def step(self, s: Array, ret: Retraction, a: Array) -> Array:
        return self._translate(s, ret.tau_quat(a))

    def base(self, s: Array) -> Array:
        return _empty(s)

    def variation(self, s: Array, eta: Array) -> Array:
        """``R -> R exp(t hat(eta))`` (right) or ``exp(t hat(eta)) R`` (left), in quaternions."""
        return self._translate(s, _pure(eta)) / 2

    def chart(self, s: Array, target: Array) -> Array:
        """Cayley coordinates ``2 e_v/e_w`` of the relative rotation e = between(R_T, R).
        Zero only where R = R_T (e = +-1); the rotation of pi that the skew part of
        R_T^T R alone would accept (e_w = 0) is a pole here, not a root."""
        e = self.between(target, s)
        return 2 * e[1:4] / e[0]

    def rplus(self, s: Array, v: Array) -> Array:
        return self._translate(s, so3.quat_exp(v))

    def rminus(self, s: Array, goal: Array) -> Array:
        return so3.quat_log(self.between(goal, s))

    def pack_target(self, x: Array) -> Array:
        return _unit_quaternion(x)

    def invalid(self, x: Array) -> Array:
        return ca.norm_2(x) < 1e-12

    def anchor(self, q: Array, y: Array) -> Array:
        return _empty(y)

    def ad(self, y: Array) -> Array:
        return so3.hat(y)

    def state_rate(self, s: Array, y: Array) -> Array:
        return self.variation(s, y)

    def guesses(self, ret: Retraction, start: Array, end: Array, V0: Array, VN: Array,
                T: Array, N: int, mask: BoundaryMask) -> Labelled:
        """Constant-velocity paths: the short geodesic and the long way round.

        The per-step element is ``exp(log(Delta)/N)``, Delta = between(R0, RT), so the
        discrete path lands on the target exactly for every retraction. A free final
        attitude gives rest.
        """
        if not mask.end_state.all():
            return [("rest", type(start).zeros(3, N))]
        v = so3.quat_log(self.between(start[:4], end[:4]))
        angle = ca.norm_2(v)
        turns = angle > 1e-9
        axis = ca.if_else(turns, v / safe_if(turns, angle, 1.0), ca.DM([1.0, 0.0, 0.0]))
        h = T / N
        return [(name, ca.repmat(ret.tau_inv_quat(so3.quat_exp(w / N)) / h, 1, N))
                for name, w in (("geodesic", v), ("long way round", axis * (angle - 2 * np.pi)))]

    def parse_state(self, value: Any) -> np.ndarray:
        """A rotation matrix, a quaternion (4 numbers) or any form of
        :func:`~ocgroupoid.lie.so3.from_spec` -> unit quaternion with w >= 0."""
        if isinstance(value, (str, dict)):
            return so3.to_quaternion(so3.from_spec(value))
        M = np.asarray(value, dtype=float)
        if M.shape == (4,):
            return so3.to_quaternion(so3.from_quaternion(M))
        return so3.to_quaternion(so3.from_matrix(M))

    def matrix(self, s: np.ndarray) -> np.ndarray:
        """The rotation matrix of a numeric state (not renormalised: drift stays visible)."""
        return np.asarray(so3.quat_to_matrix(np.asarray(s, dtype=float)))

    def distance(self, s: np.ndarray) -> float:
        return self.group.distance_from_group(self.matrix(s))

    @property
    def shown_shape(self) -> tuple[int, ...]:
        return (3, 3)

    def shown(self, s: Array) -> Array:
        """The rotation matrix, row-major."""
        return _row_major_matrix(s)

    def sample_state(self, rng: np.random.Generator) -> np.ndarray:
        return so3.to_quaternion(self.group.sample(rng))

    def sample_base(self, rng: np.random.Generator) -> None:
        return None

    # -- groupoid structure maps: the group itself, on rotation matrices -----------------

    def source(self, g: Any) -> None:
        return None

    def target(self, g: Any) -> None:
        return None

    def identity(self, x: Any) -> np.ndarray:
        return np.eye(3)

    def inverse(self, g: Any) -> np.ndarray:
        return np.asarray(g).T

    def multiply(self, g: Any, k: Any) -> np.ndarray:
        return np.asarray(g) @ np.asarray(k)


@dual
def _row_major_matrix(q: Array) -> Array:
    return ca.vec(so3.quat_to_matrix(q).T)
