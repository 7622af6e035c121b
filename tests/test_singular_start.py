"""A first guess where the constraints lose rank: the plate-ball's straight roll.

Along a straight roll the linearised rolling constraints reach every final state but one
direction of the orientation, which only the Lie bracket of the rolling fields reaches: the
equality Jacobian at the geodesic guess is singular (to the discretisation's error), and
full rank at the solution. IPOPT regularises a singular Jacobian by
``jacobian_regularization_value * mu^(1/4)``; at its default 1e-8 the first step solved a
nearly singular system and rounding chose its direction (order4 at N = 64: 88 iterations, 64
of them restoring feasibility). Our default (``DEFAULT_IPOPT``, 1e-6) makes the step
well-posed.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import ocgroupoid as og
from ocgroupoid import files

PLATE_BALL = Path(__file__).resolve().parent.parent / "problems" / "plate_ball.yaml"


def compiled(N: int) -> og.CompiledProblem:
    cfg = files.load(PLATE_BALL, [f"horizon.N={N}", "discretization.scheme=order4",
                                  "solver.backend=ipopt", "solver.multistart=false"])
    return og.compile_problem(*files.build_all(cfg))


def relative_singular_values(cp: og.CompiledProblem, x: np.ndarray) -> np.ndarray:
    """The equality Jacobian's singular values at x over its largest (every row of the
    plate-ball is an equality)."""
    tr = cp.transcription
    J = np.array(tr.functions["nlp_jac_g"](x, tr.pack())[1])
    s = np.linalg.svd(J, compute_uv=False)
    return s / s[0]


def test_the_straight_roll_is_a_singular_point_of_the_constraints() -> None:
    """At N = 16 the Jacobian at the first geodesic guess has one singular value below 1e-8
    of its largest (8e-10), the next 5e-4; at the solution none is below 1e-5 (3e-4)."""
    cp = compiled(16)
    tr = cp.transcription
    p = tr.pack()
    x0, _ = tr.start_point(cp.guesses(tr, p, False)[0], p)
    at_guess = relative_singular_values(cp, x0)
    sol = cp.solve(multistart=False)
    at_solution = relative_singular_values(cp, sol.x)
    assert at_guess[-1] < 1e-8 < at_guess[-2], at_guess[-3:]  # one direction lost
    assert at_solution[-1] > 1e-5, at_solution[-3:]


def test_ipopt_leaves_the_singular_start_whatever_the_rounding() -> None:
    """From the straight roll, its target moved by 0, 1e-15 and 1e-13, order4 at N = 64
    reaches the same minimum (order6's to its discretisation error) in at most 40 iterations
    each (88 at IPOPT's default regularisation, 33-89 with the Runge-Kutta matrix one ulp
    off)."""
    cp = compiled(64)
    sols = [cp.solve(final={"xy": [1.0, 0.5 + shift]}, multistart=False)
            for shift in (0.0, 1e-15, 1e-13)]
    assert [(s.success, s.iterations <= 40) for s in sols] == [(True, True)] * 3, \
        [(s.status, s.iterations) for s in sols]
    finer = og.solve(cp.problem, N=64, scheme="order6", multistart=False)
    for s in sols:
        assert abs(s.cost - sols[0].cost) <= 1e-9
        assert abs(s.cost - finer.cost) <= 1e-5, (s.cost, finer.cost)
