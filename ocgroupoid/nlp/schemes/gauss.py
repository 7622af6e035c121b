"""The numbers of order4: Gauss-Legendre points and weights on [0, 1], where its bounds hold
and its controls are sampled, and the polynomials its read-out reports (the quadratic velocity
of an interval, the cubic and linear controls through its samples)."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

SQRT3, SQRT15 = float(np.sqrt(3.0)), float(np.sqrt(15.0))
GAUSS2 = np.array([0.5 - SQRT3 / 6, 0.5 + SQRT3 / 6])  # nodes of the 2-point rule on [0, 1]
GAUSS2_A = np.array([[0.25, 0.25 - SQRT3 / 6], [0.25 + SQRT3 / 6, 0.25]])  # its RK matrix
GAUSS3 = np.array([0.5 - SQRT15 / 10, 0.5, 0.5 + SQRT15 / 10])
GAUSS3_W = np.array([5.0, 8.0, 5.0]) / 18.0
#: where bounds hold on each interval: both ends and the Gauss points (a control that is
#: linear on an interval then respects them everywhere; bounding only at the Gauss points
#: let adaptive steps stretch a linear control beyond its limit between them)
BOUND_POINTS = np.array([0.0, *GAUSS2, 1.0])
#: where a cubic control is sampled per interval: the bound points, so that the control a
#: solution reports equals the bounded one wherever a bound is imposed
SAMPLES = BOUND_POINTS


def quadratic(y0: Any, y1: Any, b: Any, h: Any, tau: float) -> tuple[Any, Any]:
    """The velocity at ``t_k + tau h`` and its rate, for node values y0, y1 and bubble b."""
    y = (1 - tau) * y0 + tau * y1 + 4 * tau * (1 - tau) * b
    dy = (y1 - y0 + 4 * (1 - 2 * tau) * b) / h
    return y, dy


def cubic_coefficients(samples: Any, h: Any) -> Any:
    """PPoly coefficients (highest power first, in t - t_k) of the cubics through samples
    at :data:`SAMPLES` of each interval: rows ``power * m + component``, one column per
    interval, for samples given as 4 blocks of m rows and steps h (1 x N)."""
    V_inv = np.linalg.inv(np.vander(SAMPLES, 4, increasing=True))  # alpha_j of tau^j
    m = samples.size1() // 4
    H = ca.repmat(h, m, 1)
    blocks = [samples[i * m:(i + 1) * m, :] for i in range(4)]
    alpha = [sum(float(V_inv[j, i]) * blocks[i] for i in range(4)) for j in range(4)]
    return ca.vertcat(*[alpha[j] / H**j for j in (3, 2, 1, 0)])


def linear_coefficients(u0: Any, u1: Any, t0: float, t1: float, h: Any) -> Any:
    """PPoly coefficients of the lines through u0 at t_k + t0 h and u1 at t_k + t1 h, in
    t - t_k (rows: slope block, then value block), for steps h (1 x N)."""
    H = ca.repmat(h, u0.size1(), 1)
    slope = (u1 - u0) / ((t1 - t0) * H)
    return ca.vertcat(slope, u0 - slope * t0 * H)


def bound_times(extra: int) -> np.ndarray:
    """Where the bounds hold on an interval (fractions): :data:`BOUND_POINTS` and ``extra``
    more, uniformly spaced inside (``discretization.bound_points``)."""
    inside = np.arange(1, extra + 1) / (extra + 1)
    return np.unique(np.concatenate([BOUND_POINTS, inside]))

