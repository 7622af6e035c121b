"""A continuous optimal-control problem on a Lie groupoid: the public modelling API.

A Problem holds no N and no retraction: it is the continuous statement. Symbols for the
base coordinates q, the velocities y (and, for second-order problems, their rates dy) are
created from the groupoid; the user writes the Lagrangian, cost and constraints with them::

    G = og.Groupoid(og.LieGroupFactor(state="R", velocity="Omega"))
    pb = og.Problem(G, name="slew")
    I = pb.parameter("inertia", 3, [1.0, 2.0, 3.0])
    Om = pb.velocity("Omega")
    u = pb.mechanics(0.5 * ca.dot(Om, I * Om), actuated="Omega", input_matrix=ca.diag(I))
    pb.minimize(0.5 * ca.sumsqr(u))
    pb.initial(R=np.eye(3), Omega=[0, 0, 0])
    pb.final(R=og.so3.from_rotvec([0, 0, 1]), Omega=[0, 0, 0])
    pb.horizon(5.0)

Second-order problems (order 2) minimise ``int Ltilde(q, y, dy) dt`` subject to
``Phi(q, y, dy) = 0``; first-order problems (order 1) minimise ``int l(q, y) dt`` subject to
``psi(q, y) = 0``. Boundary values, physical parameters and T are runtime parameters of the
compiled NLP: changing them never rebuilds it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import casadi as ca
import numpy as np

from ..errors import ConfigError, DimensionError
from ..groupoid.base import Factor
from ..groupoid.product import Groupoid
from .mechanics import Mechanics, control_rank, split
from .symbols import foreign_message, symbol_labels
from .units import Description, control_labels, default_description, describe
from .values import check_horizon, check_vector, number


def sx(expr: Any, what: str) -> ca.SX:
    """``expr`` as a CasADi SX expression; an MX one (``ca.MX.sym``) or anything else that is
    not an expression is refused with the fix instead of CasADi's NotImplementedError."""
    if isinstance(expr, ca.MX):
        raise ConfigError(f"{what} is a CasADi MX expression; a Problem is built from SX: "
                          "declare symbols with ca.SX.sym, or use the problem's own symbols "
                          "(pb.velocity, pb.parameter, ...)")
    try:
        return ca.SX(expr)
    except (NotImplementedError, TypeError, RuntimeError, ValueError):
        raise ConfigError(f"{what} must be a CasADi SX expression or numbers, got "
                          f"{type(expr).__name__}") from None


@dataclass(frozen=True)
class GuessContext:
    """What a model's guess hook sees of one instance.

    ``initial``/``final`` map state and velocity names to numeric values (NaN where a
    component is free; a free quantity is absent); ``base`` is the preferred geodesic guess
    (N x dim y interval velocities), to be modified rather than rebuilt.
    """

    N: int
    T: float
    params: dict[str, np.ndarray]
    initial: dict[str, np.ndarray]
    final: dict[str, np.ndarray]
    base: np.ndarray


GuessHook = Callable[["Problem", GuessContext], list[tuple[str, np.ndarray]]]


@dataclass(frozen=True)
class Inequality:
    """``lower <= expr <= upper`` wherever the scheme evaluates its constraints; the bounds
    are expressions of the parameters (infinite where a side is open)."""

    name: str
    expr: ca.SX
    lower: ca.SX
    upper: ca.SX


@dataclass
class Parameter:
    """A named runtime parameter with its default value."""

    name: str
    symbol: ca.SX
    value: np.ndarray
    doc: str = ""


@dataclass
class Boundary:
    """Prescribed values at one end: ``states[name]``, ``velocities[name]``.

    A value of None leaves the whole quantity free; for vector states and velocities a
    list may hold None in single components (``[0, 0, None]``).
    """

    states: dict[str, Any] = field(default_factory=dict)
    velocities: dict[str, Any] = field(default_factory=dict)


