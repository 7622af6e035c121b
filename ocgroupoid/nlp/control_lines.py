"""Bounded recovered controls drawn as lines: the stages ``order4`` builds when a bound reads
a control that the dynamics recover.

A recovered control is an expression of the motion, ``u = B(q)^-1 (EL residual of the
actuated velocities)`` (:meth:`~ocgroupoid.model.statement.Statement.mechanics` with an
input matrix). Bounded as it is, each bound row of ``order4`` reads the whole interval's
motion at four points, and the control may still overshoot between them. Here the
recovered controls become variables instead, linear on each interval as controls of their
own are (their values at the interval's two ends), with ``u_rec(t) - u(t) = 0`` at the two
Gauss points, where the cost and ``Phi`` are evaluated: the same continuous problem written
as ``EL = B u``, the cost by the two-point Gauss rule (exact on a line's square). A bound
on a control is then a bound on its line, held on the whole interval by its two ends. The
scheme keeps its order: on ``so3_rest_to_rest`` with ``|u| <= 10`` (never active) the cost
converges at orders 3.95, 3.99, 4.00 (N = 8 to 64 against 256), with errors 1.6 times
smaller than the recovered controls', to the same limit (2e-11 apart).

Measured (``so3_minimum_time``, N = 32, 64, 128, from the first guess): fatrop took 61, 72,
72 iterations with the recovered controls bounded at four points, and 19, 20, 26 with the
lines; IPOPT 29, 33, 34 and 20, 22, 22. The costs are lower at every N (3.714345 against
3.714589 at N = 64) and the controls stay within their bounds everywhere (the cubics
overshot them between the bound points by 6.1e-3 at N = 16). Where a bound also reads the
motion (the reaction wheels' wheel rates, the cart-pole's track), those rows stay at the
four points, and lines gained nothing reliable there: fatrop took 73 and 108 iterations on
the reaction wheels at N = 32 and 64 (63 and 53 before) and stalled near the cart-pole's
solution at N = 64; so they are drawn only where every bound is on a control.
"""

from __future__ import annotations

import casadi as ca

from ..lie.retraction import Retraction
from ..model.problem import Problem
from .stages import Stages

#: the suffix of the rows that tie a recovered control to its line
TIE = "on its line"


def bounded_controls(problem: Problem) -> list[int] | None:
    """For a problem without controls of their own that bounds its recovered controls (the
    reported controls) and nothing else, the control each bound row is (its index among
    them: the row's expression is that control's, the same expression node, as ``bounds:
    {u: ...}`` gives); None for any other problem."""
    if problem.U.numel() or not problem.controls or problem.order != 2 \
            or not problem.inequalities:
        return None
    controls = [c for _, c in problem.controls]
    rows = [next((j for j, c in enumerate(controls) if ca.is_equal(b.expr[i], c, 0)), None)
            for b in problem.inequalities for i in range(b.expr.numel())]
    return None if None in rows else [j for j in rows if j is not None]


class ControlLines(Stages):
    """:class:`Stages` with the recovered controls as variables ``U`` (module docstring):
    they are the reported controls, the rows ``u_rec - U`` join the constraints, and every
    bound row reads its control's variable (a problem :func:`bounded_controls` accepts)."""

    def __init__(self, problem: Problem, retractions: list[Retraction],
                 bounded: list[int]) -> None:
        super().__init__(problem, retractions)
        self.recovered = ca.vertcat(*[c for _, c in problem.controls])
        self.U = ca.SX.sym("u_line", self.recovered.numel())
        self._bounded = bounded
        G = problem.groupoid
        s, y = ca.SX.sym("s", G.state_size), ca.SX.sym("y", G.algebra_dim)
        dy, u0 = ca.SX.sym("dy", G.algebra_dim), ca.SX.sym("u0", self.n_u)
        #: the recovered controls themselves explain the motion exactly (the guesses' lines)
        self.estimate = ca.Function("control_estimate", [s, y, dy, problem.P, u0],
                                    self.at([self.recovered], s, y, dy),
                                    ["s", "y", "dy", "P", "u0"], ["u"])

    @property
    def controls(self) -> ca.SX:
        return self.U

    @property
    def constraints(self) -> ca.SX:
        return ca.vertcat(super().constraints, self.recovered - self.U)

    @property
    def constraint_names(self) -> list[str]:
        return super().constraint_names + [f"{n} {TIE}" for n, _ in self.problem.controls]

    @property
    def inequalities(self) -> ca.SX:
        return self.U[self._bounded]


__all__ = ["ControlLines", "bounded_controls", "TIE"]
