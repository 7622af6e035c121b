"""Fourth-order scheme (``order4``) of first-order problems.

First-order problems (:class:`GaussStages`): the seed's Runge-Kutta discrete Lagrangian
(003, §5.4) with the two-stage Gauss method (order 4). The NLP variables of interval k are
the coordinate rates ``eta_i`` at the stages ``c_i``; the stage coordinates are
``xi_i = h sum_j a_ij eta_j``, the stage velocities ``y_i = d_l tau_{xi_i}(eta_i)``,
``Theta_k = h sum_j b_j eta_j``, and

    L_d = h sum_i b_i l(q_i, y_i),   Phi_d,i = h b_i psi(q_i, y_i),   q_i = base(step(s_k, xi_i)),

all explicit: the constraints hold at the stages.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ...model.problem import Problem
from ..assembly import Block, Kind
from ..layout import Layout
from .base import Pick, Readout, Scheme, columns, stage_function
from .gauss import (
    GAUSS2,
    GAUSS2_A,
    bound_times,
    linear_coefficients,
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

    eta: np.ndarray  # (2 dim y) x N: the stage coordinate rates of each interval

    def __init__(self, problem: Problem, N: int, retraction_name: str, rule: str,
                 bound_points: int = 0) -> None:
        super().__init__(problem, N, retraction_name, rule)
        check_rule(problem, rule)
        self.bound_times = bound_times(bound_points)
        G, pb = problem.groupoid, problem
        ds, dg = G.state_size, G.algebra_dim
        s, e1, e2, T = ca.SX.sym("s", ds), ca.SX.sym("eta1", dg), ca.SX.sym("eta2", dg), \
            ca.SX.sym("T")
        h = T / N
        eta = (e1, e2)
        xi = [h * (float(GAUSS2_A[i, 0]) * e1 + float(GAUSS2_A[i, 1]) * e2) for i in range(2)]
        y = [G.velocity_of_rate(self.retractions, xi[i], eta[i]) for i in range(2)]
        sub = [self.stages.at([self.stages.running_cost(), self.stages.constraints,
                               self.stages.controls, self.stages.inequalities],
                              G.step(s, self.retractions, xi[i]), y[i]) for i in range(2)]
        # elsewhere on the interval, for the bounds: the collocation polynomial, its rate
        # linear through the stage rates and its coordinates that rate's integral
        def elsewhere(c: float) -> ca.SX:
            slope = (e2 - e1) / (GAUSS2[1] - GAUSS2[0])
            rate = e1 + slope * (c - GAUSS2[0])
            theta = h * (e1 * c + slope * ((c - GAUSS2[0]) ** 2 - GAUSS2[0] ** 2) / 2)
            return self.stages.at([self.stages.inequalities], G.step(s, self.retractions, theta),
                                  G.velocity_of_rate(self.retractions, theta, rate))[0]

        stage_H = {float(GAUSS2[0]): sub[0][3], float(GAUSS2[1]): sub[1][3]}
        H = ca.vertcat(*[stage_H[float(c)] if float(c) in stage_H else elsewhere(float(c))
                         for c in self.bound_times])
        args, names = [s, e1, e2, T, pb.P], ["s", "eta1", "eta2", "T", "P"]
        #: ``interval(s_k, eta_1, eta_2, T, P) -> (L_d, Phi_d, H)``: Phi_d at both stages, the
        #: bounds' expressions H at :attr:`bound_times`
        self.interval = ca.Function("interval", args, [
            h / 2 * (sub[0][0] + sub[1][0]), ca.vertcat(h / 2 * sub[0][1], h / 2 * sub[1][1]),
            H], names, ["L", "Phi", "H"])
        #: ``stages(...) -> (y_1, y_2, u_1, u_2)``: velocities and controls at the stages
        self.stage_values = ca.Function("stage_values", args,
                                        [y[0], y[1], sub[0][2], sub[1][2]], names,
                                        ["y1", "y2", "u1", "u2"])

    @property
    def n_stage(self) -> int:
        G = self.problem.groupoid
        return self.N * (2 * G.algebra_dim + G.state_size)

    def index(self, layout: Layout) -> None:
        """x per interval k: ``eta_1, eta_2, s_{k+1}``."""
        G = self.problem.groupoid
        dg = G.algebra_dim
        self.layout = layout
        stage = layout.stage.reshape(self.N, 2 * dg + G.state_size).T
        self.eta = stage[:2 * dg]
        self.states = np.hstack([layout.s0[:, None], stage[2 * dg:]])
        self.end_velocity = layout.VN

    def blocks(self) -> list[Block]:
        G, N, lay = self.problem.groupoid, self.N, self.layout
        assert lay is not None
        ds, dg, npar = G.state_size, G.algebra_dim, self.problem.P.numel()
        step = self.stages.step
        recon = stage_function("recon", [ds, 2 * dg, ds, 1], lambda s, e, s1, T: (
            ca.SX(1, 1), s1 - step(s, T / N * (e[:dg] + e[dg:]) / 2)))
        comps = [f"{f.state}[{j}]" for f in G.factors for j in range(f.state_size)]
        steps = lay.steps[None, :]
        blocks = [Block("recon", recon, columns(self.states[:, :N], self.eta, self.states[:, 1:],
                                                steps, ncols=N), 1, Kind.RECONSTRUCTION,
                        rows=[f"reconstruction {c}" for c in comps],
                        columns=[f"interval {k}" for k in range(N)],
                        next=slice(ds + 2 * dg, 2 * ds + 2 * dg))]
        return blocks + gauss_blocks(self, [ds, 2 * dg, 1, npar], columns(
            self.states[:, :N], self.eta, steps, lay.P, ncols=N), "stage",
            split=lambda s, e, T, P: (s, e[:dg], e[dg:], T, P))

    def readout_steps(self, pick: Pick) -> ca.MX:
        """``Theta_k = h (eta_1 + eta_2)/2``."""
        assert self.layout is not None
        dg = self.problem.groupoid.algebra_dim
        E = pick(self.eta)
        H = ca.repmat(local_horizons(self, pick) / self.N, dg, 1)
        return H * (E[:dg, :] + E[dg:, :]) / 2

    def point(self, XI: ca.MX, pick: Pick) -> list[tuple[np.ndarray, ca.MX]]:
        """Both stage rates equal to the interval velocity: Theta_k = h xi_k, so the path of
        a guess is the path of the order2 scheme's (a geodesic lands on its target)."""
        lay = self.layout
        assert lay is not None
        H = ca.repmat(local_horizons(self, pick) / self.N, XI.size1(), 1)
        S = self.stages.step.mapaccum(self.N)(pick(lay.s0), H * XI)
        return [(self.eta, ca.vertcat(XI, XI)), (self.states[:, 1:], S)]

    def readout(self, pick: Pick) -> Readout:
        """Velocities and controls at the stages; the controls between them linear on each
        interval (the collocation polynomial's rate for R^n factors)."""
        lay, N = self.layout, self.N
        assert lay is not None
        dg = self.problem.groupoid.algebra_dim
        T, P, E = local_horizons(self, pick), pick(lay.P), pick(self.eta)
        S = ca.horzcat(pick(lay.s0), self.step_over(pick))
        y1, y2, u1, u2 = self.stage_values.map(N)(S[:, :-1], E[:dg, :], E[dg:, :], T, P)
        t = ((np.arange(N)[:, None] + GAUSS2[None, :]) / N).ravel()

        def interleave(a: ca.MX, b: ca.MX) -> ca.MX:
            return ca.reshape(ca.vertcat(a, b), a.size1(), 2 * N)

        m = self.stages.controls.numel()
        coeff = linear_coefficients(u1, u2, GAUSS2[0], GAUSS2[1], T / N) if m \
            else ca.MX(0, N)
        return Readout(self.readout_steps(pick), S, t, interleave(y1, y2), t,
                       interleave(u1, u2) if m else ca.MX(0, 2 * N), np.arange(N + 1) / N,
                       coeff)

    @property
    def velocity_groups(self) -> np.ndarray:
        """Every interval: its two stage rates."""
        return self.eta.T

    def unpack(self, w: np.ndarray) -> dict[str, np.ndarray]:
        lay = self.layout
        assert lay is not None
        return {"eta": w[self.eta].T, "s": w[self.states].T, "T": w[lay.T][0], "P": w[lay.P]}
