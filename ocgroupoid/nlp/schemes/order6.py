"""Sixth-order scheme (``order6``) of second-order problems.

:class:`CubicGauss` is :class:`~.order4.QuadraticGauss` one degree up. The velocity on
interval k is the cubic through the node values ``y_k, y_{k+1}`` with two bubbles,
``y = (1 - tau) y_k + tau y_{k+1} + 4 tau (1 - tau) (b1_k + b2_k (2 tau - 1))``
(:func:`~.gauss.cubic`), continuous across nodes. The constraints ``Phi = 0`` hold at the
three Gauss points (each row scaled by its quadrature weight ``h w_i``), and the cost
``int Ltilde(q, y, dy) dt`` is the 3-point Gauss rule. The three unknowns per component and
interval (``y_{k+1}, b1_k, b2_k``) are fixed by the three Gauss points for the unactuated
components: on ``dy/dt = lambda y`` the step is Gauss-Legendre's three-stage method, the
(3, 3) Padé approximant of ``exp(z)`` (order 6, A-stable, one root). From node to node the
group increment is the sixth-order Magnus step from the cubic's values at the Gauss points
(:meth:`Factor.magnus6`, local error O(h^7)), as in order4; inside the interval, where the
Lagrangian and the bounds need q, the same step over ``[t_k, t_k + c h]`` (order4's
fourth-order step would cap the scheme at order 4).

The bounds hold at both ends and the three Gauss points of every interval
(:data:`~.gauss.BOUND_POINTS6`); the read-out samples the controls there and at the
quarters (:data:`~.gauss.SAMPLES6`) and reports the polynomial of degree 6 through the
samples, whose interpolation error stays below the scheme's. Controls of their own are
linear on an interval, as in order4 (their end values are the variables), and so are
recovered controls drawn as lines (:class:`~ocgroupoid.nlp.control_lines.ControlLines`):
the dynamics a line drives are still collocated at order 6, so the plan lands at order 6,
but the cost converges as the best line does, at order 4 (:attr:`CubicGauss.cost_order`,
what Richardson estimates use). Measured with lines on so3_rest_to_rest (``|u| <= 10``, never
active): landing 4.9e-7, 7.6e-9, 1.2e-10 at N = 8, 16, 32, cost orders 3.78, 3.95, 3.99; on
the quadrotor (thrust and torques of their own): landing 5.1e-6, 8.7e-8, 1.5e-9 at N = 16,
32, 64, the cost error falling 16 times per doubling.

Measured (the work-precision run of so3_rest_to_rest, 2026-12-02, docs/benchmarks): the
relative cost error 5.3e-7, 8.5e-9, 1.4e-10 at N = 8, 16, 32 (order4 1.1e-4, 7.6e-6,
4.8e-7), the landing 3.7e-8, 5.9e-10, 3.0e-11 (order4 4.4e-5, 2.7e-6, 1.7e-7), each solve in
the same 4 iterations as order4's at 1.0-1.2 times its time with fatrop.
"""

from __future__ import annotations

from typing import Any, ClassVar

import casadi as ca
import numpy as np

from .gauss import BOUND_POINTS6, GAUSS3, GAUSS3_W, SAMPLES6, cubic
from .order4 import QuadraticGauss


class CubicGauss(QuadraticGauss):
    """Second-order problems: continuous piecewise-cubic velocities, Phi and the cost at the
    three Gauss points, sixth-order Magnus steps (module docstring)."""

    name = "order6"
    accuracy = 6
    summary = ("piecewise-cubic velocity, 3-point Gauss cost, Phi at the 3 Gauss points "
               "(Gauss-Legendre collocation), 6th-order Magnus steps with exp")
    bubbles: ClassVar[int] = 2
    collocation: ClassVar[np.ndarray] = GAUSS3
    collocation_weights: ClassVar[np.ndarray] = GAUSS3_W
    base_bound_times: ClassVar[np.ndarray] = BOUND_POINTS6
    samples: ClassVar[np.ndarray] = SAMPLES6
    velocity = staticmethod(cubic)

    @property
    def cost_order(self) -> int:
        """6, or 4 where the controls are lines on each interval (controls of their own, or
        recovered ones drawn as lines): the cost then converges as the best line does
        (module docstring), while the plan still lands at order 6."""
        return 4 if self.stages.n_u else self.accuracy

    @staticmethod
    def inner_step(G: Any, velocity: Any, c: float, h: ca.SX) -> ca.SX:
        """Exponential coordinates of the step over ``[t_k, t_k + c h]``: the sixth-order
        Magnus step from the cubic at that subinterval's three Gauss points (local O(h^7))."""
        g1, g2, g3 = (velocity(c * float(g))[0] for g in GAUSS3)
        return G.magnus6(g1, g2, g3, c * h)
