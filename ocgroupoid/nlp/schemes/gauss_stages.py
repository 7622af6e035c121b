"""Fourth- and sixth-order schemes (``order4``, ``order6``) of first-order problems.

The seed's Runge-Kutta discrete Lagrangian (003, §5.4) with the s-stage Gauss method (order
2s): :class:`GaussStages` with two stages (order4), :class:`GaussStages3` with three
(order6). The NLP variables of interval k are the coordinate rates ``eta_i`` at the stages
``c_i``; the stage coordinates are ``xi_i = h sum_j a_ij eta_j``, the stage velocities
``y_i = d_l tau_{xi_i}(eta_i)``, ``Theta_k = h sum_j b_j eta_j``, and

    L_d = h sum_i b_i l(q_i, y_i),   Phi_d,i = h b_i psi(q_i, y_i),   q_i = base(step(s_k, xi_i)),

all explicit: the constraints hold at the stages. The method is the collocation method of
the coordinate equation ``dxi/dt = dtau_xi^-1(y)``, whose solution is smooth in any
retraction's coordinates, so the step keeps the method's order 2s with every retraction.

Bounds: with two stages at both ends and the stages (the rate is linear on an interval, so a
bound on it holds in between). With three, on the Bernstein coefficients of the quadratic
through the stage values of each bound's expression (:func:`~.gauss.hull_matrix`): the
quadratic lies within their range, so a bound on the velocities, which the replay drives as
that quadratic, holds on the whole interval. At five points it did not: a switch of the
Dubins car's turn rate inside an interval overshot ``|omega| <= 1`` by 0.08-0.13 between
them (N = 64), and the verdict refused every such plan.
"""

from __future__ import annotations

from typing import ClassVar

import casadi as ca
import numpy as np

from ...model.problem import Problem
from ..assembly import Block, Kind
from ..layout import Layout
from .base import Pick, Readout, Scheme, columns, stage_function
from .gauss import (
    BOUND_POINTS,
    GAUSS2,
    GAUSS3,
    GAUSS3_W,
    bound_times,
    hull_matrix,
    lagrange_integrals,
    lagrange_values,
    polynomial_coefficients,
)
from .order4 import check_rule, gauss_blocks, local_horizons


