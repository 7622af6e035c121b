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

The class is written in four modules, one idea each: the declarations (groupoid, symbols,
parameters, controls: :mod:`~ocgroupoid.model.declarations`), the statement (dynamics, costs,
constraints, bounds: :mod:`~ocgroupoid.model.statement`), the labels (names and units:
:mod:`~ocgroupoid.model.labels`) and, here, the boundary conditions, the horizon and the
hooks of a model (guesses, rules); boundary values are parsed by
:mod:`~ocgroupoid.model.boundary_values`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..groupoid.base import Factor
from ..groupoid.product import Groupoid
from .boundary_values import Boundary, prescribe, state_value, velocity_value
from .labels import Labels
from .statement import Statement
from .values import check_horizon

__all__ = ["Boundary", "GuessContext", "GuessHook", "Problem"]


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


class Problem(Statement, Labels):
    """An optimal-control problem on a product Lie groupoid (see the module docstring)."""

    def __init__(self, groupoid: Groupoid | Factor, name: str = "problem", order: int = 2):
        super().__init__(groupoid, name, order)
        self.guess_hook: GuessHook | None = None
        self.rules: dict[str, Callable[..., ca.SX]] = {}

    # -- boundary conditions -------------------------------------------------------------

    def initial(self, **values: Any) -> None:
        """Prescribe initial states/velocities by name (None = free)."""
        prescribe(self.start, values, "initial", self.groupoid, self.end_velocities)

    def final(self, **values: Any) -> None:
        """Prescribe final states/velocities by name (None = free)."""
        prescribe(self.end, values, "final", self.groupoid, self.end_velocities)

    def check_state(self, name: str, value: Any, end: str) -> Any:
        """Validate a state value: None, or numeric (componentwise None for R^n)."""
        return state_value(self.groupoid, name, value, end)

    def check_velocity(self, name: str, value: Any, end: str) -> list[float | None] | None:
        """Validate a velocity value: None or a vector with optional None components."""
        return velocity_value(self.groupoid, name, value, end)

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
