"""The seeds' second-order schemes (``order2``): one algebra velocity per interval.

With ``w_k = tau(h xi_k)`` (seed 000, eq. 27) each factor steps ``s_{k+1} = step(s_k, w_k)``;
x holds, per interval, ``xi_k`` and ``s_{k+1}``.

Second-order problems (:class:`NodeMidpoint`) use the discrete second-order Lagrangian of
eq. 27-29 on composable pairs ``(w_{k-1}, w_k)``, i.e. at node k:

    L_d(w_{k-1}, w_k) = h Ltilde(q_k, xi_{k-1/2}, xi_{k-1,k}),
    xi_{k-1/2} = (xi_{k-1} + xi_k)/2,   xi_{k-1,k} = (xi_k - xi_{k-1})/h,

and the constraints ``Phi_d = h Phi(...)`` likewise (eq. 17-18). At the ends the prescribed
node velocity V defines a ghost ``xi_{-1} = 2 V_0 - xi_0`` (``xi_N = 2 V_N - xi_{N-1}``), and
the end stages carry weight 1/2: the action sum is the trapezoidal rule of the cost, second
order in h.

First-order problems (:class:`IntervalMidpoint`) use ``L_d(g_k) = h l(q_{k+1/2}, xi_k)`` with
the midpoint ``q_{k+1/2} = base(step(s_k, tau(h xi_k/2)))`` and ``phi_d = h psi(...)``
(seed 001, §6.1).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import casadi as ca
import numpy as np

from ...errors import ConfigError
from ...lie.retraction import Retraction
from ...model.problem import Problem
from ..assembly import Block, Kind
from ..layout import Layout
from .base import DEFAULT_RULE, Pick, Readout, Scheme, columns, piecewise_linear, stage_function


@dataclass
class Node:
    """What a constraint rule sees at node k of a second-order problem."""

    problem: Problem
    s: ca.SX  # node state s_k
    xi_prev: ca.SX  # xi_{k-1}
    xi_next: ca.SX  # xi_k
    h: ca.SX
    retractions: list[Retraction]
    u: ca.SX | None = None  # the node's controls, when declared as variables

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
        """Evaluate an expression of (q, node states, y, dy) at this node (midpoint rule)."""
        pb = self.problem
        old, new = [pb.q, pb.s, pb.y, pb.dy], [self.q, self.s, self.y, self.dy]
        if self.u is not None and self.u.numel():
            old.append(pb.U)
            new.append(self.u)
        return ca.substitute([expr], old, new)[0]


class IntervalVelocities(Scheme):
    """Schemes with one velocity ``xi_k`` per interval and ``s_{k+1} = step(s_k, tau(h xi_k))``
    (both order-2 schemes). x per interval: ``[xi_k, s_{k+1}]``."""

    xi: np.ndarray  # dim y x N

    @property
    def n_stage(self) -> int:
        G = self.problem.groupoid
        return self.N * (G.algebra_dim + G.state_size)

    def index(self, layout: Layout) -> None:
        G = self.problem.groupoid
        dg = G.algebra_dim
        self.layout = layout
        stage = layout.stage[:self.N * (dg + G.state_size)].reshape(self.N, dg + G.state_size).T
        self.xi = stage[:dg]
        self.states = np.hstack([layout.s0[:, None], stage[dg:]])
        self.end_velocity = layout.VN

    def _h(self, T: Any) -> Any:
        return T / self.N

    def reconstruction(self) -> Block:
        """``s_{k+1} - step(s_k, tau(h xi_k)) = 0`` on every interval."""
        G, N, lay = self.problem.groupoid, self.N, self.layout
        assert lay is not None
        ds, dg = G.state_size, G.algebra_dim
        step = self.stages.step
        fun = stage_function("recon", [ds, dg, ds, 1], lambda s, xi, s1, T: (
            ca.SX(1, 1), s1 - step(s, self._h(T) * xi)))
        comps = [f"{f.state}[{j}]" for f in G.factors for j in range(f.state_size)]
        return Block("recon", fun, columns(self.states[:, :N], self.xi, self.states[:, 1:],
                                           lay.T, ncols=N), 1, Kind.RECONSTRUCTION,
                     rows=[f"reconstruction {c}" for c in comps],
                     columns=[f"interval {k}" for k in range(N)],
                     next=slice(ds + dg, 2 * ds + dg))

    def readout_steps(self, pick: Pick) -> ca.MX:
        assert self.layout is not None
        return self._h(pick(self.layout.T)) * pick(self.xi)

    def point(self, XI: ca.MX, pick: Pick) -> list[tuple[np.ndarray, ca.MX]]:
        """Velocities as given, states by forward composition, free end velocities from the
        end intervals."""
        lay = self.layout
        assert lay is not None
        S = self.stages.step.mapaccum(self.N)(pick(lay.s0), self._h(pick(lay.T)) * XI)
        return [(self.xi, XI), (self.states[:, 1:], S), (lay.V0, XI[:, 0]),
                (lay.VN, XI[:, self.N - 1])]

    def unpack(self, w: np.ndarray) -> dict[str, np.ndarray]:
        lay = self.layout
        assert lay is not None
        return {"xi": w[self.xi].T, "s": w[self.states].T, "V0": w[lay.V0], "VN": w[lay.VN],
                "T": w[lay.T][0], "P": w[lay.P]}

    def euler_lagrange(self, lagrangian: ca.Function, reconstruct: ca.Function
                       ) -> Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]:
        """Eq. 13/18 at the interior nodes j = 1..N-1: the derivative of the action sum plus
        multiplier terms along the admissible variation ``w_{j-1} -> w_{j-1} exp(t eta)``,
        ``w_j -> exp(-t eta) w_j`` (seed 000, eq. 11), which moves s_j and leaves every
        other state (and so the reconstruction) unchanged. The gradient comes from CasADi's
        AD of ``lagrangian``, the variation from the retractions' ``dtau_inv`` formulas
        (:meth:`Factor.dxi`); both are built once, the map ``(x, p, lam) -> residuals``
        evaluates them."""
        xs, ps, ls = lagrangian.mx_in()
        gradient = ca.Function("grad", [xs, ps, ls], [ca.gradient(lagrangian(xs, ps, ls), xs)])
        G, N = self.problem.groupoid, self.N
        dg, ds = G.algebra_dim, G.state_size
        xp, xn, s, T = ca.SX.sym("xp", dg), ca.SX.sym("xn", dg), ca.SX.sym("s", ds), \
            ca.SX.sym("T")
        h = self._h(T)
        Dp, Dn, Ds = ca.SX.zeros(dg, dg), ca.SX.zeros(dg, dg), ca.SX.zeros(ds, dg)
        for f, r, vs, ss in zip(G.factors, self.retractions, G.velocity_layout.slices,
                                G.state_layout.slices):
            for a in range(f.algebra_dim):
                eta = ca.SX.zeros(f.algebra_dim)
                eta[a] = 1.0
                dprev, dnext = f.dxi(r, h, xp[vs], xn[vs], eta)
                Dp[vs, vs.start + a] = dprev
                Dn[vs, vs.start + a] = dnext
                Ds[ss, vs.start + a] = f.variation(s[ss], eta)
        variation = ca.Function("variation", [xp, xn, s, T], [Dp, Dn, Ds]).map(N - 1)

        def residual(x: np.ndarray, p: np.ndarray, lam: np.ndarray) -> np.ndarray:
            grad = np.concatenate([np.array(gradient(x, p, lam)).ravel(), np.zeros(p.size)])
            d = self.unpack(np.concatenate([x, p]))
            mats = variation(d["xi"][:-1].T, d["xi"][1:].T, d["s"][1:N].T, d["T"])
            # mapped outputs are [D_1 | D_2 | ...]; as (rows, dim y, node) arrays:
            Dps, Dns, Dss = (np.array(M).reshape(M.shape[0], dg, N - 1, order="F")
                             for M in mats)
            g_prev, g_next = grad[self.xi[:, :-1]], grad[self.xi[:, 1:]]
            g_s = grad[self.states[:, 1:N]]
            return (np.einsum("abj,aj->jb", Dps, g_prev) + np.einsum("abj,aj->jb", Dns, g_next)
                    + np.einsum("abj,aj->jb", Dss, g_s))
        return residual


class NodeMidpoint(IntervalVelocities):
    """Second-order problems: the seeds' node stages, ghosts and trapezoidal end weights."""

    name = "order2"
    accuracy = 2
    problem_order = 2
    summary = ("seed 000 eq. 27-29: node stages on composable pairs, ghost end velocities, "
               "trapezoidal end weights")

    def __init__(self, problem: Problem, N: int, retraction_name: str, rule: str) -> None:
        super().__init__(problem, N, retraction_name, rule)
        if rule != DEFAULT_RULE and rule not in problem.rules:
            known = [DEFAULT_RULE, *problem.rules]
            raise ConfigError(f"unknown rule {rule!r} for {problem.name}; choose {known}")
        G = problem.groupoid
        ds, dg, nu = G.state_size, G.algebra_dim, self.stages.n_u
        s, xp, xn = ca.SX.sym("s", ds), ca.SX.sym("xi_prev", dg), ca.SX.sym("xi_next", dg)
        T, u = ca.SX.sym("T"), ca.SX.sym("u", nu)
        node = Node(problem, s, xp, xn, self._h(T), self.retractions, u)
        if rule != DEFAULT_RULE:
            phi = ca.vec(ca.SX(problem.rules[rule](node)))
        else:
            phi = ca.vertcat(*[node.substitute(c) for _, c in problem.constraints]) \
                if problem.constraints else ca.SX(0, 1)
        h = self._h(T)
        #: ``node(s_k, xi_{k-1}, xi_k, u_k, T, P) -> (L_d, Phi_d, u_k, H_k)`` at node k (H:
        #: the bounds' expressions; u_k: the node's controls when they are variables of their
        #: own, else empty and the controls come out of the dynamics)
        self.node = ca.Function(
            "node", [s, xp, xn, u, T, problem.P],
            [h * node.substitute(self.stages.running_cost()), h * phi,
             node.substitute(self.stages.controls), node.substitute(self.stages.inequalities)],
            ["s", "xi_prev", "xi_next", "u_in", "T", "P"], ["L", "Phi", "u", "H"])
        if nu:
            assert self.stages.estimate is not None
            #: ``node_controls(s_k, xi_{k-1}, xi_k, T, P) -> u_k`` that best explain the
            #: motion at a node (the guesses' controls)
            self.node_controls = ca.Function("node_controls", [s, xp, xn, T, problem.P], [
                self.stages.estimate(s, node.y, node.dy, problem.P, ca.DM.zeros(nu))])

    @property
    def n_stage(self) -> int:
        return super().n_stage + (self.N + 1) * self.stages.n_u

    def index(self, layout: Layout) -> None:
        """x: per interval ``[xi_k, s_{k+1}]``, then the node controls ``u_0 .. u_N`` when
        they are variables of their own."""
        super().index(layout)
        G, nu = self.problem.groupoid, self.stages.n_u
        self.U = layout.stage[self.N * (G.algebra_dim + G.state_size):].reshape(
            self.N + 1, nu).T

    def point(self, XI: ca.MX, pick: Pick) -> list[tuple[np.ndarray, ca.MX]]:
        """As for every interval-velocity scheme; declared controls: those that best explain
        the guess's motion at each node (:attr:`node_controls`)."""
        parts = super().point(XI, pick)
        if not self.stages.n_u:
            return parts
        lay = self.layout
        assert lay is not None
        S = ca.horzcat(pick(lay.s0), parts[1][1])
        prev, nxt = ca.horzcat(XI[:, :1], XI), ca.horzcat(XI, XI[:, -1:])
        return parts + [(self.U, self.node_controls.map(self.N + 1)(S, prev, nxt,
                                                                    pick(lay.T), pick(lay.P)))]

    def unpack(self, w: np.ndarray) -> dict[str, np.ndarray]:
        return {**super().unpack(w), "u": w[self.U].T}

    def blocks(self) -> list[Block]:
        G, N, lay = self.problem.groupoid, self.N, self.layout
        assert lay is not None
        ds, dg, npar = G.state_size, G.algebra_dim, self.problem.P.numel()
        S, XI, T, P = self.states, self.xi, lay.T, lay.P

        def node(weight: float, ghost: str, kind: Kind) -> Any:
            def body(s: ca.SX, a: ca.SX, b: ca.SX, u: ca.SX, t: ca.SX, par: ca.SX) -> Any:
                xp, xn = {"prev": (2 * a - b, b), "next": (a, 2 * b - a), "": (a, b)}[ghost]
                L, phi, _, H = self.node(s, xp, xn, u, t, par)
                return (weight * L, phi) if kind is Kind.PATH else (ca.SX(1, 1), H)
            return body

        U = self.U
        sizes = [ds, dg, dg, self.stages.n_u, 1, npar]
        names = [n for n, c in self.problem.constraints for _ in range(c.numel())]
        rows = {Kind.PATH: [names[r] if r < len(names) else f"Phi[{r}]"
                            for r in range(self.node.size1_out(1))],
                Kind.INEQUALITY: self.stages.inequality_names}
        kinds = [Kind.PATH] + ([Kind.INEQUALITY] if self.problem.inequalities else [])
        stages = (("node0", 0.5, "prev", columns(S[:, 0], lay.V0, XI[:, 0], U[:, 0], T, P,
                                                 ncols=1), [0]),
                  ("node", 1.0, "", columns(S[:, 1:N], XI[:, :N - 1], XI[:, 1:], U[:, 1:N], T,
                                            P, ncols=N - 1), list(range(1, N))),
                  ("nodeN", 0.5, "next", columns(S[:, N], XI[:, N - 1], lay.VN, U[:, N], T, P,
                                                 ncols=1), [N]))
        blocks = [self.reconstruction()]
        for kind in kinds:
            suffix = "" if kind is Kind.PATH else "_bounds"
            bounds = self.stages.inequality_bounds() if kind is Kind.INEQUALITY else None
            for name, weight, ghost, idx, nodes in stages:
                blocks.append(Block(name + suffix, stage_function(
                    name + suffix, sizes, node(weight, ghost, kind)), idx, 1 + npar, kind,
                    rows[kind], [f"node {k}" for k in nodes], np.array(nodes) / N,
                    bounds=bounds))
        return blocks

    def readout(self, pick: Pick) -> Readout:
        """Node velocities ``V_0, (xi_{k-1} + xi_k)/2, V_N`` and node controls."""
        lay, N = self.layout, self.N
        assert lay is not None
        XI, V0, VN, T, P = pick(self.xi), pick(lay.V0), pick(lay.VN), pick(lay.T), pick(lay.P)
        S = ca.horzcat(pick(lay.s0), self.step_over(pick))
        prev = ca.horzcat(2 * V0 - XI[:, 0], XI)
        nxt = ca.horzcat(XI, 2 * VN - XI[:, -1])
        t = np.arange(N + 1) / N
        u = self.node.map(N + 1)(S, prev, nxt, pick(self.U), T, P)[2]
        return Readout(self.readout_steps(pick), S, t,
                       ca.horzcat(V0, (XI[:, :-1] + XI[:, 1:]) / 2, VN), t, u, t,
                       piecewise_linear(u, t, T))