class GaussStages(Scheme):
    """First-order problems: the seed's Runge-Kutta discrete Lagrangian with the two-stage
    Gauss method, constraints at the stages (module docstring)."""

    name = "order4"
    accuracy = 4
    problem_order = 1
    adaptive_steps = True
    rescue = "order2"
    summary = ("seed 003 §5.4: Runge-Kutta discrete Lagrangian, 2-stage Gauss, constraints "
               "at the stages")
    #: the stages (fractions of an interval) and the quadrature weights b_i
    collocation: ClassVar[np.ndarray] = GAUSS2
    collocation_weights: ClassVar[np.ndarray] = np.array([0.5, 0.5])
    #: where the bounds hold (before ``discretization.bound_points``)
    base_bound_times: ClassVar[np.ndarray] = BOUND_POINTS
    #: whether the bounds hold on the Bernstein coefficients of the polynomial through the
    #: stage values (:func:`~.gauss.hull_matrix`) instead of at points
    hull: ClassVar[bool] = False

    eta: np.ndarray  # (stages dim y) x N: the stage coordinate rates of each interval

    def __init__(self, problem: Problem, N: int, retraction_name: str, rule: str,
                 bound_points: int = 0) -> None:
        super().__init__(problem, N, retraction_name, rule)
        check_rule(problem, rule)
        #: where the bounds hold on an interval (fractions); with :attr:`hull`, the Greville
        #: abscissae of the Bernstein coefficients the bounds hold on
        self.bound_times = np.linspace(0.0, 1.0, self.collocation.size + bound_points) \
            if self.hull else bound_times(bound_points, self.base_bound_times)
        G, pb = problem.groupoid, problem
        ds, dg, c, b = G.state_size, G.algebra_dim, self.collocation, self.collocation_weights
        s, T = ca.SX.sym("s", ds), ca.SX.sym("T")
        eta = [ca.SX.sym(f"eta{i + 1}", dg) for i in range(c.size)]
        h = T / N

        def at(tau: float) -> tuple[ca.SX, ca.SX]:
            """The collocation polynomial at ``t_k + tau h``: its coordinates (the integral
            of its rate) and its rate (through the stage rates)."""
            zero = ca.SX.zeros(dg)
            theta = h * sum((float(w) * e for w, e in zip(lagrange_integrals(c, tau), eta)), zero)
            rate = sum((float(w) * e for w, e in zip(lagrange_values(c, tau), eta)), zero)
            return theta, rate

        xi = [at(float(ci))[0] for ci in c]
        y = [G.velocity_of_rate(self.retractions, xi[i], eta[i]) for i in range(c.size)]
        sub = [self.stages.at([self.stages.running_cost(), self.stages.constraints,
                               self.stages.controls, self.stages.inequalities],
                              G.step(s, self.retractions, xi[i]), y[i]) for i in range(c.size)]

        def elsewhere(tau: float) -> ca.SX:
            """The bounds' expressions between the stages, on the collocation polynomial."""
            theta, rate = at(tau)
            return self.stages.at([self.stages.inequalities], G.step(s, self.retractions, theta),
                                  G.velocity_of_rate(self.retractions, theta, rate))[0]

        if self.hull:
            M = hull_matrix(c, bound_points)
            H = ca.vertcat(*[sum((float(M[r, i]) * sub[i][3] for i in range(c.size)),
                                 ca.SX.zeros(sub[0][3].shape)) for r in range(M.shape[0])])
        else:
            stage_H = {float(ci): sub[i][3] for i, ci in enumerate(c)}
            H = ca.vertcat(*[stage_H[float(t)] if float(t) in stage_H else elsewhere(float(t))
                             for t in self.bound_times])
        args = [s, *eta, T, pb.P]
        names = ["s", *(f"eta{i + 1}" for i in range(c.size)), "T", "P"]
        #: ``interval(s_k, eta_1, ..., eta_s, T, P) -> (L_d, Phi_d, H)``: Phi_d at every
        #: stage, the bounds' expressions H at :attr:`bound_times`
        self.interval = ca.Function("interval", args, [
            h * sum(float(w) * sb[0] for w, sb in zip(b, sub)),
            ca.vertcat(*[h * float(w) * sb[1] for w, sb in zip(b, sub)]), H],
            names, ["L", "Phi", "H"])
        #: ``stage_values(...) -> (y_1, ..., y_s, u_1, ..., u_s)``: velocities and controls
        #: at the stages
        self.stage_values = ca.Function(
            "stage_values", args, [*y, *(sb[2] for sb in sub)], names,
            [*(f"y{i + 1}" for i in range(c.size)), *(f"u{i + 1}" for i in range(c.size))])

    def held_rows(self, points: int) -> np.ndarray:
        """With :attr:`hull`, every Bernstein coefficient: the first alone at the bound let
        the quadratic leave it inside the arc (the Dubins car's LSL at N = 32 landed 250
        times worse phased than uniform; held together, every word's length is exact to
        1e-13). Else the rule of :meth:`Scheme.held_rows`."""
        return np.ones(points, dtype=bool) if self.hull else super().held_rows(points)

    @property
    def n_stage(self) -> int:
        G = self.problem.groupoid
        return self.N * (self.collocation.size * G.algebra_dim + G.state_size)

    def index(self, layout: Layout) -> None:
        """x per interval k: ``eta_1, ..., eta_s, s_{k+1}``."""
        G = self.problem.groupoid
        ne = self.collocation.size * G.algebra_dim
        self.layout = layout
        stage = layout.stage.reshape(self.N, ne + G.state_size).T
        self.eta = stage[:ne]
        self.states = np.hstack([layout.s0[:, None], stage[ne:]])
        self.end_velocity = layout.VN

    def _stage_rates(self, e: ca.SX) -> list[ca.SX]:
        """The stacked stage rates of an interval, one by one."""
        dg = self.problem.groupoid.algebra_dim
        return [e[i * dg:(i + 1) * dg] for i in range(self.collocation.size)]

    def blocks(self) -> list[Block]:
        G, N, lay = self.problem.groupoid, self.N, self.layout
        assert lay is not None
        ds, npar = G.state_size, self.problem.P.numel()
        ne = self.collocation.size * G.algebra_dim
        step, b = self.stages.step, self.collocation_weights
        recon = stage_function("recon", [ds, ne, ds, 1], lambda s, e, s1, T: (
            ca.SX(1, 1), s1 - step(s, T / N * sum(float(w) * r for w, r in
                                                  zip(b, self._stage_rates(e))))))
        comps = [f"{f.state}[{j}]" for f in G.factors for j in range(f.state_size)]
        steps = lay.steps[None, :]
        blocks = [Block("recon", recon, columns(self.states[:, :N], self.eta, self.states[:, 1:],
                                                steps, ncols=N), 1, Kind.RECONSTRUCTION,
                        rows=[f"reconstruction {c}" for c in comps],
                        columns=[f"interval {k}" for k in range(N)],
                        next=slice(ds + ne, 2 * ds + ne))]
        return blocks + gauss_blocks(self, [ds, ne, 1, npar], columns(
            self.states[:, :N], self.eta, steps, lay.P, ncols=N), "stage",
            split=lambda s, e, T, P: (s, *self._stage_rates(e), T, P), at=self.collocation,
            where=[f"hull point {j + 1} of {self.bound_times.size}"
                   for j in range(self.bound_times.size)] if self.hull else None)

    def readout_steps(self, pick: Pick) -> ca.MX:
        """``Theta_k = h sum_i b_i eta_i``."""
        assert self.layout is not None
        dg = self.problem.groupoid.algebra_dim
        E = pick(self.eta)
        H = ca.repmat(local_horizons(self, pick) / self.N, dg, 1)
        return H * sum(float(w) * E[i * dg:(i + 1) * dg, :]
                       for i, w in enumerate(self.collocation_weights))

    def point(self, XI: ca.MX, pick: Pick) -> list[tuple[np.ndarray, ca.MX]]:
        """Every stage rate equal to the interval velocity: Theta_k = h xi_k, so the path of
        a guess is the path of the order2 scheme's (a geodesic lands on its target)."""
        lay = self.layout
        assert lay is not None
        H = ca.repmat(local_horizons(self, pick) / self.N, XI.size1(), 1)
        S = self.stages.step.mapaccum(self.N)(pick(lay.s0), H * XI)
        return [(self.eta, ca.vertcat(*[XI] * self.collocation.size)), (self.states[:, 1:], S)]

    def readout(self, pick: Pick) -> Readout:
        """Velocities and controls at the stages; the controls between them the polynomial
        through the stage values on each interval (a line with two stages; for R^n factors
        the collocation polynomial's rate)."""
        lay, N, c = self.layout, self.N, self.collocation
        assert lay is not None
        dg, k = self.problem.groupoid.algebra_dim, self.collocation.size
        T, P, E = local_horizons(self, pick), pick(lay.P), pick(self.eta)
        S = ca.horzcat(pick(lay.s0), self.step_over(pick))
        out = self.stage_values.map(N)(S[:, :-1], *[E[i * dg:(i + 1) * dg, :] for i in range(k)],
                                       T, P)
        ys, us = list(out[:k]), list(out[k:])
        t = ((np.arange(N)[:, None] + c[None, :]) / N).ravel()

        def interleave(parts: list[ca.MX]) -> ca.MX:
            return ca.reshape(ca.vertcat(*parts), parts[0].size1(), k * N)

        m = self.stages.controls.numel()
        coeff = polynomial_coefficients(ca.vertcat(*us), c, T / N) if m else ca.MX(0, N)
        return Readout(self.readout_steps(pick), S, t, interleave(ys), t,
                       interleave(us) if m else ca.MX(0, k * N), np.arange(N + 1) / N, coeff)

    @property
    def velocity_groups(self) -> np.ndarray:
        """Every interval: its stage rates."""
        return self.eta.T

    def unpack(self, w: np.ndarray) -> dict[str, np.ndarray]:
        lay = self.layout
        assert lay is not None
        return {"eta": w[self.eta].T, "s": w[self.states].T, "T": w[lay.T][0], "P": w[lay.P]}


class GaussStages3(GaussStages):
    """First-order problems: the seed's Runge-Kutta discrete Lagrangian with the three-stage
    Gauss method (order 6), constraints at the stages (module docstring)."""

    name = "order6"
    accuracy = 6
    summary = ("seed 003 §5.4: Runge-Kutta discrete Lagrangian, 3-stage Gauss, constraints "
               "at the stages")
    collocation = GAUSS3
    collocation_weights = GAUSS3_W
    hull = True
