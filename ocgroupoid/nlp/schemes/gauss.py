"""The numbers of order4 and order6: Gauss-Legendre points and weights on [0, 1], their
collocation (Runge-Kutta) matrices, where their bounds hold and their controls are sampled,
and the polynomials their read-outs report (the quadratic or cubic velocity of an interval,
the controls through its samples, lines)."""

from __future__ import annotations

from math import comb
from typing import Any

import casadi as ca
import numpy as np

SQRT3, SQRT15 = float(np.sqrt(3.0)), float(np.sqrt(15.0))
GAUSS2 = np.array([0.5 - SQRT3 / 6, 0.5 + SQRT3 / 6])  # nodes of the 2-point rule on [0, 1]
GAUSS3 = np.array([0.5 - SQRT15 / 10, 0.5, 0.5 + SQRT15 / 10])
GAUSS3_W = np.array([5.0, 8.0, 5.0]) / 18.0


def lagrange_integrals(nodes: np.ndarray, c: float) -> np.ndarray:
    """``int_0^c l_j(tau) dtau`` for the Lagrange basis ``l_j`` of ``nodes``: the weights
    that turn the stage rates of a collocation polynomial into its coordinates at ``c``
    (at ``c = c_i`` the row i of the collocation method's Runge-Kutta matrix, Hairer-Wanner
    II.7 (7.5))."""
    k = nodes.size
    V_inv = np.linalg.inv(np.vander(nodes, k, increasing=True))  # l_j = sum_p V_inv[p, j] t^p
    return np.array([sum(V_inv[p, j] * c ** (p + 1) / (p + 1) for p in range(k))
                     for j in range(k)])


def lagrange_values(nodes: np.ndarray, c: float) -> np.ndarray:
    """``l_j(c)`` for the Lagrange basis of ``nodes``: the stage rates' weights in the
    collocation polynomial's rate at ``c``."""
    return np.array([np.prod([(c - m) / (n - m) for m in nodes if m != n]) for n in nodes])


#: the Runge-Kutta matrices of the 2- and 3-stage Gauss methods
GAUSS2_A = np.array([lagrange_integrals(GAUSS2, float(c)) for c in GAUSS2])
GAUSS3_A = np.array([lagrange_integrals(GAUSS3, float(c)) for c in GAUSS3])
#: where bounds hold on each interval: both ends and the Gauss points (a control that is
#: linear on an interval then respects them everywhere; bounding only at the Gauss points
#: let adaptive steps stretch a linear control beyond its limit between them)
BOUND_POINTS = np.array([0.0, *GAUSS2, 1.0])
#: where a cubic control is sampled per interval: the bound points, so that the control a
#: solution reports equals the bounded one wherever a bound is imposed
SAMPLES = BOUND_POINTS
#: order6's: the bounds at both ends and its three Gauss points
BOUND_POINTS6 = np.array([0.0, *GAUSS3, 1.0])
#: where order6 samples a control (a polynomial of degree 6 through them, so that the
#: read-out's interpolation error, O(h^7) per interval, stays below the scheme's): its bound
#: points and the quarters between them
SAMPLES6 = np.array([0.0, GAUSS3[0], 0.25, 0.5, 0.75, GAUSS3[2], 1.0])


def quadratic(y0: Any, y1: Any, b: Any, h: Any, tau: float) -> tuple[Any, Any]:
    """The velocity at ``t_k + tau h`` and its rate, for node values y0, y1 and bubble b."""
    y = (1 - tau) * y0 + tau * y1 + 4 * tau * (1 - tau) * b
    dy = (y1 - y0 + 4 * (1 - 2 * tau) * b) / h
    return y, dy


def cubic(y0: Any, y1: Any, b: Any, h: Any, tau: float) -> tuple[Any, Any]:
    """order6's velocity at ``t_k + tau h`` and its rate, for node values y0, y1 and bubbles
    ``b = (b1, b2)`` (stacked): ``y = (1 - tau) y0 + tau y1 + 4 tau (1 - tau) (b1 + b2 (2 tau
    - 1))``, b1 the value at the midpoint minus the mean of the ends (as order4's bubble), b2
    the odd cubic part."""
    n = b.shape[0] // 2
    b1, b2 = b[:n], b[n:]
    w = b1 + (2 * tau - 1) * b2
    y = (1 - tau) * y0 + tau * y1 + 4 * tau * (1 - tau) * w
    dy = (y1 - y0 + 4 * (1 - 2 * tau) * w + 8 * tau * (1 - tau) * b2) / h
    return y, dy


def polynomial_coefficients(samples: Any, at: np.ndarray, h: Any) -> Any:
    """PPoly coefficients (highest power first, in t - t_k) of the polynomials of degree
    ``at.size - 1`` through samples at the fractions ``at`` of each interval: rows
    ``power * m + component``, one column per interval, for samples given as ``at.size``
    blocks of m rows and steps h (1 x N)."""
    k = at.size
    V_inv = np.linalg.inv(np.vander(at, k, increasing=True))  # alpha_j of tau^j
    m = samples.size1() // k
    H = ca.repmat(h, m, 1)
    blocks = [samples[i * m:(i + 1) * m, :] for i in range(k)]
    alpha = [sum(float(V_inv[j, i]) * blocks[i] for i in range(k)) for j in range(k)]
    return ca.vertcat(*[alpha[j] / H**j for j in range(k - 1, -1, -1)])


def hull_matrix(nodes: np.ndarray, elevate: int = 0) -> np.ndarray:
    """The Bernstein coefficients, on [0, 1], of the polynomial of degree ``nodes.size - 1``
    through values at ``nodes``, degree-elevated ``elevate`` times: a matrix of
    ``nodes.size + elevate`` rows applied to the values. The polynomial lies in the convex
    hull of its coefficients (Farin, Curves and Surfaces for CAGD, §5.3), so bounds on them
    bound it on the whole interval; each elevation (ibid. §6.1, ``b'_i = i/(n+1) b_{i-1} +
    (1 - i/(n+1)) b_i``) tightens the hull towards the polynomial."""
    n = nodes.size - 1
    basis = np.array([[comb(n, m) * c ** m * (1 - c) ** (n - m) for m in range(n + 1)]
                      for c in nodes])
    M = np.linalg.inv(basis)
    for d in range(n, n + elevate):
        E = np.zeros((d + 2, d + 1))
        for i in range(d + 2):
            if i > 0:
                E[i, i - 1] = i / (d + 1)
            if i <= d:
                E[i, i] = 1 - i / (d + 1)
        M = E @ M
    return M


def bound_times(extra: int, points: np.ndarray = BOUND_POINTS) -> np.ndarray:
    """Where the bounds hold on an interval (fractions): a scheme's ``points``
    (:data:`BOUND_POINTS`) and ``extra`` more, uniformly spaced inside
    (``discretization.bound_points``)."""
    inside = np.arange(1, extra + 1) / (extra + 1)
    return np.unique(np.concatenate([points, inside]))

