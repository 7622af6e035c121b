"""Fourth-order schemes (``order4``).

Second-order problems (:class:`QuadraticGauss`). The velocity on interval k is the
quadratic through the node values ``y_k, y_{k+1}`` with a bubble ``b_k`` (value at the
midpoint minus the mean of the ends): ``y = (1 - tau) y_k + tau y_{k+1} + 4 tau (1 - tau)
b_k``, continuous across nodes, its rate jumping there. The cost ``int Ltilde(q, y, dy) dt``
is the 3-point Gauss-Legendre rule; the constraints ``Phi = 0`` hold at the two Gauss points
(each row scaled by its quadrature weight ``h/2``, so that its multiplier approximates the
seeds' ``lambda(t)`` there). The group increment solves the reconstruction equation
(``ds/dt = s y`` on the body side) for the quadratic velocity by the sixth-order Magnus step
from its values at the three Gauss points, ``s_{k+1} = step(s_k, exp(W_k))``
(:meth:`Factor.magnus6`: explicit, no nested derivatives of a retraction, local error
O(h^7), the 3-point Gauss rule on R^n). Inside the interval, where the Lagrangian and the
bounds need q, the fourth-order step over ``[t_k, t_k + c h]``, ``h c/2 (y(c g_1) + y(c g_2))
+ sqrt(3)/12 (c h)^2 [y(c g_1), y(c g_2)]`` (:meth:`Factor.magnus`, local O(h^5)), is enough:
its error enters the cost and ``Phi`` at the scheme's own order. The step from node to node
is what a plan's landing measures: where the controls drive the velocities exactly (the
reaction wheels' torques), the replay integrates the same velocity, and what it misses is
the step's error alone. With the fourth-order step the wheels' plan missed its final
attitude by 1.2e-7 at N = 32 and 7.4e-9 at N = 64; with this one by 6.9e-12 and 7.4e-14,
in the same iterations (so3 and the custom rigid body land 1.7 times closer,
``so3_minimum_time`` 1.2-1.5 times; the quadrotor and the heavy top, whose landing the
collocation's velocity error dominates, as before). Its price is in the derivatives: timed in
pairs with fatrop and JIT at N = 64, the Hessian and the Jacobian took 40-50 % longer and a
whole solve of a rigid body 1.16-1.3 times as long (docs/explanation/schemes.md). Since
``tau(tau^-1(exp W)) = exp W``, the increments are those of any retraction: the scheme steps
with exp (measured: an RK4 step of ``dTheta/dt = dtau^-1(Theta) y`` in the retraction's
coordinates gave the same order with stage Hessians several times larger, from its nested
``dtau^-1``).

Why this space: a quadratic per interval leaves two unknowns per component and interval
(``y_{k+1}``, ``b_k``), which the two Gauss points determine for the unactuated components:
on ``dy/dt = lambda y`` the step is Gauss-Legendre's ``(1 + z/2 + z^2/12)/(1 - z/2 +
z^2/12)``, ``z = lambda h`` (order 4, A-stable, one root). A C1 cubic Hermite velocity has the
same count per interval but one more unknown (the initial rate) and a second root
``~ exp(-z/3)`` of the one-step map: a free, undamped mode at the grid scale, which the
optimiser used to satisfy the heavy top's equations only at the Gauss points (cost near 0,
replay 0.4 rad off; measured, see tests/test_order4.py).

Controls of their own (``pb.control``) are linear on each interval, jumping at nodes; their
variables are the values at the interval's two ends, the cost and ``Phi`` read them at the
Gauss points and the bounds at every bound point, so that a bound on the controls alone, held
at the ends, holds on the whole interval and the control the read-out reports is the one
bounded. Why the ends and not the Gauss values (the same line in other coordinates): a bound
at an end is then a row on one variable, which fatrop's Riccati recursion takes as it comes.
With the Gauss values as the variables and the ends bounded on the motion's estimate there,
fatrop regularised its KKT system near the solution and converged linearly:
quadrotor_min_time took 38, 53, 65, 75 iterations at N = 16, 32, 64, 128 (IPOPT 26, 31, 37,
43); with only the ends bounded on the line, 135 at N = 64 in those coordinates and 30 in
these. Now 25, 27, 35, 35 (IPOPT 23, 28, 32, 37), the cost 4e-6 to 7e-4 lower on every grid
(docs/benchmarks/performance.md, "fatrop by itself"). Where every bound is affine in the
controls of their own alone (the quadrotor's thrust and torques), a bound is a line on the
interval too, within its bounds wherever it is within them at both ends: the bounds then hold
at the ends only (:func:`on_the_line`), and the rows at the Gauss points, implied, are not
built. quadrotor_min_time at N = 64 has 512 inequality rows instead of 1024, IPOPT 29
iterations instead of 32 and fatrop 32 instead of 35, at the same optimum.

Recovered controls (an input matrix: ``u = B^-1 EL``) are expressions of the motion, cubic
on an interval; their bounds hold at :data:`~.gauss.BOUND_POINTS` and read the interval's
whole motion. Where every bound of a problem bounds such a control, the controls are drawn
as lines instead (:class:`~ocgroupoid.nlp.control_lines.ControlLines`): variables like
controls of their own, tied to the recovered ones at the Gauss points, bounded at the ends.

First-order problems: :class:`~ocgroupoid.nlp.schemes.gauss_stages.GaussStages`.
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING, Any, ClassVar

import casadi as ca
import numpy as np

from ...errors import ConfigError
from ...model.problem import Problem
from ..assembly import Block, Kind
from ..control_lines import ControlLines, bounded_controls
from ..layout import Layout
from ..stages import Stages
from .base import DEFAULT_RULE, Pick, Readout, Scheme, columns, stage_function
from .gauss import (
    BOUND_POINTS,
    GAUSS2,
    GAUSS3,
    GAUSS3_W,
    SAMPLES,
    bound_times,
    polynomial_coefficients,
    quadratic,
)

if TYPE_CHECKING:
    from .gauss_stages import GaussStages


def local_horizons(scheme: Scheme, pick: Pick) -> ca.MX:
    """Each interval's local horizon N h_k (1 x N): T for uniform steps."""
    assert scheme.layout is not None
    return pick(scheme.layout.steps[None, :])


