"""A Lie group G as a groupoid over a point: body (right) or spatial (left) convention."""

from __future__ import annotations

from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..lie._backend import is_symbolic
from ..lie.group import Array, LieGroup
from ..lie.retraction import Retraction
from ..lie.rn import Rn
from ..lie.so3 import SO3
from .base import BoundaryMask, Factor, Labelled, Side


def _empty(like: Array) -> Array:
    return type(like).zeros(0, 1) if is_symbolic(like) else np.zeros(0)


class LieGroupFactor(Factor):
    """G => {e} for G = SO(3), SE(3) or SE(2). Body convention ``g_{k+1} = g_k w_k``
    (``dg/dt = g hat(xi)``) or spatial ``g_{k+1} = w_k g_k`` (``dg/dt = hat(xi) g``),
    ``w_k = tau(h xi_k)``.

    Node states are the group's parameters (a unit quaternion for SO(3), quaternion and
    position for SE(3), ...; their product is the group product) and shown to users as the
    group matrix. Everything that differs between groups is the group's
    (:class:`~ocgroupoid.lie.group.LieGroup`); the Lagrangian is reduced: it sees the
    velocity, never g.
    """

    base_size = 0

    def __init__(self, group: LieGroup = SO3, state: str = "R", velocity: str = "Omega",
                 side: Side = "right") -> None:
        if isinstance(group, Rn):
            raise ConfigError(f"LieGroupFactor is implemented for SO(3), SE(3) and SE(2), not "
                              f"{group.name}; use Pair for R^n")
        if side not in ("right", "left"):
            raise ConfigError(f"side must be 'right' (body) or 'left' (spatial), got {side!r}")
        self.group = group
        self.state, self.velocity, self.side = state, velocity, side
        self.state_size = self.target_size = group.size
        self.state_dim = group.dim
        self.manifold = group.manifold
        self.value_kind = group.kind
        self.value_meaning = group.meaning

    def between(self, a: Array, b: Array) -> Array:
        """The element carrying a to b: ``a^{-1} b`` (right) or ``b a^{-1}`` (left), so that
        ``b = step(a, between(a, b))``. Every relative element is this one."""
        return self.group.between(a, b, self.side)

    def step(self, s: Array, ret: Retraction, a: Array) -> Array:
        return self.group.translate(s, ret.tau(a), self.side)

    def base(self, s: Array) -> Array:
        return _empty(s)

    def variation(self, s: Array, eta: Array) -> Array:
        """``g -> g exp(t hat(eta))`` (right) or ``exp(t hat(eta)) g`` (left), stored."""
        return self.group.body_rate(s, eta) if self.side == "right" else \
            self.group.spatial_rate(s, eta)

    def chart(self, s: Array, target: Array) -> Array:
        """The group's chart of the relative element between(g_T, g): Cayley coordinates of
        its rotation (and its position), zero only where g = g_T; a rotation of pi is a pole,
        not a root."""
        return self.group.chart(self.between(target, s))

    def rplus(self, s: Array, v: Array) -> Array:
        return self.group.rplus(s, v, self.side)

    def rminus(self, s: Array, goal: Array) -> Array:
        return self.group.rminus(s, goal, self.side)

    def pack_target(self, x: Array) -> Array:
        return self.group.normalise(x)

    def invalid(self, x: Array) -> Array:
        return self.group.invalid(x)

    def anchor(self, q: Array, y: Array) -> Array:
        return _empty(y)

    def ad(self, y: Array) -> Array:
        return self.group.ad(y)

    def state_rate(self, s: Array, y: Array) -> Array:
        return self.variation(s, y)

    def guesses(self, ret: Retraction, start: Array, end: Array, V0: Array, VN: Array,
                T: Array, N: int, mask: BoundaryMask) -> Labelled:
        """The group's paths from start to end (:meth:`LieGroup.paths`: the constant twist
        ``log(between(start, end))/T``, the long way round), each step read out by the
        retraction, so that the discrete path lands on the target exactly. A free final
        state gives rest."""
        if not mask.end_state.all():
            return [("rest", type(start).zeros(self.algebra_dim, N))]
        n, h = self.state_size, T / N
        delta = self.between(start[:n], end[:n])
        out = []
        for label, steps in self.group.paths(delta, N, self.side):
            xi = [ret.tau_inv(w) / h for w in steps]
            out.append((label, ca.repmat(xi[0], 1, N) if len(xi) == 1 else ca.horzcat(*xi)))
        return out

    def parse_state(self, value: Any) -> np.ndarray:
        """A user's value in any form the group accepts (:meth:`LieGroup.parse`)."""
        return self.group.parse(value)

    @cached_property
    def _matrix(self) -> ca.Function:
        s = ca.SX.sym("s", self.state_size)
        return ca.Function("matrix", [s], [self.group.matrix(s)])

    def matrix(self, s: np.ndarray) -> np.ndarray:
        """The group matrix of a numeric state (not renormalised: drift stays visible),
        through a compiled Function: diagnostics call it at every node."""
        return np.array(self._matrix(np.asarray(s, dtype=float)))

    def distance(self, s: np.ndarray) -> float:
        return float(self.group.distance_from_group(self.matrix(s)))

    def distances(self, states: np.ndarray) -> np.ndarray:
        """:meth:`distance` of every row, the matrices evaluated in one mapped call and
        measured as one stack."""
        n = len(states)
        M = np.array(self._matrix.map(n)(np.asarray(states, dtype=float).T))
        r, c = self.group.matrix_shape
        return np.asarray(self.group.distance_from_group(M.reshape(r, n, c).swapaxes(0, 1)),
                          dtype=float).reshape(n)

    @property
    def matrix_shape(self) -> tuple[int, ...]:
        return self.group.matrix_shape

    def as_matrix(self, s: Array) -> Array:
        """The group matrix, row-major."""
        return self.group.as_matrix(s)

    def sample_state(self, rng: np.random.Generator) -> np.ndarray:
        return self.group.sample(rng)

    def sample_base(self, rng: np.random.Generator) -> None:
        return None

    # -- groupoid structure maps: the group itself, on its parameters -------------------

    def source(self, g: Any) -> None:
        return None

    def target(self, g: Any) -> None:
        return None

    def identity(self, x: Any) -> np.ndarray:
        return self.group.identity()

    def inverse(self, g: Any) -> np.ndarray:
        return np.asarray(self.group.inverse(np.asarray(g)))

    def multiply(self, g: Any, k: Any) -> np.ndarray:
        return np.asarray(self.group.compose(np.asarray(g), np.asarray(k)))
