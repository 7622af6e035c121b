"""The stage Functions every scheme shares: the step on the groupoid, the charts of the final
states, and the user's final conditions.

``step(s, a)`` is the product of the factors' steps by the algebra increment ``a``
(``a = h xi_k`` for a constant velocity on the interval): ``s_{k+1} = step(s_k, tau(a))``,
e.g. ``R_{k+1} = R_k tau(a)`` (seed 000, eq. 27).
"""

from __future__ import annotations

import casadi as ca

from ..errors import ConfigError
from ..lie.retraction import Retraction
from ..model.mechanics import least_squares_controls
from ..model.problem import Problem


class Stages:
    """Scheme-independent stage Functions of one problem under one choice of retraction."""

    def __init__(self, problem: Problem, retractions: list[Retraction]) -> None:
        G = problem.groupoid
        self.problem, self.retractions = problem, retractions
        ds, dg = G.state_size, G.algebra_dim
        s, a, y = ca.SX.sym("s", ds), ca.SX.sym("a", dg), ca.SX.sym("y", dg)
        self.step = ca.Function("step", [s, a], [G.step(s, retractions, a)],
                                ["s", "a"], ["s_next"])
        target = ca.SX.sym("target", G.target_size)
        charts = [f.chart(s[ss], target[ts]) for f, ss, ts in
                  zip(G.factors, G.state_layout.slices, G.target_layout.slices)]
        self.chart = ca.Function("chart", [s, target], [ca.vertcat(*charts)])
        ends = [c for _, c in problem.final_conditions]
        self.final_conditions = ca.Function(
            "final_conditions", [s, y, problem.P],
            [ca.substitute(ca.vertcat(*ends), ca.vertcat(problem.q, problem.s, problem.y),
                           ca.vertcat(G.base(s), s, y)) if ends else ca.SX(0, 1)],
            ["s", "y", "P"], ["residual"])
        #: the controls that are decision variables (the controls of their own)
        self.U: ca.SX = problem.U
        #: ``estimate(s, y, dy, P, u0) -> u``: the controls declared as variables that best
        #: explain the motion (least squares on the actuated equations, from u0), where a
        #: scheme carries none (the guesses' controls); None without them
        self.estimate: ca.Function | None = None
        if self.n_u:
            mech = problem.dynamics
            if mech is None or mech.force is None:
                raise ConfigError(f"{problem.name}: the controls {list(problem.inputs)} need "
                                  "the force they exert: call pb.mechanics(l, actuated=..., "
                                  "force=...)")
            dy, u0 = ca.SX.sym("dy", dg), ca.SX.sym("u0", self.n_u)
            affine = not ca.depends_on(ca.jacobian(mech.force, problem.U), problem.U)
            u = least_squares_controls(mech.force, problem.U, mech.EL[list(mech.actuated)],
                                       u0, affine)
            self.estimate = ca.Function("control_estimate", [s, y, dy, problem.P, u0],
                                        self.at([u], s, y, dy), ["s", "y", "dy", "P", "u0"],
                                        ["u"])

    @property
    def n_u(self) -> int:
        """The number of controls that are decision variables (:attr:`U`)."""
        return int(self.U.numel())

    @property
    def controls(self) -> ca.SX:
        """The reported controls as one column of expressions in (q, y[, dy], P)."""
        pb = self.problem
        return ca.vertcat(*[c for _, c in pb.controls]) if pb.controls else ca.SX(0, 1)

    @property
    def constraints(self) -> ca.SX:
        """All path constraints (Phi or psi) as one column."""
        pb = self.problem
        return ca.vertcat(*[c for _, c in pb.constraints]) if pb.constraints else ca.SX(0, 1)

    @property
    def constraint_names(self) -> list[str]:
        """One name per row of :attr:`constraints`, e.g. ``Phi``."""
        return [n for n, c in self.problem.constraints for _ in range(c.numel())]

    @property
    def inequalities(self) -> ca.SX:
        """The expressions of every bound, as one column."""
        pb = self.problem
        return ca.vertcat(*[b.expr for b in pb.inequalities]) if pb.inequalities \
            else ca.SX(0, 1)

    @property
    def inequality_names(self) -> list[str]:
        """One name per inequality row, e.g. ``torque[2]``."""
        return [f"{b.name}[{i}]" if b.expr.numel() > 1 else b.name
                for b in self.problem.inequalities for i in range(b.expr.numel())]

    def inequality_bounds(self, points: int = 1) -> tuple[ca.SX, ca.SX] | None:
        """Lower and upper bounds of the inequality rows of a column with ``points`` times."""
        pb = self.problem
        if not pb.inequalities:
            return None
        lo = ca.vertcat(*[b.lower for b in pb.inequalities])
        hi = ca.vertcat(*[b.upper for b in pb.inequalities])
        return ca.repmat(lo, points, 1), ca.repmat(hi, points, 1)

    def running_cost(self) -> ca.SX:
        """The running cost weighted by the objective's effort weight."""
        pb = self.problem
        assert pb.cost is not None
        return pb.weights["effort"] * pb.cost

    def at(self, exprs: list[ca.SX], s: ca.SX, y: ca.SX, dy: ca.SX | None = None,
           u: ca.SX | None = None) -> list[ca.SX]:
        """Expressions of (q, node states, y[, dy][, u]) evaluated at a point with state s
        (u: the values of the controls that are variables, :attr:`U`)."""
        pb, G = self.problem, self.problem.groupoid
        old, new = [pb.q, pb.s, pb.y], [G.base(s), s, y]
        if dy is not None:
            old.append(pb.dy)
            new.append(dy)
        if u is not None and self.n_u:
            old.append(self.U)
            new.append(u)
        return ca.substitute(exprs, old, new)
