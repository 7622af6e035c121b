"""What a problem states: its dynamics, its cost, its constraints and its bounds.

:class:`Statement` adds to the declarations (:mod:`~ocgroupoid.model.declarations`) the
methods that write the continuous problem — ``mechanics``, ``minimize``, ``terminal_cost``,
``objective``, ``bound``, ``subject_to``, ``conserved``, ``final_condition`` — each checking
that its expressions read only the symbols they may
(:func:`~ocgroupoid.model.symbols.check_symbols`).
"""

from __future__ import annotations

from typing import Any, Sequence

import casadi as ca
import numpy as np

from ..errors import ConfigError, DimensionError
from .declarations import Declarations, Inequality, sx
from .mechanics import control_rank, split
from .symbols import check_symbols
from .values import number


class Statement(Declarations):
    """The dynamics, costs, constraints and bounds of a problem (see the module docstring)."""

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
        check_symbols(self, lagrangian, "the Lagrangian", rates=False, states=True)
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
            check_symbols(self, force, "the force", rates=False, states=True, controls=True)
            self._check_controls_enter(force)
        elif self.inputs:
            raise ConfigError(f"controls {list(self.inputs)} were declared with pb.control: "
                              "pass the generalised force they exert, "
                              "mechanics(l, actuated=..., force=...)")
        else:
            input_matrix = None if input_matrix is None else sx(input_matrix, "the input matrix")
            if input_matrix is not None:
                check_symbols(self, input_matrix, "the input matrix", rates=False,
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
        check_symbols(self, integrand, "the cost", states=True, controls=True)
        self.cost = integrand

    def terminal_cost(self, expr: ca.SX) -> None:
        """Add a Mayer term ``expr(s_N, y_N)`` on the final node (order 1: ``expr(s_N)``)."""
        expr = sx(expr, "the terminal cost")
        if expr.shape != (1, 1):
            raise DimensionError(f"a terminal cost is a scalar, got shape {expr.shape}")
        check_symbols(self, expr, "terminal cost", states=True, rates=False,
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
        check_symbols(self, expr, f"bound {name or ''}".strip(), states=True, controls=True)
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
        check_symbols(self, side, f"bound {name!r}", params_only=True)
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
        check_symbols(self, expr, f"constraint {name}", states=True, controls=True)
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
        check_symbols(self, expr, f"{what} {name!r}", states=states, rates=False,
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
        check_symbols(self, expr, "the controls", states=True)
        self.controls = list(zip(names, ca.vertsplit(expr)))

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
