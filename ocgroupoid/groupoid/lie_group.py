"""A Lie group G as a groupoid over a point: body (right) or spatial (left) convention."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..lie import so3
from ..lie._backend import is_symbolic
from ..lie.group import Array, LieGroup
from ..lie.retraction import Retraction
from ..lie.so3 import SO3
from .base import Factor, Side


def _empty(like: Array) -> Array:
    return type(like).zeros(0, 1) if is_symbolic(like) else np.zeros(0)


def _conj(q: Array) -> Array:
    return ca.vertcat(q[0], -q[1:4]) if is_symbolic(q) else np.concatenate([q[:1], -q[1:4]])


def _pure(v: Array) -> Array:
    return ca.vertcat(0, v) if is_symbolic(v) else np.concatenate([[0.0], np.ravel(v)])


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

    def step(self, s: Array, ret: Retraction, a: Array) -> Array:
        return self._translate(s, ret.tau_quat(a))

    def base(self, s: Array) -> Array:
        return _empty(s)

    def variation(self, s: Array, eta: Array) -> Array:
        """``R -> R exp(t hat(eta))`` (right) or ``exp(t hat(eta)) R`` (left), in quaternions."""
        return self._translate(s, _pure(eta)) / 2

    def chart(self, s: Array, target: Array) -> Array:
        """Cayley coordinates ``2 e_v/e_w`` of the relative rotation e = q_T^* q (right) or
        q q_T^* (left). Zero only where R = R_T (e = +-1); the rotation of pi that the skew
        part of R_T^T R alone would accept (e_w = 0) is a pole here, not a root."""
        e = self._translate(_conj(target), s) if self.side == "right" else \
            so3.quat_multiply(s, _conj(target))
        return 2 * e[1:4] / e[0]

    def pack_target(self, value: Any) -> np.ndarray:
        return self.parse_state(value)

    def anchor(self, q: Array, y: Array) -> Array:
        return _empty(y)

    def ad(self, y: Array) -> Array:
        return so3.hat(y)

    def state_rate(self, s: Array, y: Array) -> Array:
        return self.variation(s, y)

    def parse_state(self, value: Any) -> np.ndarray:
        M = np.asarray(value, dtype=float)
        if M.shape == (4,):
            return so3.to_quaternion(so3.from_quaternion(M))
        return so3.to_quaternion(so3.from_matrix(M))

    def matrix(self, s: np.ndarray) -> np.ndarray:
        """The rotation matrix of a numeric state (not renormalised: drift stays visible)."""
        return np.asarray(so3.quat_to_matrix(np.asarray(s, dtype=float)))

    def distance(self, s: np.ndarray) -> float:
        return self.group.distance_from_group(self.matrix(s))

    def format_state(self, s: np.ndarray) -> Any:
        return self.matrix(s).tolist()

    def geodesics(self, s0: np.ndarray, sT: np.ndarray | None, T: float, N: int,
                  ret: Retraction) -> list[tuple[str, np.ndarray]]:
        """Constant-velocity paths: the short geodesic and the long way round.

        The per-step element is ``exp(log(Delta)/N)``, so the discrete path lands on the
        target exactly for every retraction (Delta = R0^T RT body, RT R0^T spatial).
        """
        if sT is None:
            return [("rest", np.zeros((N, 3)))]
        R0, RT = self.matrix(s0), self.matrix(sT)
        v = so3.log(R0.T @ RT if self.side == "right" else RT @ R0.T)
        angle = float(np.linalg.norm(v))
        axis = v / angle if angle > 1e-9 else np.array([1.0, 0.0, 0.0])
        paths = [("geodesic", v), ("long way round", axis * (angle - 2 * np.pi))]
        return [(name, np.tile(ret.tau_inv(so3.exp(w / N)) / (T / N), (N, 1)))
                for name, w in paths]

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