class IntervalMidpoint(IntervalVelocities):
    """First-order problems: one stage per interval at its midpoint (seed 001, §6.1)."""

    name = "order2"
    accuracy = 2
    problem_order = 1
    summary = "seed 001 §6.1: interval stages at the midpoint, h l(q_{k+1/2}, xi_k)"

    def __init__(self, problem: Problem, N: int, retraction_name: str, rule: str) -> None:
        super().__init__(problem, N, retraction_name, rule)
        if rule != DEFAULT_RULE:
            raise ConfigError(f"unknown rule {rule!r} for the first-order problem "
                              f"{problem.name}; choose {DEFAULT_RULE!r}")
        G = problem.groupoid
        s, xi, T = ca.SX.sym("s", G.state_size), ca.SX.sym("xi", G.algebra_dim), ca.SX.sym("T")
        h = self._h(T)
        s_mid = G.step(s, self.retractions, h * xi / 2)
        sub = self.stages.at([self.stages.running_cost(), self.stages.constraints,
                              self.stages.controls, self.stages.inequalities], s_mid, xi)
        #: ``interval(s_k, xi_k, T, P) -> (L_d, phi_d, u_{k+1/2}, H_{k+1/2})`` on interval k
        self.interval = ca.Function("interval", [s, xi, T, problem.P],
                                    [h * sub[0], h * sub[1], sub[2], sub[3]],
                                    ["s", "xi", "T", "P"], ["L", "Phi", "u", "H"])

    def blocks(self) -> list[Block]:
        G, N, lay = self.problem.groupoid, self.N, self.layout
        assert lay is not None
        npar = self.problem.P.numel()

        def body(kind: Kind) -> Any:
            def f(s: ca.SX, xi: ca.SX, t: ca.SX, par: ca.SX) -> Any:
                L, phi, _, H = self.interval(s, xi, t, par)
                return (L, phi) if kind is Kind.PATH else (ca.SX(1, 1), H)
            return f

        names = [n for n, c in self.problem.constraints for _ in range(c.numel())]
        sizes = [G.state_size, G.algebra_dim, 1, npar]
        idx = columns(self.states[:, :N], self.xi, lay.T, lay.P, ncols=N)
        cols, times = [f"interval {k}" for k in range(N)], (np.arange(N) + 0.5) / N
        blocks = [self.reconstruction(),
                  Block("interval", stage_function("interval", sizes, body(Kind.PATH)), idx,
                        1 + npar, Kind.PATH, names, cols, times)]
        if self.problem.inequalities:
            blocks.append(Block("interval_bounds", stage_function(
                "interval_bounds", sizes, body(Kind.INEQUALITY)), idx, 1 + npar,
                Kind.INEQUALITY, self.stages.inequality_names, cols, times,
                bounds=self.stages.inequality_bounds()))
        return blocks

    def readout(self, pick: Pick) -> Readout:
        """Interval velocities at the midpoints; the midpoint controls extended linearly to
        t = 0 and t = T, so that a linear interpolation covers the horizon at second order."""
        lay, N = self.layout, self.N
        assert lay is not None
        XI, T, P = pick(self.xi), pick(lay.T), pick(lay.P)
        S = ca.horzcat(pick(lay.s0), self.step_over(pick))
        t_mid = (np.arange(N) + 0.5) / N
        u = self.interval.map(N)(S[:, :-1], XI, T, P)[2]
        t_u = t_mid
        if u.size1():
            u = ca.horzcat(u[:, 0] - (u[:, 1] - u[:, 0]) / 2, u,
                           u[:, -1] + (u[:, -1] - u[:, -2]) / 2)
            t_u = np.concatenate([[0.0], t_mid, [1.0]])
        return Readout(self.readout_steps(pick), S, t_mid, XI, t_u, u, t_u,
                       piecewise_linear(u, t_u, T))