def gauss_blocks(scheme: QuadraticGauss | GaussStages, sizes: list[int], idx: np.ndarray,
                 point: str, split: Any = None, at: np.ndarray = GAUSS2,
                 where: list[str] | None = None) -> list[Block]:
    """The path block (cost and Phi_d at the Gauss points ``at`` of every interval) and, with
    bounds, the inequality block of an order4 or order6 scheme whose ``interval`` Function
    returns ``(L, Phi, H)``; ``split`` maps the stage inputs to the Function's arguments,
    ``where`` names the bound rows of an interval (default: by their times)."""
    N, pb = scheme.N, scheme.problem
    npar = pb.P.numel()
    names = scheme.stages.constraint_names
    times = ((np.arange(N)[:, None] + at[None, :]) / N).ravel()
    cols = [f"interval {k}" for k in range(N)]
    call = (lambda *z: scheme.interval(*split(*z))) if split else scheme.interval  # noqa: E731
    blocks = [Block("interval", stage_function("interval", sizes, lambda *z: tuple(
        call(*z)[:2])), idx, 1 + npar, Kind.PATH,
        [f"{n} ({point} {j + 1})" for j in range(at.size) for n in names], cols, times,
        points=at.size)]
    if pb.inequalities:
        bt = scheme.bound_times
        named = {0.0: "start", 1.0: "end",
                 **{float(c): f"{point} {j + 1}" for j, c in enumerate(at)}}
        where = where or [named.get(float(c), f"at {c:.3g} of the interval") for c in bt]
        blocks.append(Block("interval_bounds", stage_function(
            "interval_bounds", sizes, lambda *z: (ca.SX(1, 1), call(*z)[2])), idx, 1 + npar,
            Kind.INEQUALITY, [f"{n} ({w})" for w in where
                              for n in scheme.stages.inequality_names], cols,
            ((np.arange(N)[:, None] + bt[None, :]) / N).ravel(), points=bt.size,
            bounds=scheme.stages.inequality_bounds(points=bt.size)))
    return blocks


