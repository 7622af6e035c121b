"""The continuous controlled dynamics of a problem, as one right-hand side.

Second-order problems with mechanics: ``M(q, g, y) dy/dt = F(q, g, y, u) - c(q, g, y)``
with ``F_actuated = B(q, g) u`` or the declared force of controls of their own (the
controlled Euler-Lagrange(-Poincare) equations, ``M`` the Jacobian of the EL operator in
``dy``, g the group states a potential reads); second-order problems whose controls are the
accelerations: ``dy/dt = u``; first-order problems whose controls are velocity components:
the constraints ``psi(q, y) = 0`` solved for the remaining velocities. States follow the
reconstruction equations (``G.state_rate``: ``dR/dt = R hat(Omega)``, ...).

The replay (:mod:`ocgroupoid.verify.replay`) integrates it; the shooting baselines
(:mod:`ocgroupoid.nlp.schemes.shooting`) discretise it. Any other problem has no continuous
dynamics, and :attr:`Dynamics.reason` says why. :func:`rk4` is the one classical Runge-Kutta
step they all take (the replay, the shooting baselines, the simulator's comparison).
"""

from __future__ import annotations

from typing import Any, Callable

import casadi as ca

from ..model.problem import Problem
from .stages import Stages


class Dynamics:
    """``rhs(z, u, P) -> dz/dt`` with ``z = (s, y)`` (second order) or ``z = s`` (first
    order); ``velocity(s, u, P) -> y`` of a first-order problem; ``acceleration(s, y, u, P)
    -> dy/dt`` of a second-order one. ``rhs`` is None when the problem has no continuous
    dynamics (:attr:`reason`)."""

    def __init__(self, problem: Problem, stages: Stages) -> None:
        pb, G = problem, problem.groupoid
        self.problem = pb
        s, y, u = ca.SX.sym("s", G.state_size), ca.SX.sym("y", G.algebra_dim), \
            ca.SX.sym("u", len(pb.controls))
        self.s, self.y, self.u = s, y, u
        q = G.base(s)
        self.reason = ""
        self.rhs: ca.Function | None = None
        self.velocity: ca.Function | None = None
        self.acceleration: ca.Function | None = None
        #: constraint names the dynamics satisfy by construction (not imposed again)
        self.implied: set[str] = set()
        ctrl = stages.controls
        if pb.order == 2 and pb.dynamics is not None:
            mech = pb.dynamics
            here = ([pb.q, pb.s, pb.y], [q, s, y])
            EL = ca.substitute([mech.EL], *here)[0]
            M = ca.jacobian(EL, pb.dy)
            c = ca.substitute(EL, pb.dy, ca.DM.zeros(G.algebra_dim))
            F = ca.substitute([mech.generalised_force(u, G.algebra_dim)], *here)[0]
            self._second(ca.solve(M, F - c))
            self.implied = {"Phi"}
        elif pb.order == 2 and ca.depends_on(ctrl, pb.dy) and ca.is_equal(ctrl, pb.dy, 2):
            self._second(u)
        elif pb.order == 1:
            self._first_order(q, ctrl, stages.constraints)
        else:
            self.reason = "no dynamics: the controls are neither mechanics nor accelerations"

    @property
    def second(self) -> bool:
        """Whether the dynamic state carries the velocities (second-order problems)."""
        return self.problem.order == 2

    def _second(self, dy: ca.SX) -> None:
        pb, G, s, y, u = self.problem, self.problem.groupoid, self.s, self.y, self.u
        self.acceleration = ca.Function("acceleration", [s, y, u, pb.P], [dy])
        self.rhs = ca.Function("rhs", [ca.vertcat(s, y), u, pb.P],
                               [ca.vertcat(G.state_rate(s, y), dy)])

    def _first_order(self, q: ca.SX, ctrl: ca.SX, psi: ca.SX) -> None:
        pb, G, s, u = self.problem, self.problem.groupoid, self.s, self.u
        ctrl_idx = []
        for k in range(ctrl.numel()):
            hits = [i for i in range(pb.y.numel()) if ca.is_equal(ctrl[k], pb.y[i])]
            if not hits:
                self.reason = "first-order controls must be velocity components"
                return
            ctrl_idx.append(hits[0])
        dep = [i for i in range(pb.y.numel()) if i not in ctrl_idx]
        if psi.numel() != len(dep):
            self.reason = (f"{len(dep)} velocities are not controls but {psi.numel()} "
                           "constraints determine them")
            return
        yfull = ca.SX.zeros(pb.y.numel())
        yfull[ctrl_idx] = u
        ydep = ca.SX.sym("ydep", len(dep))
        yfull[dep] = ydep
        res = ca.substitute(ca.substitute(psi, pb.q, q), pb.y, yfull)
        J = ca.jacobian(res, ydep)
        r0 = ca.substitute(res, ydep, ca.DM.zeros(len(dep)))
        ysol = ca.substitute(yfull, ydep, -ca.solve(J, r0))  # exact for affine psi
        self.velocity = ca.Function("velocity", [s, u, pb.P], [ysol])
        self.rhs = ca.Function("rhs", [s, u, pb.P], [G.state_rate(s, ysol)])
        self.implied = {name for name, _ in pb.constraints}


def rk4(f: Callable[[Any, float], Any], z: Any, h: Any) -> Any:
    """One classical RK4 step of ``dz/dt = f(z, s)`` over h, ``s`` the fraction of the step
    at which f is sampled (0, 1/2, 1: a time-dependent control is read there)."""
    k1 = f(z, 0.0)
    k2 = f(z + h / 2 * k1, 0.5)
    k3 = f(z + h / 2 * k2, 0.5)
    k4 = f(z + h * k3, 1.0)
    return z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
