"""What a problem declares before it states anything: its groupoid and order, the symbols
of the base coordinates, node states, velocities and their rates, the runtime parameters and
the controls of their own.

:class:`Declarations` is the base of :class:`~ocgroupoid.model.problem.Problem`: it holds
every attribute of a problem, which the statement (dynamics, costs, constraints:
:mod:`~ocgroupoid.model.statement`) and the labels (:mod:`~ocgroupoid.model.labels`) build on.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..groupoid.base import Factor
from ..groupoid.product import Groupoid
from .boundary_values import Boundary
from .mechanics import Mechanics
from .units import Description, describe
from .values import check_vector


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


class Declarations:
    """The attributes of a problem and its symbols (see the module docstring)."""

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
        v = f.as_matrix(self.s[self.groupoid.state_layout.slices[i]])
        shape = f.matrix_shape
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