def on_the_line(bounds: ca.SX, pb: Problem, U: ca.SX) -> bool:
    """Whether every bound's expression is affine in the controls that are variables ``U``
    and depends on nothing else but the parameters: on the line an interval's controls
    follow, such an expression is a line too, within its bounds wherever it is within them
    at both ends."""
    motion = ca.vertcat(pb.q, pb.s, pb.y, pb.dy)
    return bool(U.numel()) and bounds.numel() > 0 and not ca.depends_on(bounds, motion) \
        and not ca.depends_on(ca.jacobian(bounds, U), U)


def check_rule(problem: Problem, rule: str) -> None:
    """ConfigError unless ``rule`` is the midpoint rule, the only one order4 has."""
    if rule != DEFAULT_RULE:
        raise ConfigError(
            f"rule {rule!r} discretises the constraints of the order2 scheme; order4 imposes "
            f"them at the Gauss points: leave discretization.rule at {DEFAULT_RULE!r} (the "
            "scheme's own) or choose scheme order2")


class QuadraticGauss(Scheme):
    """Second-order problems: continuous piecewise-quadratic velocities, Gauss quadrature and
    collocation, an RK4 step of the coordinate equation (module docstring)."""

    name = "order4"
    accuracy = 4
    problem_order = 2
    adaptive_steps = True
    rescue = "order2"
    summary = ("piecewise-quadratic velocity, 3-point Gauss cost, Phi at the 2 Gauss points "
               "(Gauss-Legendre collocation), 6th-order Magnus step with exp")
    #: bubbles per interval and velocity component (the velocity's degree less one)
    bubbles: ClassVar[int] = 1
    #: the Gauss points (fractions of an interval) where Phi holds, and their weights
    collocation: ClassVar[np.ndarray] = GAUSS2
    collocation_weights: ClassVar[np.ndarray] = np.array([0.5, 0.5])
    #: where the bounds hold (before ``discretization.bound_points``) and where the controls
    #: are sampled
    base_bound_times: ClassVar[np.ndarray] = BOUND_POINTS
    samples: ClassVar[np.ndarray] = SAMPLES
    #: the velocity at ``t_k + tau h`` and its rate, ``(y0, y1, b, h, tau) -> (y, dy)``
    velocity = staticmethod(quadratic)

    Y: np.ndarray  # dim y x (N+1) node velocities (y_0 = V_0, y_N = V_N)
    B: np.ndarray  # (bubbles dim y) x N bubbles

    def __init__(self, problem: Problem, N: int, retraction_name: str, rule: str,
                 bound_points: int = 0) -> None:
        # the increments are exponential coordinates: tau(tau^-1(exp W)) = exp W for every
        # retraction, so the scheme steps with exp whatever the retraction asked for
        super().__init__(problem, N, "exp", rule)
        check_rule(problem, rule)
        G, pb = problem.groupoid, problem
        ds, dg, nu = G.state_size, G.algebra_dim, self.stages.n_u
        #: where the bounds hold on an interval (fractions): its ends only when every bound
        #: is affine in the controls that are variables alone (then implied on the whole
        #: line between them) and no more points were asked for, else
        #: :attr:`base_bound_times` and the ``bound_points`` more
        self.bound_times = np.array([0.0, 1.0]) if bound_points == 0 and \
            on_the_line(self.stages.inequalities, pb, self.stages.U) \
            else bound_times(bound_points, self.base_bound_times)
        s = ca.SX.sym("s", ds)
        y0, y1 = (ca.SX.sym(n, dg) for n in ("y0", "y1"))
        b = ca.SX.sym("b", self.bubbles * dg)
        ue = ca.SX.sym("u", 2 * nu)  # controls of their own at the interval's two ends
        T = ca.SX.sym("T")
        h = T / N

        # each point's velocity, step and state built once: the cost, Phi, the bounds and
        # the samples read the same points (the cart-pole's interval: 846 -> 666
        # instructions with order6, 488 -> 460 with order4)
        @lru_cache(maxsize=None)
        def velocity(tau: float) -> tuple[ca.SX, ca.SX]:
            return self.velocity(y0, y1, b, h, tau)

        # from node to node: the sixth-order Magnus step (module docstring)
        g1, g2, g3 = (velocity(float(g))[0] for g in GAUSS3)
        step = G.magnus6(g1, g2, g3, h)

        @lru_cache(maxsize=None)
        def theta(c: float) -> ca.SX:
            """Exponential coordinates of the step to t_k + c h: inside the interval
            :meth:`inner_step`, at its end the node's."""
            if c == 0.0:
                return ca.SX.zeros(dg)
            if c == 1.0:
                return step
            return self.inner_step(G, velocity, c, h)

        @lru_cache(maxsize=None)
        def state(c: float) -> ca.SX:
            return G.step(s, self.retractions, theta(c))

        def at(expr: ca.SX, tau: float, u: ca.SX | None = None) -> ca.SX:
            y, dy = velocity(tau)
            return self.stages.at([expr], state(tau), y, dy, u)[0]

        # controls of their own: linear on the interval, their variables its end values
        # (module docstring); every point reads the line
        def u_at(c: float) -> ca.SX | None:
            return (1.0 - c) * ue[:nu] + c * ue[nu:] if nu else None

        args = [s, y0, y1, b, ue, T, pb.P]
        names = ["s", "y0", "y1", "b", "u_ends", "T", "P"]
        cost = self.stages.running_cost()
        # with controls of their own, linear on an interval, the collocation's Gauss rule
        # (order4: 2 points, order 4); else the 3-point rule
        points, weights = (self.collocation, self.collocation_weights) if nu else \
            (GAUSS3, GAUSS3_W)
        L = h * sum(float(w) * at(cost, float(c), u_at(float(c)))
                    for c, w in zip(points, weights))
        phi, ineq = self.stages.constraints, self.stages.inequalities
        Phi = ca.vertcat(*[h * float(w) * at(phi, float(c), u_at(float(c))) for c, w in
                           zip(self.collocation, self.collocation_weights)]) \
            if phi.numel() else ca.SX(0, 1)
        H = ca.vertcat(*[at(ineq, float(c), u_at(float(c))) for c in self.bound_times]) \
            if ineq.numel() else ca.SX(0, 1)
        #: ``interval(s_k, y_k, y_{k+1}, b_k, u_k, T, P) -> (L_d, Phi_d, H)``: Phi_d stacks
        #: the Gauss points, the bounds' expressions H the :attr:`bound_times`; u_k: the
        #: controls of their own at the interval's ends (empty when they are recovered)
        self.interval = ca.Function("interval", args, [L, Phi, H], names, ["L", "Phi", "H"])
        #: ``increment(y_k, y_{k+1}, b_k, T) -> W_k``, exponential coordinates of the step
        self.increment = ca.Function("increment", [y0, y1, b, T], [step],
                                     ["y0", "y1", "b", "T"], ["Theta"])
        u = self.stages.controls
        #: controls at :attr:`samples` of an interval (one-sided at its ends), stacked
        self.control_samples = ca.Function(
            "control_samples", args,
            [ca.vertcat(*[at(u, float(c), u_at(float(c))) for c in self.samples])], names,
            ["u"])
        if nu:
            assert self.stages.estimate is not None
            u1, u2 = (self.stages.estimate(state(float(c)),
                                           *velocity(float(c)), pb.P, ca.DM.zeros(nu))
                      for c in GAUSS2)
            #: ``end_controls(s_k, y_k, y_{k+1}, b_k, T, P) -> u_k``: the line through the
            #: controls that best explain the motion at the Gauss points, at the interval's
            #: ends (the guesses' controls)
            self.end_controls = ca.Function("end_controls", args[:4] + args[5:], [ca.vertcat(
                *[u1 + (u2 - u1) * (c - GAUSS2[0]) / (GAUSS2[1] - GAUSS2[0])
                  for c in (0.0, 1.0)])])

    @staticmethod
    def inner_step(G: Any, velocity: Any, c: float, h: ca.SX) -> ca.SX:
        """Exponential coordinates of the step over ``[t_k, t_k + c h]``: the fourth-order
        Magnus step from the velocity at its two Gauss points (local O(h^5); module
        docstring)."""
        ya, yb = (velocity(c * float(g))[0] for g in GAUSS2)
        return G.magnus(ya, yb, c * h)

    def make_stages(self) -> Stages:
        """:class:`ControlLines` where every bound of the problem is on its recovered
        controls (:func:`bounded_controls`), else the plain stages."""
        bounded = bounded_controls(self.problem)
        return super().make_stages() if bounded is None else \
            ControlLines(self.problem, self.retractions, bounded)

    @property
    def n_stage(self) -> int:
        G = self.problem.groupoid
        return ((1 + self.bubbles) * self.N - 1) * G.algebra_dim + \
            self.N * (G.state_size + 2 * self.stages.n_u)

    def index(self, layout: Layout) -> None:
        """x per interval k: ``b_k``, ``y_{k+1}`` (not the last: y_N is V_N), ``s_{k+1}``;
        then the controls of their own at the interval's ends, when declared."""
        G, N = self.problem.groupoid, self.N
        dg, ds = G.algebra_dim, G.state_size
        self.layout = layout
        self.Y = np.zeros((dg, N + 1), dtype=np.int64)
        nb = self.bubbles * dg
        self.B = np.zeros((nb, N), dtype=np.int64)
        self.states = np.zeros((ds, N + 1), dtype=np.int64)
        self.Y[:, 0], self.Y[:, N], self.states[:, 0] = layout.V0, layout.VN, layout.s0
        c = 0
        for k in range(N):
            self.B[:, k] = layout.stage[c:c + nb]
            c += nb
            if k < N - 1:
                self.Y[:, k + 1] = layout.stage[c:c + dg]
                c += dg
            self.states[:, k + 1] = layout.stage[c:c + ds]
            c += ds
        self.UE = layout.stage[c:].reshape(N, 2 * self.stages.n_u).T
        self.end_velocity = layout.VN

    def blocks(self) -> list[Block]:
        G, N, lay = self.problem.groupoid, self.N, self.layout
        assert lay is not None
        ds, dg, npar = G.state_size, G.algebra_dim, self.problem.P.numel()
        nb = self.bubbles * dg
        step, inc = self.stages.step, self.increment
        recon = stage_function("recon", [ds, dg, dg, nb, ds, 1], lambda s, y0, y1, b, s1, T: (
            ca.SX(1, 1), s1 - step(s, inc(y0, y1, b, T))))
        comps = [f"{f.state}[{j}]" for f in G.factors for j in range(f.state_size)]
        cols = [self.states[:, :N], self.Y[:, :N], self.Y[:, 1:], self.B]
        steps = lay.steps[None, :]
        blocks = [Block("recon", recon, columns(*cols, self.states[:, 1:], steps, ncols=N), 1,
                        Kind.RECONSTRUCTION, rows=[f"reconstruction {c}" for c in comps],
                        columns=[f"interval {k}" for k in range(N)],
                        next=slice(ds + 2 * dg + nb, 2 * ds + 2 * dg + nb))]
        return blocks + gauss_blocks(self, [ds, dg, dg, nb, 2 * self.stages.n_u, 1, npar],
                                     columns(*cols, self.UE, steps, lay.P, ncols=N),
                                     "Gauss point", at=self.collocation)

    def _increments(self, Y: ca.MX, B: ca.MX, T: ca.MX) -> ca.MX:
        return self.increment.map(self.N)(Y[:, :-1], Y[:, 1:], B, T)

    def readout_steps(self, pick: Pick) -> ca.MX:
        return self._increments(pick(self.Y), pick(self.B), local_horizons(self, pick))

    def point(self, XI: ca.MX, pick: Pick) -> list[tuple[np.ndarray, ca.MX]]:
        """Node velocities: the mean of the adjacent interval velocities (prescribed ends
        kept); bubbles: the velocity's mean on each interval equals its interval velocity
        (the other bubbles of order6 zero); states by the scheme's own reconstruction."""
        lay, N = self.layout, self.N
        assert lay is not None
        Y = ca.horzcat(XI[:, 0], (XI[:, :-1] + XI[:, 1:]) / 2, XI[:, N - 1])
        ends = [ca.vertcat(*[guess[i] if idx[i] < lay.nx else given[i]
                             for i in range(idx.size)])
                for idx, guess, given in ((lay.V0, Y[:, 0], pick(lay.V0)),
                                          (lay.VN, Y[:, N], pick(lay.VN)))]
        Y = ca.horzcat(ends[0], Y[:, 1:N], ends[1])
        B = ca.vertcat(1.5 * (XI - (Y[:, :-1] + Y[:, 1:]) / 2),  # mean: (y_k + y_{k+1})/2
                       ca.MX.zeros((self.bubbles - 1) * XI.size1(), N))  # + 2 b_k/3
        H = local_horizons(self, pick)
        S = self.stages.step.mapaccum(N)(pick(lay.s0), self._increments(Y, B, H))
        parts = [(self.Y, Y), (self.B, B), (self.states[:, 1:], S)]
        if self.stages.n_u:
            S0 = ca.horzcat(pick(lay.s0), S[:, :-1])
            parts.append((self.UE, self.end_controls.map(N)(S0, Y[:, :-1], Y[:, 1:], B, H,
                                                              pick(lay.P))))
        return parts

    def readout(self, pick: Pick) -> Readout:
        """Node velocities; controls sampled at :attr:`samples` of each interval and the
        polynomials through them (cubics for order4, one per interval: the controls jump with
        the rates at nodes; for controls of their own, lines)."""
        lay, N = self.layout, self.N
        assert lay is not None
        T, P = local_horizons(self, pick), pick(lay.P)
        Y, B = pick(self.Y), pick(self.B)
        steps = self._increments(Y, B, T)
        S = ca.horzcat(pick(lay.s0), self.stages.step.mapaccum(N)(pick(lay.s0), steps))
        samples = self.control_samples.map(N)(S[:, :-1], Y[:, :-1], Y[:, 1:], B,
                                              pick(self.UE), T, P)
        m, k = self.stages.controls.numel(), self.samples.size - 1
        t_u = np.concatenate([(np.arange(N)[:, None] + self.samples[None, :k]).ravel() / N,
                              [1.0]])
        u = ca.horzcat(ca.reshape(samples[:k * m, :], m, k * N), samples[k * m:, -1]) if m \
            else ca.MX(0, k * N + 1)
        coeff = polynomial_coefficients(samples, self.samples, T / N) if m else ca.MX(0, N)
        return Readout(steps, S, np.arange(N + 1) / N, Y, t_u, u, np.arange(N + 1) / N, coeff)

    @property
    def velocity_groups(self) -> np.ndarray:
        """Interval k: its bubbles b_k and the velocity y_{k+1} at its end (the last interval:
        its first bubble twice, y_N being V_N)."""
        dg = self.problem.groupoid.algebra_dim
        Yend = np.hstack([self.Y[:, 1:-1], self.B[:dg, -1:]])
        return np.vstack([self.B, Yend]).T

    def unpack(self, w: np.ndarray) -> dict[str, np.ndarray]:
        lay = self.layout
        assert lay is not None
        return {"y": w[self.Y].T, "b": w[self.B].T, "s": w[self.states].T, "u": w[self.UE].T,
                "T": w[lay.T][0], "P": w[lay.P]}
