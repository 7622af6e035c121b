"""A factor of a product Lie groupoid, seen from discrete mechanics.

Every factor carries node states ``s_k`` (a point of its base, or a group element) and
algebra velocities ``xi_k`` on the intervals, linked by the step

    s_{k+1} = step(s_k, tau(h xi_k)),

i.e. the groupoid element between nodes k and k+1 is the composable pair it generates.
A factor also knows its structure maps (source, target, identity, inverse, multiplication),
its Lie algebroid (anchor and bracket, for the Euler-Lagrange operator), the admissible
variations at a node (seed 000, eq. 11), and charts for boundary conditions.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, Literal

import numpy as np

from ..lie.group import Array, LieGroup
from ..lie.retraction import Retraction

Side = Literal["right", "left"]
Element = Any


class Factor(ABC):
    """One factor groupoid with node states, velocities and the step that links them."""

    state: str  # name of the node state (boundary-condition key), e.g. "R"
    velocity: str  # name of the velocity, e.g. "Omega"
    group: LieGroup  # group whose algebra holds the velocities
    side: Side  # "right": s_{k+1} = s_k . w (body); "left": s_{k+1} = w . s_k (spatial)
    state_size: int  # length of a flattened node state
    state_dim: int  # manifold dimension of the node state (= boundary conditions on it)
    manifold: str  # the manifold of the node states, as messages name it (e.g. "S^2")
    base_size: int  # coordinates of the base the Lagrangian sees (0 over a point)
    target_size: int  # length of the packed boundary value of a state (state + chart data)
    componentwise: bool = False  # True when single state components may be left free

    @property
    def algebra_dim(self) -> int:
        return self.group.dim

    # -- discrete structure -------------------------------------------------------------

    @abstractmethod
    def step(self, s: Array, ret: Retraction, a: Array) -> Array:
        """The next node state reached from ``s`` by the group element ``tau(a)``."""

    @abstractmethod
    def base(self, s: Array) -> Array:
        """Base coordinates q of a node state (what the Lagrangian may depend on)."""

    @abstractmethod
    def variation(self, s: Array, eta: Array) -> Array:
        """First-order change of the node state under the admissible variation eta."""

    def dxi(self, ret: Retraction, h: Any, xi_prev: Array, xi_next: Array, eta: Array
            ) -> tuple[Array, Array]:
        """Changes of the adjacent velocities under the variation eta at a node.

        Right (body) factors move ``w_{k-1} -> w_{k-1} exp(t eta)``,
        ``w_k -> exp(-t eta) w_k``; left (spatial) factors the mirror image. With
        ``xi = tau_inv(w)/h`` this gives the trivialised-derivative formulas below
        (seed 000, eq. 30, with ``dtau_inv`` in place of its expanded Cayley terms).
        """
        if self.side == "right":
            return (ret.dtau_inv_left(h * xi_prev) @ eta / h,
                    -(ret.dtau_inv(h * xi_next) @ eta) / h)
        return (ret.dtau_inv(h * xi_prev) @ eta / h,
                -(ret.dtau_inv_left(h * xi_next) @ eta) / h)

    @abstractmethod
    def chart(self, s: Array, target: Array) -> Array:
        """Local coordinates (length ``state_dim``) of ``s`` around the packed target;
        zero exactly at the target, with no spurious root (e.g. at a rotation of pi)."""

    @abstractmethod
    def pack_target(self, value: Any) -> np.ndarray:
        """Numeric state value -> the packed vector the NLP parameters hold."""

    def state_of_target(self, packed: Array) -> Array:
        """The flattened state inside a packed target."""
        return packed[: self.state_size]

    # -- Lie algebroid (continuous mechanics) --------------------------------------------

    @abstractmethod
    def anchor(self, q: Array, y: Array) -> Array:
        """rho(q, y) = dq/dt, linear in the velocity y."""

    @abstractmethod
    def ad(self, y: Array) -> Array:
        """Matrix of the bracket [y, .] on this factor's algebra."""

    @abstractmethod
    def state_rate(self, s: Array, y: Array) -> Array:
        """ds/dt of the flattened state for the velocity y (reconstruction equation)."""

    # -- numeric helpers ---------------------------------------------------------------

    @abstractmethod
    def parse_state(self, value: Any) -> np.ndarray:
        """A user value (already numeric) -> flattened state, validated."""

    @abstractmethod
    def distance(self, s: np.ndarray) -> float:
        """Distance of a flattened numeric state from the manifold."""

    @abstractmethod
    def geodesics(self, s0: np.ndarray, sT: np.ndarray | None, T: float, N: int,
                  ret: Retraction) -> list[tuple[str, np.ndarray]]:
        """Labelled velocity guesses (N x dim) that join s0 to sT, shortest first."""

    def format_state(self, s: np.ndarray) -> Any:
        """A flattened numeric state as the JSON-friendly value users see."""
        return np.asarray(s, dtype=float).tolist()

    # -- groupoid structure maps (on numeric elements) -----------------------------------

    @abstractmethod
    def source(self, g: Element) -> Any:
        """alpha(g)."""

    @abstractmethod
    def target(self, g: Element) -> Any:
        """beta(g)."""

    @abstractmethod
    def identity(self, x: Any) -> Element:
        """epsilon(x)."""

    @abstractmethod
    def inverse(self, g: Element) -> Element:
        """i(g)."""

    @abstractmethod
    def multiply(self, g: Element, k: Element) -> Element:
        """m(g, k), defined when target(g) = source(k)."""

    def element(self, s: np.ndarray, w: Any) -> Element:
        """The groupoid element carrying node state ``s`` by ``w`` to the next node."""
        return w

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.state}, {self.velocity})"
