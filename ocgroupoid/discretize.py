"""Stage functions of the discrete problem: one CasADi Function per kind of stage.

With ``w_k = tau(h xi_k)`` (seed 000, eq. 27) each factor steps ``s_{k+1} = step(s_k, w_k)``.

Second-order problems use the discrete second-order Lagrangian of eq. 27-29 on composable
pairs ``(w_{k-1}, w_k)``, i.e. at node k:

    L_d(w_{k-1}, w_k) = h Ltilde(q_k, xi_{k-1/2}, xi_{k-1,k}),
    xi_{k-1/2} = (xi_{k-1} + xi_k)/2,   xi_{k-1,k} = (xi_k - xi_{k-1})/h,

and the constraints ``Phi_d = h Phi(...)`` likewise (eq. 17-18). At the ends the prescribed
node velocity V defines a ghost ``xi_{-1} = 2 V_0 - xi_0`` (``xi_N = 2 V_N - xi_{N-1}``), and
the end stages carry weight 1/2: the action sum is the trapezoidal rule of the cost, second
order in h.

First-order problems use ``L_d(g_k) = h l(q_{k+1/2}, xi_k)`` with the midpoint
``q_{k+1/2} = base(step(s_k, tau(h xi_k/2)))`` and ``phi_d = h psi(...)`` (seed 001, §6.1).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import casadi as ca

from .errors import ConfigError
from .lie.retraction import RETRACTION_NAMES, Retraction, retraction

if TYPE_CHECKING:
    from .problem import Problem

DEFAULT_RULE = "midpoint"


@dataclass(frozen=True)
class Discretization:
    """N intervals, a retraction for the group factors, and a rule for the constraints."""

    N: int
    retraction: str = "cayley"
    rule: str = DEFAULT_RULE

    def __post_init__(self) -> None:
        if not isinstance(self.N, int) or isinstance(self.N, bool) or self.N < 2:
            raise ConfigError(f"N must be an integer >= 2, got {self.N!r}")
        if self.retraction not in RETRACTION_NAMES:
            raise ConfigError(
                f"unknown retraction {self.retraction!r}; choose one of "
                f"{', '.join(RETRACTION_NAMES)}"
            )


@dataclass
class Node:
    """What a constraint rule sees at node k of a second-order problem."""

    problem: "Problem"
    s: ca.SX  # node state s_k
    xi_prev: ca.SX  # xi_{k-1}
    xi_next: ca.SX  # xi_k
    h: ca.SX
    retractions: list[Retraction]

    @property
    def q(self) -> ca.SX:
        return self.problem.groupoid.base(self.s)

    @property
    def y(self) -> ca.SX:
        return (self.xi_prev + self.xi_next) / 2

    @property
    def dy(self) -> ca.SX:
        return (self.xi_next - self.xi_prev) / self.h

    def substitute(self, expr: ca.SX) -> ca.SX:
        """Evaluate an expression of (q, y, dy) at this node with the midpoint rule."""
        pb = self.problem
        return ca.substitute([expr], [pb.q, pb.y, pb.dy], [self.q, self.y, self.dy])[0]


class Stages:
    """The stage Functions of one problem under one discretisation."""

    def __init__(self, problem: "Problem", disc: Discretization) -> None:
        G = problem.groupoid
        if problem.cost is None:
            raise ConfigError(f"problem {problem.name!r} has no cost; call minimize()")
        if disc.rule != DEFAULT_RULE and disc.rule not in problem.rules:
            known = [DEFAULT_RULE, *problem.rules]
            raise ConfigError(f"unknown rule {disc.rule!r} for {problem.name}; choose {known}")
        self.problem, self.disc = problem, disc
        self.retractions = [retraction(disc.retraction, f.group) for f in G.factors]
        ds, dg = G.state_size, G.algebra_dim
        s, s1 = ca.SX.sym("s", ds), ca.SX.sym("s1", ds)
        xi, xp, xn = ca.SX.sym("xi", dg), ca.SX.sym("xi_prev", dg), ca.SX.sym("xi_next", dg)
        T, P = ca.SX.sym("T"), problem.P
        h = T / disc.N
        self.step = ca.Function("step", [s, xi, T], [self._step(s, xi, h)],
                                ["s", "xi", "T"], ["s_next"])
        self.recon = ca.Function("recon", [s, xi, s1, T], [s1 - self._step(s, xi, h)],
                                 ["s", "xi", "s_next", "T"], ["residual"])
        target = ca.SX.sym("target", G.target_size)
        charts = [f.chart(s[ss], target[ts]) for f, ss, ts in
                  zip(G.factors, G.state_layout.slices, G.target_layout.slices)]
        self.chart = ca.Function("chart", [s, target], [ca.vertcat(*charts)])
        ends = [c for _, c in problem.final_conditions]
        self.final_conditions = ca.Function(
            "final_conditions", [s, xi, P],
            [ca.substitute(ca.vertcat(*ends), ca.vertcat(problem.q, problem.y),
                           ca.vertcat(G.base(s), xi)) if ends else ca.SX(0, 1)],
            ["s", "y", "P"], ["residual"])
        u = ca.vertcat(*[c for _, c in problem.controls]) if problem.controls else ca.SX(0, 1)
        if problem.order == 2:
            node = Node(problem, s, xp, xn, h, self.retractions)
            phi = self._node_constraints(node)
            self.node = ca.Function(
                "node", [s, xp, xn, T, P],
                [h * node.substitute(problem.cost), h * phi, node.substitute(u)],
                ["s", "xi_prev", "xi_next", "T", "P"], ["L", "Phi", "u"])
        else:
            q_mid = G.base(self._step(s, xi / 2, h))
            args = [problem.q, problem.y]
            psi = ca.vertcat(*[c for _, c in problem.constraints]) if problem.constraints \
                else ca.SX(0, 1)
            sub = ca.substitute([problem.cost, psi, u], args, [q_mid, xi])
            self.node = ca.Function("interval", [s, xi, T, P], [h * sub[0], h * sub[1], sub[2]],
                                    ["s", "xi", "T", "P"], ["L", "Phi", "u"])

    def _step(self, s: ca.SX, xi: ca.SX, h: ca.SX) -> ca.SX:
        G = self.problem.groupoid
        return ca.vertcat(*[f.step(s[ss], r, h * xi[vs]) for f, r, ss, vs in
                            zip(G.factors, self.retractions, G.state_layout.slices,
                                G.velocity_layout.slices)])

    def _node_constraints(self, node: Node) -> ca.SX:
        pb = self.problem
        if self.disc.rule != DEFAULT_RULE:
            return ca.vec(ca.SX(pb.rules[self.disc.rule](node)))
        parts = [node.substitute(c) for _, c in pb.constraints]
        return ca.vertcat(*parts) if parts else ca.SX(0, 1)

    @property
    def n_constraints(self) -> int:
        """Rows of Phi_d per node (order 2) or per interval (order 1)."""
        return int(self.node.size1_out(1))
