"""The API is general: a problem shipped nowhere in systems/, stated in a few lines."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import ocgroupoid as og

T = 2.0
Q0, V0 = np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.0, -1.0])
Q1, V1 = np.array([1.0, 2.0, 3.0]), np.array([0.0, 1.0, 0.0])


def minimum_acceleration() -> og.Problem:
    """min 1/2 int |d2q/dt2|^2 on R^3 with the pair groupoid (seed 000, §3.1.1, eq. 16)."""
    pb = og.Problem(og.Pair(3, state="q", velocity="v"), name="min_acceleration")
    a = pb.acceleration("v")
    pb.minimize(0.5 * ca.sumsqr(a))
    pb.report_controls(a, ["a1", "a2", "a3"])
    pb.initial(q=Q0, v=V0)
    pb.final(q=Q1, v=V1)
    pb.horizon(T)
    return pb


def cubic(t: np.ndarray) -> np.ndarray:
    s = t / T
    h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, \
        s**3 - s**2
    return (h00[:, None] * Q0 + h10[:, None] * T * V0 + h01[:, None] * Q1
            + h11[:, None] * T * V1)


@pytest.fixture(scope="module")
def sols() -> dict[int, og.Solution]:
    pb = minimum_acceleration()
    return {N: og.solve(pb, N=N) for N in (8, 16, 32, 64, 128)}


def test_interior_nodes_satisfy_the_discrete_equations(sols) -> None:
    for N, sol in sols.items():
        q = sol.states["q"]
        fourth = q[4:] - 4 * q[3:-1] + 6 * q[2:-2] - 4 * q[1:-3] + q[:-4]
        assert np.max(np.abs(fourth)) <= 1e-10, N
        assert sol.diagnostics["euler_lagrange_residual_max"] <= 1e-10, N


def test_nodes_converge_to_the_cubic_at_second_order(sols) -> None:
    err = [np.max(np.abs(sol.states["q"] - cubic(sol.t))) for sol in sols.values()]
    orders = np.log2(np.array(err[:-1]) / np.array(err[1:]))
    assert np.all(orders >= 1.8), (err, orders)


def test_replay_of_accelerations_lands_on_target(sols) -> None:
    errs = [s.diagnostics["replay"]["terminal_error"]["q"] for s in sols.values()]
    assert np.all(np.log2(np.array(errs[:-1]) / np.array(errs[1:])) >= 1.8)


def rolling_problem(controls: bool = True, **final: object) -> og.Problem:
    """A kinematic first-order problem on R^2 x SO(3): roll, w = (-v_y, v_x, 0); without
    ``controls`` it reports none, and its replay is driven by its velocities."""
    G = og.Groupoid(og.Pair(2, "xy", "v"), og.LieGroupFactor(state="R", velocity="w",
                                                             side="left"))
    pb = og.Problem(G, name="roll", order=1)
    v, w = pb.velocity("v"), pb.velocity("w")
    pb.minimize(0.5 * ca.sumsqr(v))
    pb.subject_to(w - ca.vertcat(-v[1], v[0], 0), name="roll")
    if controls:
        pb.report_controls(v, ["vx", "vy"])
    pb.initial(xy=[0, 0], R=np.eye(3))
    pb.final(**final)
    pb.horizon(1.0)
    return pb


def test_first_order_problem_on_a_product() -> None:
    """Reach a target on R^2 with the attitude free: roll straight at unit speed."""
    sol = og.solve(rolling_problem(xy=[1.0, 0.0]), N=32)
    assert sol.success
    assert np.allclose(sol.controls[1:-1], [[1.0, 0.0]] * 32, atol=1e-8)
    assert sol.cost == pytest.approx(0.5, rel=1e-9)
    R_end = sol.states["R"][-1]
    assert np.allclose(R_end, og.so3.from_rotvec([0, 1.0, 0]), atol=1e-3)
    assert sol.diagnostics["replay"]["available"]
    assert sol.diagnostics["euler_lagrange_residual_max"] <= 1e-8
