"""A factor of a product Lie groupoid, seen from discrete mechanics.

Every factor carries node states ``s_k`` (a point of its base, or a group element) and
algebra velocities ``xi_k`` on the intervals, linked by the step

    s_{k+1} = step(s_k, tau(h xi_k)),

i.e. the groupoid element between nodes k and k+1 is the composable pair it generates.
A factor also knows its structure maps (source, target, identity, inverse, multiplication),
its Lie algebroid (anchor and bracket, for the Euler-Lagrange operator), the admissible
variations at a node (seed 000, eq. 11), charts for boundary conditions, and everything
else that differs between factors: the geodesic guesses, ``rplus``/``rminus`` (manif's
vocabulary) and the terminal error, random samples, how a state is shown and how a boundary
value is packed into the NLP parameters. No code outside this package asks which factor it
holds.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Literal

import casadi as ca
import numpy as np

from ..lie._backend import is_symbolic
from ..lie.group import Array, LieGroup
from ..lie.retraction import Retraction

Side = Literal["right", "left"]
Element = Any
Labelled = list[tuple[str, Any]]


@dataclass(frozen=True)
class BoundaryMask:
    """Which boundary components of one factor are prescribed (True), for its guesses."""

    end_state: np.ndarray  # one flag per chart row (state_dim)
    start_velocity: np.ndarray  # one flag per velocity component
    end_velocity: np.ndarray


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
    value_kind: str  # how a parameter file writes the state: rotation, pose, direction, vector
    value_meaning: str  # one line for parameter-file documentation

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

    def coordinate_rate(self, ret: Retraction, theta: Array, y: Array) -> Array:
        """``dTheta/dt`` that moves the state as ``s(t) = step(s_k, tau(Theta(t)))`` with the
        velocity y: ``dtau^{-1}_left(Theta) y`` for right (body) factors (``s^{-1} ds/dt =
        y``), ``dtau^{-1}(Theta) y`` for left (spatial) ones (seed 003, §5.4: the
        left-trivialised derivative ``d_l tau``)."""
        return ret.dtau_inv_left(theta) @ y if self.side == "right" else ret.dtau_inv(theta) @ y

    def magnus_bracket(self, a: Array, b: Array) -> Array:
        """The bracket the Magnus expansion of ``dY/dt = A Y`` is written with: ``[a, b]``
        on left (spatial) factors; ``-[a, b]`` on right (body) ones, whose reconstruction
        ``dY/dt = Y A`` is that equation in the opposite algebra."""
        sign = -1.0 if self.side == "right" else 1.0
        return sign * (self.ad(a) @ b)

    def magnus(self, ya: Array, yb: Array, H: Any) -> Array:
        """Exponential coordinates of the step over an interval of length H from the velocities
        ya, yb at its two Gauss points: the fourth-order Magnus step
        ``H/2 (ya + yb) - sqrt(3)/12 H^2 [ya, yb]`` (the bracket of :meth:`magnus_bracket`;
        local error O(H^5); exact on R^n, where the bracket vanishes)."""
        return H / 2 * (ya + yb) - float(np.sqrt(3.0)) / 12 * H * H * \
            self.magnus_bracket(ya, yb)

    def magnus6(self, y1: Array, y2: Array, y3: Array, H: Any) -> Array:
        """Exponential coordinates of the step over an interval of length H from the velocities
        y1, y2, y3 at its three Gauss points: the sixth-order Magnus step (Blanes, Casas & Ros
        2000; Blanes et al., Phys. Rep. 470 (2009), eq. 253), with the bracket of
        :meth:`magnus_bracket`:

            a1 = H y2,  a2 = sqrt(15)/3 H (y3 - y1),  a3 = 10/3 H (y3 - 2 y2 + y1),
            C1 = [a1, a2],  C2 = -1/60 [a1, 2 a3 + C1],
            W = a1 + a3/12 + 1/240 [-20 a1 - a3 + C1, a2 + C2]

        (local error O(H^7); on R^n, where the brackets vanish, the 3-point Gauss rule)."""
        bracket = self.magnus_bracket
        a1 = H * y2
        a2 = float(np.sqrt(15.0)) / 3 * H * (y3 - y1)
        a3 = 10.0 / 3 * H * (y3 - 2 * y2 + y1)
        c1 = bracket(a1, a2)
        c2 = -1.0 / 60 * bracket(a1, 2 * a3 + c1)
        return a1 + a3 / 12 + 1.0 / 240 * bracket(-20 * a1 - a3 + c1, a2 + c2)

    def velocity_of_rate(self, ret: Retraction, theta: Array, rate: Array) -> Array:
        """The velocity of a coordinate rate: the inverse of :meth:`coordinate_rate`."""
        return ret.dtau_left(theta) @ rate if self.side == "right" else ret.dtau(theta) @ rate

    @abstractmethod
    def chart(self, s: Array, target: Array) -> Array:
        """Local coordinates (length ``state_dim``) of ``s`` around the packed target;
        zero exactly at the target, with no spurious root (e.g. at a rotation of pi)."""

    # -- manifold operations (manif's vocabulary) --------------------------------------

    @abstractmethod
    def rplus(self, s: Array, v: Array) -> Array:
        """The state ``s`` moved by the tangent vector v (length ``algebra_dim``)."""

    @abstractmethod
    def rminus(self, s: Array, goal: Array) -> Array:
        """The tangent vector v with ``rplus(goal, v) = s``; ``|v|`` is their distance."""

    @cached_property
    def rminus_function(self) -> ca.Function:
        """:meth:`rminus` as one CasADi Function of numeric ``(s, goal)``: the same formula
        as the operation-by-operation evaluation on DM, in one call (0.3 ms -> 10 us on
        SO(3); a replay and its verdict take up to ten terminal errors)."""
        s, goal = ca.SX.sym("s", self.state_size), ca.SX.sym("goal", self.state_size)
        return ca.Function(f"rminus_{self.state}", [s, goal], [self.rminus(s, goal)])

    def terminal_error(self, s: Array, goal: Array, mask: np.ndarray) -> float:
        """Distance of a numeric state from a goal over the prescribed components: the angle
        for rotations and directions, the Euclidean norm over ``mask`` on R^n."""
        v = np.asarray(self.rminus_function(np.asarray(s, dtype=float).ravel(),
                                            np.asarray(goal, dtype=float).ravel())).ravel()
        return float(np.linalg.norm(v[mask] if self.componentwise else v))

    # -- NLP parameters: a state value and its packed target ---------------------------

    def state_of_target(self, packed: Array) -> Array:
        """The flattened state inside a packed target."""
        return packed[: self.state_size]

    @abstractmethod
    def pack_target(self, x: Array) -> Array:
        """A state value (quaternion, unit vector, vector; numeric or a graph) -> the packed
        target the NLP parameters hold: the state normalised, plus its chart data."""

    def invalid(self, x: Array) -> Array:
        """1 where a state value cannot be packed (a zero quaternion, a direction that is
        not of unit length), else 0: how exported C flags bad parameter files."""
        return ca.DM(0) if not is_symbolic(x) else type(x)(0)

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

    # -- guesses ---------------------------------------------------------------------

    @abstractmethod
    def guesses(self, ret: Retraction, start: Array, end: Array, V0: Array, VN: Array,
                T: Array, N: int, mask: BoundaryMask) -> Labelled:
        """Labelled velocity guesses, each ``dim x N`` (one column per interval), as graphs
        of the packed start and end targets, the end velocities and T; the preferred first.
        Written once: Python evaluates them, exported C runs the same graph."""

    # -- users' view of a state ----------------------------------------------------------

    @abstractmethod
    def parse_state(self, value: Any) -> np.ndarray:
        """A user value (already numeric) -> flattened state, validated."""

    @abstractmethod
    def distance(self, s: np.ndarray) -> float:
        """Distance of a flattened numeric state from the manifold."""

    def distances(self, states: np.ndarray) -> np.ndarray:
        """:meth:`distance` of every row of ``states``."""
        return np.array([self.distance(s) for s in states])

    @property
    def matrix_shape(self) -> tuple[int, ...]:
        """Shape of a state as users see it (a rotation: its 3 x 3 matrix)."""
        return (self.state_size,)

    def as_matrix(self, s: Array) -> Array:
        """A state as users see it, flattened row-major (numeric or a graph)."""
        return s

    # -- random samples (property tests, generic points) --------------------------------

    @abstractmethod
    def sample_state(self, rng: np.random.Generator) -> np.ndarray:
        """A random flattened node state."""

    def sample_base(self, rng: np.random.Generator) -> Any:
        """A random point of the base, as the structure maps see it (None over a point)."""
        return self.sample_state(rng)

    def sample_element(self, rng: np.random.Generator, source: Any = None) -> Element:
        """A random groupoid element, starting at ``source`` when given."""
        s = self.sample_base(rng) if source is None else source
        return self.element(s, self.group.sample(rng))

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

    def element(self, s: Any, w: Any) -> Element:
        """The groupoid element carrying node state ``s`` by ``w`` to the next node."""
        return w

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.state}, {self.velocity})"


def zeros_like(x: Array, rows: int, cols: int) -> Array:
    """A rows x cols zero matrix of the same kind (MX, SX, DM) as x."""
    return type(x).zeros(rows, cols) if is_symbolic(x) or isinstance(x, ca.DM) \
        else ca.DM.zeros(rows, cols)
