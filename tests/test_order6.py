"""The sixth-order scheme: orders measured on refinements, the discrete Euler-Lagrange
residual with the solver's multipliers at the three Gauss points, the plan replayed by SciPy
as a user would, fatrop on its stages; on first-order problems the three-stage Gauss discrete
Lagrangian, its orders, multipliers and exported verdict."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.nlp.control_lines import ControlLines
from ocgroupoid.nlp.schemes import GaussStages3
from ocgroupoid.nlp.schemes.gauss import GAUSS3, SAMPLES6, hull_matrix
from ocgroupoid.systems.heavy_top import heavy_top
from ocgroupoid.systems.rigid_body import rigid_body
from ocgroupoid.verify.diagnostics import replay_of
from ocgroupoid.verify.graph import FIGURES, verify_function
from ocgroupoid.verify.verdict import REPLAY_TOLERANCE

from .test_api_general import cubic, minimum_acceleration, rolling_problem
from .test_order4 import (
    assert_clean,
    cost_orders,
    orders,
    replay_error,
    replay_slew,
    same_minimum,
)

ROOT = Path(__file__).resolve().parent.parent
MIN_ORDER = 5.5
SO3_NS = [4, 8, 16]
BALL_NS = [8, 16, 32, 64]


@pytest.fixture(scope="module")
def so3() -> dict[int, og.Solution]:
    return {N: og.solve(rigid_body(), N=N, scheme="order6") for N in [*SO3_NS, 32]}


def test_so3_converges_at_sixth_order(so3) -> None:
    """Cost and landing at order 6 (the landing's N = 32 is at the replay's own floor, ~3e-11,
    and left out of the orders); order4 lands over 1000 times farther at N = 8 and 16."""
    assert og.compile_problem(rigid_body(), N=4, scheme="order6").transcription.scheme \
        .cost_order == 6
    for sol in so3.values():
        assert_clean(sol)
        assert sol.discretization["scheme"] == "order6" and sol.iterations <= 10
        assert sol.diagnostics["verdict"]["verified"], sol.diagnostics["verdict"]
    costs = [so3[N].cost for N in [*SO3_NS, 32]]
    same_minimum(costs)
    assert np.all(cost_orders(costs) >= MIN_ORDER), (costs, cost_orders(costs))
    errors = [replay_error(so3[N], "R") for N in SO3_NS]
    assert np.all(orders(errors) >= MIN_ORDER), (errors, orders(errors))
    order4 = og.solve(rigid_body(), N=16, scheme="order4")
    assert replay_error(order4, "R") >= 100 * replay_error(so3[16], "R")


def test_control_polynomial_replayed_by_scipy_lands_on_target(so3) -> None:
    """The JSON's controls.ppoly (degree 6 on each interval, through the samples) replayed
    by DOP853: N = 16 lands within 1e-8 rad of the target, at rest (order4 needs N = 64)."""
    angle, shape, rate = replay_slew(so3[16], 1e-13)
    assert shape == (SAMPLES6.size, 16, 3)
    assert angle <= 1e-8 and rate <= 1e-8


def test_controls_are_the_polynomial_at_their_samples(so3) -> None:
    sol = so3[8]
    assert sol.controls_t.size == 6 * 8 + 1
    np.testing.assert_allclose(sol.control(sol.controls_t[:-1]), sol.controls[:-1], rtol=0,
                               atol=1e-12)  # each sample from the piece that starts there


def test_multipliers_sit_at_the_three_gauss_points_and_enter_the_residual() -> None:
    """The heavy top (constraints: the top's equations), N = 16, multi-start: Phi's
    multipliers at the three Gauss points of every interval, the discrete Euler-Lagrange
    residual with them at rounding, and the cheapest minimum known (order4's at N = 256:
    22.8193)."""
    sol = og.solve(heavy_top(), N=16, scheme="order6", multistart=True)
    assert sol.success, sol.status
    t = np.asarray(sol.multipliers["t"])
    h = sol.T / 16
    assert t.size == 48 and np.allclose(t[:3] / h, GAUSS3)
    assert np.asarray(sol.multipliers["Phi"]).shape == (48, 3)
    assert sol.diagnostics["euler_lagrange_residual_max"] <= 1e-8
    assert abs(sol.cost - 22.8193) <= 2e-3, sol.cost


@pytest.mark.parametrize("N", [2, 5])
def test_minimum_acceleration_cubic_is_exact(N: int) -> None:
    """The optimal path is a cubic, inside the scheme's space: every N reproduces it."""
    sol = og.solve(minimum_acceleration(), N=N, scheme="order6")
    assert sol.success
    assert np.max(np.abs(sol.states["q"] - cubic(sol.t))) <= 1e-10
    assert sol.diagnostics["euler_lagrange_residual_max"] <= 1e-10


def test_lines_land_at_sixth_order_and_cost_at_fourth() -> None:
    """Recovered controls drawn as lines (every bound on them; here |u| <= 10, never active):
    the dynamics a line drives are collocated at sixth order, so the plan lands at order 6,
    while the cost converges as the best line does, at order 4, to the recovered
    formulation's limit (measured: landing 4.9e-7, 7.6e-9, 1.2e-10 at N = 8, 16, 32; cost
    orders 3.78, 3.95, 3.99 from N = 4 against N = 128; the limits 7e-11 apart)."""
    cfg = files.load(ROOT / "problems" / "so3_rest_to_rest.yaml",
                     ["discretization.scheme=order6", "solver.multistart=false",
                      "bounds.u=[-10.0, 10.0]"])
    pb = files.build(cfg)
    sols = {}
    for N in (4, 8, 16, 32, 128):
        solver = og.compile_problem(pb, N=N, scheme="order6")
        assert isinstance(solver.transcription.scheme.stages, ControlLines)
        assert solver.transcription.scheme.cost_order == 4  # what Richardson estimates use
        sols[N] = solver.solve()
        assert sols[N].success, (N, sols[N].status)
    landing = [replay_error(sols[N], "R") for N in (8, 16, 32)]
    assert np.all(orders(landing) >= MIN_ORDER), (landing, orders(landing))
    errors = [abs(sols[N].cost - sols[128].cost) for N in (4, 8, 16, 32)]
    assert 3.7 <= orders(errors).min() and orders(errors).max() <= 4.5, orders(errors)
    recovered = og.solve(rigid_body(), N=128, scheme="order6", replay=False).cost
    assert abs(sols[128].cost - recovered) < 1e-9 * recovered


def test_fatrop_solves_its_stages_without_falling_back() -> None:
    """fatrop takes order6's stages as they come and reaches IPOPT's optimum."""
    ipopt = og.solve(rigid_body(), N=16, scheme="order6")
    fatrop = og.solve(rigid_body(), N=16, scheme="order6", backend="fatrop")
    assert fatrop.success and fatrop.diagnostics["runs"][-1]["backend"] == "fatrop", \
        fatrop.diagnostics["runs"]
    assert abs(fatrop.cost - ipopt.cost) <= 1e-10 * ipopt.cost


def test_bounds_hold_at_the_ends_and_gauss_points_and_more_on_demand() -> None:
    """The reaction wheels' rate bounds: one row per bound point, five per interval (ends and
    three Gauss points), two more with ``bound_points: 2``; the optimum within them."""
    cfg = files.load(ROOT / "problems" / "reaction_wheels.yaml",
                     ["discretization.scheme=order6", "solver.multistart=false"])
    pb = files.build(cfg)
    rows = {}
    for extra in (0, 2):
        solver = og.compile_problem(pb, N=8, scheme="order6", bound_points=extra)
        assert np.allclose(solver.transcription.scheme.bound_times,
                           np.unique([0.0, *GAUSS3, 1.0, *np.arange(1, extra + 1) /
                                      (extra + 1)]))
        sol = solver.solve()
        assert sol.success, sol.status
        assert sol.diagnostics["verdict"]["verified"], sol.diagnostics["verdict"]
        rows[extra] = solver.transcription.rows(og.nlp.Kind.INEQUALITY).size
    assert rows[2] * 5 == rows[0] * 7


@pytest.fixture(scope="module")
def balls() -> dict[str, dict[int, og.Solution]]:
    """Both plate-ball files with order6 (the three-stage Gauss discrete Lagrangian) on
    N = 8 ... 64, multi-start."""
    out = {}
    for name in ("plate_ball", "plate_ball_rotating"):
        pb = files.build(files.load(ROOT / "problems" / f"{name}.yaml"))
        out[name] = {N: og.compile_problem(pb, N=N, scheme="order6").solve(multistart=True)
                     for N in BALL_NS}
    return out


@pytest.mark.parametrize("name", ["plate_ball", "plate_ball_rotating"])
def test_plate_ball_converges_at_sixth_order(balls, name: str) -> None:
    """First-order problems: cost and landing at order 6 (measured 5.6-5.95 on N = 8 ... 64),
    clean and verified; order4 lands at least 20 times farther at N = 16 (measured 45 and
    158 times); the velocities and controls are read out as the quadratic through the three
    stages of each interval."""
    sols = balls[name]
    assert isinstance(og.compile_problem(files.build(files.load(
        ROOT / "problems" / f"{name}.yaml")), N=4, scheme="order6").transcription.scheme,
        GaussStages3)
    for sol in sols.values():
        assert_clean(sol)
        assert sol.discretization["scheme"] == "order6"
        assert sol.diagnostics["verdict"]["verified"], sol.diagnostics["verdict"]
    costs = [sols[N].cost for N in BALL_NS]
    same_minimum(costs)
    assert np.all(cost_orders(costs) >= MIN_ORDER), (costs, cost_orders(costs))
    errors = [sols[N].diagnostics["replay"]["max_terminal_error"] for N in BALL_NS]
    assert np.all(orders(errors) >= MIN_ORDER), (errors, orders(errors))
    order4 = files.build(files.load(ROOT / "problems" / f"{name}.yaml"))
    landing4 = og.compile_problem(order4, N=16, scheme="order4").solve(multistart=True) \
        .diagnostics["replay"]["max_terminal_error"]
    assert landing4 >= 20 * errors[1], (landing4, errors[1])
    assert sols[16].control_ppoly["c"].shape == (3, 16, 2)


def test_plate_ball_multipliers_sit_at_the_three_stages(balls) -> None:
    sol = balls["plate_ball"][16]
    h = sol.T / 16
    t = np.asarray(sol.multipliers["t"])
    assert t.size == 48 and np.allclose(t[:3] / h, GAUSS3)
    assert np.asarray(sol.multipliers["Phi"]).shape[0] == 48
    assert np.allclose(sol.velocity_t[:3] / h, GAUSS3)


def rolled_by_its_velocities() -> og.Problem:
    """A first-order problem whose plan the replay drives by its velocities (no controls:
    the five velocities, three of them fixed by the rolling constraint): roll a ball on
    the plane back to its start, turned by 1 rad about the vertical."""
    return rolling_problem(controls=False, xy=[0, 0], R=og.so3.from_rotvec([0, 0, 1.0]))


def test_exported_verdict_replays_the_quadratic_velocities() -> None:
    """A plan driven by its velocities: the replay follows the quadratic through each
    interval's three stage velocities, in Python and in the verdict's graph (what exported C
    checks), and lands at order 6 (measured 5.70, 5.93). The graph's replay (64 RK4 substeps,
    which agree with 256 to 1e-11) and Python's agree to 1e-3 of the miss, the accuracy
    Python's replay claims: it used to extrapolate against an already extrapolated result and
    reported misses up to 0.4 % off (0.15 % here at N = 8, 0.4 % on plate_ball at N = 16)."""
    errors = []
    for N in (8, 16, 32):
        solver = og.compile_problem(rolled_by_its_velocities(), N=N, scheme="order6")
        sol = solver.solve(multistart=True)
        replay = sol.diagnostics["replay"]
        assert sol.success and replay["input"] == "velocities", replay
        assert sol.diagnostics["verdict"]["verified"], sol.diagnostics["verdict"]
        tr = solver.transcription
        verify = verify_function(tr, replay_of(tr), 64, 1e-6, REPLAY_TOLERANCE)
        _, figures = verify(sol.x, sol.p, sol.lam_g)
        miss = float(figures[FIGURES.index("max_terminal_error")])
        assert miss == pytest.approx(replay["max_terminal_error"], rel=1e-3), (N, miss, replay)
        errors.append(miss)
    assert np.all(orders(errors) >= MIN_ORDER), (errors, orders(errors))


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-10, 10), min_size=3, max_size=3), st.integers(0, 6))
def test_the_bernstein_hull_bounds_the_quadratic_through_the_stages(coeff: list[float],
                                                                     elevate: int) -> None:
    """What first-order order6 bounds (:func:`hull_matrix`): the Bernstein coefficients of
    the quadratic through the three stage values reproduce it, it lies within their range on
    the whole interval, and each degree elevation only tightens that range."""
    from math import comb
    t = np.linspace(0.0, 1.0, 201)
    p = coeff[0] + coeff[1] * t + coeff[2] * t ** 2
    at_stages = coeff[0] + coeff[1] * GAUSS3 + coeff[2] * GAUSS3 ** 2
    b = hull_matrix(GAUSS3, elevate) @ at_stages
    n = b.size - 1
    assert b.size == 3 + elevate
    curve = sum(b[m] * comb(n, m) * t ** m * (1 - t) ** (n - m) for m in range(n + 1))
    assert np.allclose(curve, p, atol=1e-9)
    assert b.min() <= p.min() + 1e-9 and b.max() >= p.max() - 1e-9
    coarser = hull_matrix(GAUSS3, max(elevate - 1, 0)) @ at_stages
    assert coarser.min() <= b.min() + 1e-9 and coarser.max() >= b.max() - 1e-9