class Problem:
    """An optimal-control problem on a product Lie groupoid (see the module docstring)."""

    def __init__(self, groupoid: Groupoid | Factor, name: str = "problem", order: int = 2):
        if not isinstance(groupoid, Groupoid):
            groupoid = Groupoid(groupoid)
        if order not in (1, 2):
            raise ConfigError(f"order is 1 (first-order cost) or 2 (second-order), got {order}")
        self.groupoid = groupoid
        self.name = name
        self.order = order
        self.q = ca.SX.sym("q", groupoid.base_size)
        self.s = ca.SX.sym("s", groupoid.state_size)  # the node states (costs, bounds)
        self.y = ca.SX.sym("y", groupoid.algebra_dim)
        self.dy = ca.SX.sym("dy", groupoid.algebra_dim)
        self.params: dict[str, Parameter] = {}
        self.cost: ca.SX | None = None
        self.constraints: list[tuple[str, ca.SX]] = []
        self.controls: list[tuple[str, ca.SX]] = []
        self.dynamics: Mechanics | None = None
        self.start = Boundary()
        self.end = Boundary()
        self.T: float | None = None
        self.guess_hook: GuessHook | None = None
        self.rules: dict[str, Callable[..., ca.SX]] = {}
        self.invariants: list[tuple[str, ca.SX]] = []
        self.final_conditions: list[tuple[str, ca.SX]] = []
        self.inequalities: list[Inequality] = []
        self.terminal: ca.SX | None = None
        self.weights = {"effort": 1.0, "time": 0.0}
        self.T_free = False
        self.T_bounds: tuple[float, float] = (0.0, np.inf)
        self.descriptions: dict[str, Description] = {}  # names and units (describe)
        #: controls declared as variables of their own (:meth:`control`), by name
        self.inputs: dict[str, ca.SX] = {}

    @property
    def end_velocities(self) -> bool:
        """Whether velocities carry boundary values: in second-order problems (the cost
        depends on dy), not in first-order ones (the velocities are the controls)."""
        return self.order == 2

    # -- symbols -----------------------------------------------------------------------

    def parameter(self, name: str, size: int = 1, value: Sequence[float] | float | None = None,
                  doc: str = "") -> ca.SX:
        """Declare a runtime parameter; returns its symbol (a column of length ``size``)."""
        if name in self.params:
            raise ConfigError(f"parameter {name!r} declared twice")
        if value is None:
            raise ConfigError(f"parameter {name!r} needs a default value")
        vec = np.asarray(check_vector(value, size, what=f"parameter {name}"), dtype=float)
        sym = ca.SX.sym(name, size)
        self.params[name] = Parameter(name, sym, vec, doc)
        return sym

    @property
    def P(self) -> ca.SX:
        """All parameter symbols, stacked in declaration order."""
        syms = [p.symbol for p in self.params.values()]
        return ca.vertcat(*syms) if syms else ca.SX.zeros(0, 1)

    @property
    def U(self) -> ca.SX:
        """The controls declared with :meth:`control`, stacked in declaration order (empty
        when the controls are recovered from the dynamics)."""
        syms = list(self.inputs.values())
        return ca.vertcat(*syms) if syms else ca.SX.zeros(0, 1)

    @property
    def explicit_controls(self) -> bool:
        """Whether the controls are decision variables of their own (:meth:`control`)."""
        return bool(self.inputs)

    def control(self, name: str, size: int = 1, unit: str | Sequence[str] | None = None,
                meaning: str | None = None, components: Sequence[str] | None = None,
                group: str | Sequence[str] | None = None) -> ca.SX:
        """Declare a control as a variable of its own (second-order problems), e.g. a thrust
        ``f`` and body torques ``tau`` (size 3); returns its symbol. The generalised force it
        exerts is any expression of the state and the controls, given to
        :meth:`mechanics` as ``force=``; the cost, bounds and constraints read it by name.
        Its components are reported as ``name`` (size 1) or ``name1 .. name<size>``;
        ``unit``, ``meaning``, ``components`` and ``group`` describe it as
        :meth:`describe` does (``pb.control("tau", 3, unit="N m", meaning="body torques")``)."""
        if self.order != 2:
            raise ConfigError(f"control {name!r}: controls of their own drive second-order "
                              "problems (mechanics); in a first-order problem the velocities "
                              "are the controls")
        if self.dynamics is not None:
            raise ConfigError(f"control {name!r}: declare the controls before mechanics()")
        if not isinstance(name, str) or not name.isidentifier():
            raise ConfigError(f"a control's name is an identifier such as 'f' or 'tau', got "
                              f"{name!r}")
        taken = {*self.params, *self.groupoid.state_names, *self.groupoid.velocity_names,
                 *self.inputs}
        if name in taken:
            raise ConfigError(f"control {name!r}: the name is already a parameter, state, "
                              "velocity or control of this problem; choose another")
        if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < 1:
            raise ConfigError(f"control {name!r}: size is an integer >= 1, got {size!r}")
        described = any(v is not None for v in (unit, meaning, components, group))
        desc = describe("controls", int(size), name, meaning, unit, components, group) \
            if described else None  # checked before the control is declared
        sym = ca.SX.sym(name, int(size))
        self.inputs[name] = sym
        names = [name] if size == 1 else [f"{name}{i + 1}" for i in range(int(size))]
        self.controls += list(zip(names, ca.vertsplit(sym)))
        if desc is not None:
            self.descriptions[name] = desc
        return sym

    @property
    def parameter_slices(self) -> dict[str, slice]:
        """Where each parameter sits in P (declaration order)."""
        out, k = {}, 0
        for name, prm in self.params.items():
            out[name] = slice(k, k + prm.symbol.numel())
            k = out[name].stop
        return out

    def parameter_values(self, overrides: dict[str, Any] | None = None) -> np.ndarray:
        """Stacked parameter values, defaults overridden by ``overrides``."""
        overrides = dict(overrides or {})
        unknown = set(overrides) - set(self.params)
        if unknown:
            raise ConfigError(f"unknown parameters {sorted(unknown)}; known: {list(self.params)}")
        vals = []
        for p in self.params.values():
            v = overrides.get(p.name, p.value)
            vals.append(np.asarray(check_vector(v, p.symbol.numel(), what=f"parameter {p.name}")))
        return np.concatenate(vals) if vals else np.zeros(0)

    def node_state(self, name: str) -> ca.SX:
        """The node state ``name`` as users see it (a rotation as its 3 x 3 matrix, a point of
        S^2 or R^n as a vector), for costs, bounds and terminal costs: a reduced Lagrangian
        never depends on a group state, but a keep-out cone or a tracking cost may."""
        i, f = self.groupoid.by_state(name)
        v = f.shown(self.s[self.groupoid.state_layout.slices[i]])
        shape = f.shown_shape
        return ca.reshape(v, shape[1], shape[0]).T if len(shape) == 2 else v  # type: ignore[return-value]  # Array = Any (lie/group.py)

    def state(self, name: str) -> ca.SX:
        """Base coordinates of the factor whose node state is ``name`` (e.g. Gamma, theta)."""
        i, f = self.groupoid.by_state(name)
        if f.base_size == 0:
            raise ConfigError(
                f"{name} is a group state over a point: a reduced Lagrangian cannot depend on "
                "it; use its velocity instead"
            )
        return self.q[self.groupoid.base_layout.slices[i]]

    def velocity(self, name: str) -> ca.SX:
        """The velocity symbol of one factor (e.g. Omega, dtheta)."""
        i, _ = self.groupoid.by_velocity(name)
        return self.y[self.groupoid.velocity_layout.slices[i]]

    def acceleration(self, name: str) -> ca.SX:
        """The rate of a velocity (second-order problems only)."""
        if self.order != 2:
            raise ConfigError("accelerations exist in second-order problems only (order=2)")
        i, _ = self.groupoid.by_velocity(name)
        return self.dy[self.groupoid.velocity_layout.slices[i]]

    def _indices(self, actuated: str | Sequence[str] | Sequence[int]) -> list[int]:
        if isinstance(actuated, str):
            actuated = [actuated]
        out: list[int] = []
        for a in actuated:
            if isinstance(a, str):
                i, _ = self.groupoid.by_velocity(a)
                s = self.groupoid.velocity_layout.slices[i]
                out.extend(range(s.start, s.stop))
            else:
                out.append(int(a))
        return out

    # -- the continuous problem ------------------------------------------------------------

    def mechanics(self, lagrangian: ca.SX,
                  actuated: str | Sequence[str] | Sequence[int] | None = None,
                  input_matrix: Any = None, control_names: Sequence[str] | None = None,
                  force: Any = None) -> ca.SX:
        """Controlled Euler-Lagrange dynamics of ``lagrangian`` (second-order problems).

        The Lagrangian ``l(q, g, y)`` may read the node states of group factors
        (:meth:`node_state`: gravity ``m gravity p_3`` on SE(3)); their trivialised
        derivative enters the equations (forced Euler-Poincare, :mod:`.mechanics`).

        ``actuated`` names velocities (or indices of y) that carry the generalised force
        (default: all of them); the rest become constraints ``Phi^A = 0``. Either

        * ``input_matrix`` (square, an expression of q, g and the parameters; default I):
          ``F = input_matrix @ u``, the controls u are recovered from the actuated
          equations and returned as expressions of (q, g, y, dy); or
        * ``force``: ``F(q, g, y, u)`` on the actuated components, an expression of the
          controls declared with :meth:`control` (``vertcat(tau, 0, 0, f)``: thrust along
          body z) — fewer controls than actuated components is underactuation. Returns the
          stacked controls.
        """
        if self.order != 2:
            raise ConfigError("mechanics() builds a second-order problem; use order=2")
        if self.dynamics is not None:
            raise ConfigError("mechanics() was already called for this problem")
        lagrangian = sx(lagrangian, "the Lagrangian")
        self._check_symbols(lagrangian, "the Lagrangian", rates=False, states=True)
        if actuated is None:
            actuated = list(range(self.y.numel()))
        if force is not None:
            if input_matrix is not None:
                raise ConfigError("mechanics(): give input_matrix (F = B u, controls recovered "
                                  "from the dynamics) or force (controls of their own), not "
                                  "both")
            if not self.inputs:
                raise ConfigError("mechanics(force=...): declare the controls first, e.g. "
                                  "f = pb.control('f'); tau = pb.control('tau', 3)")
            if control_names is not None:
                raise ConfigError("mechanics(force=...): the controls are named by "
                                  "pb.control(name, size); drop control_names")
            force = ca.vec(sx(force, "the force"))
            self._check_symbols(force, "the force", rates=False, states=True, controls=True)
            self._check_controls_enter(force)
        elif self.inputs:
            raise ConfigError(f"controls {list(self.inputs)} were declared with pb.control: "
                              "pass the generalised force they exert, "
                              "mechanics(l, actuated=..., force=...)")
        else:
            input_matrix = None if input_matrix is None else sx(input_matrix, "the input matrix")
            if input_matrix is not None:
                self._check_symbols(input_matrix, "the input matrix", rates=False,
                                    velocities=False, states=True)
        mech = split(self.groupoid, lagrangian, self.q, self.y, self.dy,
                     self._indices(actuated), input_matrix, self.s, force, self.U)
        self.dynamics = mech
        if mech.phi.numel():
            self.subject_to(mech.phi, name="Phi")
        if force is None:
            names = list(control_names or [f"u{i + 1}" for i in range(mech.u.numel())])
            self.report_controls(mech.u, names)
        return mech.u

    def _check_controls_enter(self, force: ca.SX) -> None:
        """Every declared control must push somewhere, and independently of the others: the
        Jacobian dF/du has full column rank at sample states."""
        unused = [n for n, sym in self.inputs.items() if not ca.depends_on(force, sym)]
        if unused:
            raise ConfigError(f"the force does not depend on the controls {unused}: a control "
                              "that exerts no force cannot be determined; use it in force= "
                              "or remove it")
        args = ca.vertcat(self.q, self.s, self.y, self.P)
        rng = np.random.default_rng(0)
        samples = []
        for _ in range(3):
            s = np.concatenate([f.sample_state(rng) for f in self.groupoid.factors]) \
                if self.groupoid.factors else np.zeros(0)
            q = np.array(ca.Function("base", [self.s], [self.groupoid.base(self.s)])(s)
                         ).ravel()
            samples.append(np.concatenate([q, s, rng.normal(size=self.y.numel()),
                                           self.parameter_values()]))
        rank = control_rank(force, self.U, args, np.array(samples))
        if rank < self.U.numel():
            raise ConfigError(
                f"the {self.U.numel()} controls are not independent in the force: dF/du has "
                f"rank {rank} at sample states, so some combination of them exerts no force "
                "and cannot be determined; remove or merge controls")

    def minimize(self, integrand: ca.SX) -> None:
        """Set the running cost: ``int integrand dt`` (Ltilde for order 2, l for order 1); it
        may depend on the node states (:meth:`node_state`), e.g. to track an attitude."""
        integrand = sx(integrand, "the cost integrand")
        if integrand.shape != (1, 1):
            raise DimensionError(f"the cost integrand is a scalar, got shape {integrand.shape}")
        self._check_symbols(integrand, "the cost", states=True, controls=True)
        self.cost = integrand

    def terminal_cost(self, expr: ca.SX) -> None:
        """Add a Mayer term ``expr(s_N, y_N)`` on the final node (order 1: ``expr(s_N)``)."""
        expr = sx(expr, "the terminal cost")
        if expr.shape != (1, 1):
            raise DimensionError(f"a terminal cost is a scalar, got shape {expr.shape}")
        self._check_symbols(expr, "terminal cost", states=True, rates=False,
                            velocities=self.end_velocities)
        self.terminal = expr if self.terminal is None else self.terminal + expr

    def objective(self, effort: float = 1.0, time: float = 0.0) -> None:
        """Weigh the running cost (effort) against the final time: the NLP minimises
        ``effort * int cost dt + time * T`` (+ the terminal cost). A time weight needs a free
        horizon (:meth:`horizon` with ``free=True``)."""
        self.weights = {"effort": number(effort, "objective.effort"),
                        "time": number(time, "objective.time")}
        if self.weights["effort"] < 0 or self.weights["time"] < 0:
            raise ConfigError(f"objective weights must be >= 0, got {self.weights}")

    def minimize_time(self, effort: float = 0.0) -> None:
        """Minimum time: ``T + effort * int cost dt`` (effort 0: pure minimum time; a small
        effort regularises the controls, e.g. ``1 + rho |u|^2``)."""
        self.objective(effort=effort, time=1.0)
        if self.cost is None:
            self.cost = ca.SX(0)

    def bound(self, expr: Any, lower: Any = None, upper: Any = None, name: str | None = None
              ) -> None:
        """Impose ``lower <= expr <= upper`` wherever the scheme evaluates its constraints
        (the nodes for order2, the Gauss points for order4, ...).

        ``expr`` is any expression of q, the node states, y, dy (order 2) and the parameters
        — a control, a velocity, a position, ``dot(R e1, s)`` for a keep-out cone. ``lower``
        and ``upper`` are numbers, lists (per component), None (that side open, also per
        component) or expressions of the parameters (they change without a rebuild).
        """
        expr = ca.vec(sx(expr, f"bound {name or ''}".strip()))
        self._check_symbols(expr, f"bound {name or ''}".strip(), states=True, controls=True)
        n = expr.numel()
        label = name or f"bound{len(self.inequalities) + 1}"
        if any(b.name == label for b in self.inequalities):
            raise ConfigError(f"bound name {label!r} used twice")
        sides = [self._side(v, n, label, inf) for v, inf in ((lower, -np.inf), (upper, np.inf))]
        if lower is None and upper is None:
            raise ConfigError(f"bound {label!r}: give a lower or an upper bound (or both)")
        self.inequalities.append(Inequality(label, expr, *sides))

    def _side(self, value: Any, n: int, name: str, inf: float) -> ca.SX:
        """One side of a bound as a column of n parameter expressions (+-inf where open);
        ``value`` is None, a number, an expression or a list mixing them (per component)."""
        def one(v: Any) -> ca.SX:
            if v is None:
                return ca.SX(inf)
            if isinstance(v, (ca.SX, ca.MX)):
                return ca.vec(sx(v, f"a side of bound {name!r}"))
            if isinstance(v, (float, np.floating)) and np.isinf(v):
                return ca.SX(float(v))  # +-inf: that side open
            return ca.SX(number(v, f"bound {name!r}"))

        parts = value if isinstance(value, (list, tuple, np.ndarray)) else [value]
        side = ca.vertcat(*[one(v) for v in np.asarray(parts, dtype=object).ravel()]) \
            if not isinstance(value, (ca.SX, ca.MX)) else one(value)
        self._check_symbols(side, f"bound {name!r}", params_only=True)
        if side.numel() == 1 and n > 1:
            side = ca.repmat(side, n, 1)
        if side.numel() != n:
            raise DimensionError(f"bound {name!r}: {side.numel()} bounds for {n} expressions")
        return side

    def subject_to(self, expr: ca.SX, name: str = "c") -> None:
        """Add equality constraints ``expr = 0`` along the trajectory, imposed wherever the
        scheme evaluates its constraints; ``expr`` reads q, the node states (``R e_3 = e_3``),
        the velocities, their rates (order 2), the controls and the parameters."""
        expr = ca.vec(sx(expr, f"constraint {name}"))
        self._check_symbols(expr, f"constraint {name}", states=True, controls=True)
        if any(n == name for n, _ in self.constraints):
            raise ConfigError(f"constraint name {name!r} used twice")
        self.constraints.append((name, expr))

    def conserved(self, name: str, expr: ca.SX) -> None:
        """Declare ``expr(q, y)`` conserved by the dynamics for every control (a Casimir).

        Its final value is then fixed by the initial one, and a final condition that it
        already determines is reported as over-determined before IPOPT runs (see
        :mod:`ocgroupoid.nlp.boundary`, which also checks the claim against the constraints).
        """
        if self.order != 2 or not self.constraints:
            raise ConfigError(f"conserved quantity {name!r}: declare it after mechanics() or "
                              "subject_to() of a second-order problem (order=2)")
        self._end_expression(name, expr, self.invariants, "conserved quantity")

    def final_condition(self, name: str, expr: ca.SX) -> None:
        """Impose ``expr(q_N, g_N, y_N) = 0`` on the final node (order 1: ``expr(q_N, g_N)``),
        for conditions that are not a prescribed value of a state or velocity component
        (``R_N e_3 = e_3``: upright, heading free)."""
        self._end_expression(name, expr, self.final_conditions, "final condition", states=True)

    def _end_expression(self, name: str, expr: ca.SX, where: list[tuple[str, ca.SX]],
                        what: str, states: bool = False) -> None:
        expr = ca.vec(sx(expr, f"{what} {name}"))
        self._check_symbols(expr, f"{what} {name!r}", states=states, rates=False,
                            velocities=self.order == 2)
        if any(n == name for n, _ in where):
            raise ConfigError(f"{what} name {name!r} used twice")
        where.append((name, expr))

    def report_controls(self, expr: ca.SX, names: Sequence[str]) -> None:
        """Declare which expressions are the controls the Solution reports."""
        expr = ca.vec(sx(expr, "the controls"))
        if self.inputs:
            raise ConfigError(f"the controls {list(self.inputs)} were declared with "
                              "pb.control and are reported by their names")
        if len(names) != expr.numel():
            raise DimensionError(f"{expr.numel()} controls but {len(names)} names")
        self._check_symbols(expr, "the controls", states=True)
        self.controls = list(zip(names, ca.vertsplit(expr)))

    def _check_symbols(self, expr: ca.SX, what: str, states: bool = False,
                       rates: bool = True, velocities: bool = True,
                       params_only: bool = False, controls: bool = False) -> None:
        """Refuse symbols that ``what`` may not read, or that are not this problem's
        (compared by identity, not by name); the message names them as the user does."""
        groups = [("the parameters", self.P)]
        if not params_only:
            groups.append(("the base coordinates (pb.state)", self.q))
            if states:
                groups.append(("the node states (pb.node_state)", self.s))
            if velocities:
                groups.append(("the velocities", self.y))
            if rates and self.order == 2:
                groups.append(("their rates (pb.acceleration)", self.dy))
            if controls:
                groups.append(("the controls (pb.control)", self.U))
        allowed = ca.vertsplit(ca.vertcat(*[g for _, g in groups]))
        bad = [v for v in ca.symvar(expr) if not any(ca.is_equal(v, a) for a in allowed)]
        if not bad:
            return
        mine = symbol_labels(self)
        known = list(dict.fromkeys(label for v in bad for sym, label in mine
                                   if ca.is_equal(v, sym)))
        strangers = [v.name() for v in bad if not any(ca.is_equal(v, sym) for sym, _ in mine)]
        may = ", ".join(n for n, _ in groups)
        parts = []
        if known:
            parts.append(f"{what} may not depend on {', '.join(known)}: it may read {may}")
        if strangers:
            parts.append(foreign_message(what, strangers))
        raise ConfigError("; ".join(parts))

    # -- boundary conditions -------------------------------------------------------------

    def initial(self, **values: Any) -> None:
        """Prescribe initial states/velocities by name (None = free)."""
        self._set(self.start, values, "initial")

    def final(self, **values: Any) -> None:
        """Prescribe final states/velocities by name (None = free)."""
        self._set(self.end, values, "final")

    def _set(self, where: Boundary, values: dict[str, Any], end: str) -> None:
        for name, value in values.items():
            if name in self.groupoid.state_names:
                where.states[name] = self.check_state(name, value, end)
            elif name in self.groupoid.velocity_names:
                if not self.end_velocities:
                    raise ConfigError(
                        f"{end}.{name}: a first-order problem takes no velocity conditions"
                    )
                where.velocities[name] = self.check_velocity(name, value, end)
            else:
                raise ConfigError(
                    f"{end}.{name}: unknown; states are {self.groupoid.state_names}, "
                    f"velocities {self.groupoid.velocity_names}"
                )

    def check_state(self, name: str, value: Any, end: str) -> Any:
        """Validate a state value: None, or numeric (componentwise None for R^n)."""
        _, f = self.groupoid.by_state(name)
        if value is None:
            return None
        if f.componentwise:
            return check_vector(value, f.state_size, allow_none=True, what=f"{end}.{name}")
        return f.parse_state(value)

    def check_velocity(self, name: str, value: Any, end: str) -> list[float | None] | None:
        """Validate a velocity value: None or a vector with optional None components."""
        _, f = self.groupoid.by_velocity(name)
        if value is None:
            return None
        return check_vector(value, f.algebra_dim, allow_none=True, what=f"{end}.{name}")

    def horizon(self, T: float, free: bool = False, T_min: float | None = None,
                T_max: float | None = None) -> None:
        """Set the final time T (> 0). ``free=True`` makes T a decision variable (T is then its
        initial guess), within ``[T_min, T_max]`` (seed 001, §6.3: time as a variable of the
        discrete problem, uniform steps h = T/N or adaptive ones)."""
        self.T = check_horizon(T)
        self.T_free = bool(free)
        lo = 0.0 if T_min is None else check_horizon(T_min)
        hi = np.inf if T_max is None else check_horizon(T_max)
        if not free and (T_min is not None or T_max is not None):
            raise ConfigError("T_min and T_max bound a free horizon: call horizon(T, free=True, "
                              "T_min=..., T_max=...)")
        if lo > hi or (free and not lo <= self.T <= hi):
            raise ConfigError(f"the horizon guess T = {self.T} must lie in [T_min, T_max] = "
                              f"[{lo}, {hi}]")
        self.T_bounds = (lo, hi)

    def guesses(self, hook: "GuessHook") -> None:
        """Register model-specific initial guesses for multi-start.

        ``hook(problem, context)`` returns labelled velocity arrays (N x dim y), one row per
        interval; ``context`` is a :class:`GuessContext` (N, T, parameters, boundary values
        and the preferred geodesic guess).
        """
        self.guess_hook = hook

    def rule(self, name: str, builder: Callable[..., ca.SX]) -> None:
        """Register an alternative discretisation of the constraints of the order2 scheme:
        ``builder(node)`` gets a :class:`ocgroupoid.nlp.schemes.Node`."""
        self.rules[name] = builder

    # -- names and units of what a Solution reports (plots, solution files) ----------------

    def describe(self, name: str, meaning: str | None = None,
                 unit: str | Sequence[str] | None = None,
                 components: Sequence[str] | None = None,
                 group: str | Sequence[str] | None = None) -> None:
        """Say what ``name`` means and its unit, for plots and solution files::

            pb.describe("Omega", "body angular velocity", "rad/s",
                        components=["about body axis 1", "about body axis 2", "about body axis 3"])

        ``name`` is a state, a velocity, a control, ``u`` (all the controls), a constraint
        (its multipliers) or ``t`` (the time axis; "s" unless declared). ``unit`` is one
        string for every component or a list of one per component; ``components`` labels
        each component (the legend); ``group`` (one string, or one per component) names the
        quantity group a component is drawn with: a figure has one panel per (group, unit)
        of a quantity, so components of one unit in different groups get panels of their
        own. A vector state's components are its entries; a group state's are its tangent
        coordinates, in its velocity's order (SO(3): 3 angles; SE(3): 3 angles, then the
        position; SE(2): the heading, then x, y). A later call for the same name replaces an
        earlier one. Undescribed states and velocities of group factors get their units by
        default (:mod:`ocgroupoid.model.units`).
        """
        kind, n = self._quantity(name)
        self.descriptions[name] = describe(kind, n, name, meaning, unit, components, group)

    def _quantity(self, name: str) -> tuple[str, int]:
        """The labels section ``name`` belongs to and its number of components."""
        G = self.groupoid
        controls = [n for n, _ in self.controls]
        constraints = {n: c.numel() for n, c in self.constraints}
        if not isinstance(name, str):
            raise ConfigError(f"describe: a name is a string, got {name!r}")
        if name == "t":
            return "time", 1
        if name in G.state_names:
            _, f = G.by_state(name)
            shape = f.shown_shape  # a matrix: a group element, described in its tangent
            return "states", f.algebra_dim if len(shape) == 2 else int(np.prod(shape))
        if name in G.velocity_names:
            return "velocities", G.by_velocity(name)[1].algebra_dim
        if name in controls:
            return "controls", 1
        if name in self.inputs:  # a control of its own with several components (tau)
            return "controls", self.inputs[name].numel()
        if name == "u" and controls:
            return "controls", len(controls)
        if name in constraints:
            return "multipliers", constraints[name]
        raise ConfigError(
            f"describe: unknown name {name!r}; known: states {G.state_names}, velocities "
            f"{G.velocity_names}, controls {controls + (['u'] if controls else [])}, "
            f"constraints {list(constraints)}, and t (time). Controls and constraints exist "
            "once mechanics(), report_controls() or subject_to() declared them: describe "
            "them after")

    def labels(self, P: Any = None) -> dict[str, Any]:
        """Names and units of everything a Solution reports, JSON-ready (``Solution.labels``).

        ``time`` (meaning, unit, and ``free: [T_min, T_max]`` for a free horizon); the
        described ``states``, ``velocities`` and ``multipliers`` (name -> meaning, components,
        units); ``controls`` (one label and unit per control, in order); ``final``: which
        final states and velocities are prescribed (True, False, or per component);
        ``bounds``: one entry per bound row (name, component, the quantity it limits if it is
        a control, a velocity or a vector state component, and its sides at the parameter
        values P, default the declared ones; None where a side is open).
        """
        d = self.descriptions
        time = d.get("t")
        out: dict[str, Any] = {"time": {"meaning": time.meaning if time else "time",
                                        "unit": time.units[0] if time else "s"}}
        if self.T_free:
            out["time"]["free"] = [_finite(v) for v in self.T_bounds]
        for kind in ("states", "velocities", "multipliers"):
            out[kind] = {n: v.as_dict() for n, v in d.items() if v.kind == kind}
        for f in self.groupoid.factors:  # the defaults of what the model left undescribed
            for kind, n in (("states", f.state), ("velocities", f.velocity)):
                default = default_description(f, kind, out["time"]["unit"], d.get(f.state))
                if n not in d and default is not None:
                    out[kind][n] = default.as_dict()
        names = [n for n, _ in self.controls]
        if names:
            out["controls"] = control_labels(
                names, {n: sym.numel() for n, sym in self.inputs.items()}, d)
        out["final"] = {**{f.state: _prescribed(self.end.states.get(f.state))
                           for f in self.groupoid.factors},
                        **{f.velocity: _prescribed(self.end.velocities.get(f.velocity))
                           for f in self.groupoid.factors if self.end_velocities}}
        out["bounds"] = self._bound_labels(self.parameter_values() if P is None else P)
        return out

    def _bound_labels(self, P: Any) -> list[dict[str, Any]]:
        rows: list[dict[str, Any]] = []
        for b in self.inequalities:
            sides = ca.vertcat(b.lower, b.upper)
            lo, hi = np.split(np.array(ca.Function("sides", [self.P], [sides])(P)).ravel(), 2)
            for i, e in enumerate(ca.vertsplit(b.expr)):
                row = {"name": b.name, "component": i, "lower": _finite(lo[i]),
                       "upper": _finite(hi[i]), "parametric": False, **self._limited(e)}
                for key, side in (("lower", b.lower[i]), ("upper", b.upper[i])):
                    if self.P.numel() and ca.depends_on(side, self.P):
                        row["parametric"] = True
                        row[f"{key}_affine"] = self._affine(side)
                rows.append(row)
        return rows

    def _affine(self, side: ca.SX) -> dict[str, Any] | None:
        """``side = constant + sum over parameters of gradient . value`` when it is affine in
        the parameters (``-tau_max``), so that a reader evaluates it at other values; else
        None."""
        if not ca.is_linear(side, self.P):
            return None
        grad, c0 = ca.Function("affine", [self.P], [ca.jacobian(side, self.P), side])(
            np.zeros(self.P.numel()))
        g = np.array(grad).ravel()
        return {"constant": float(c0), "gradient": {
            name: g[sl].tolist() for name, sl in self.parameter_slices.items() if g[sl].any()}}

    def _limited(self, e: ca.SX) -> dict[str, Any]:
        """The reported quantity a bound row limits: a control, or a component of a velocity
        or of a vector state; ``quantity`` None for any other expression."""
        G = self.groupoid
        for j, (n, c) in enumerate(self.controls):
            if ca.is_equal(e, c, 64):
                return {"quantity": "controls", "of": n, "index": j}
        if e.is_symbolic():
            for f, vs in zip(G.factors, G.velocity_layout.slices):
                for k in range(vs.start, vs.stop):
                    if ca.is_equal(e, self.y[k]):
                        return {"quantity": "velocities", "of": f.velocity, "index": k - vs.start}
            for f, qs in zip(G.factors, G.base_layout.slices):
                for k in range(qs.start, qs.stop):
                    if f.componentwise and ca.is_equal(e, self.q[k]):
                        return {"quantity": "states", "of": f.state, "index": k - qs.start}
        return {"quantity": None, "of": None, "index": None}


def _finite(v: Any) -> float | None:
    """A JSON number, None for an infinite (open) side."""
    v = float(v)
    return v if np.isfinite(v) else None


def _prescribed(value: Any) -> bool | list[bool]:
    """Whether a boundary value prescribes its state: wholly, not at all, or per component."""
    if value is None:
        return False
    if isinstance(value, (list, tuple)) and any(v is None for v in value):
        return [v is not None for v in value]
    return True
