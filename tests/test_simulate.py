"""og.simulate: the variational integrator against RK4 over 10^5 steps (issue 16).

The free rigid body tumbles near its unstable middle axis; the free heavy top (rotor torques
zero) precesses and nutates. At h = 0.1 the variational integrator's energy error at the
nodes is O(h^2) and does not grow, its states stay on the group to rounding and the rigid
body's quadratic invariants of the interval velocities are conserved to rounding; RK4 at the
same step drifts (linearly in time) and leaves the group.
"""

from __future__ import annotations

import numpy as np
import pytest

import ocgroupoid as og
from ocgroupoid.errors import ConfigError, DimensionError, SolverError
from ocgroupoid.systems.heavy_top import heavy_top
from ocgroupoid.systems.plate_ball import plate_ball
from ocgroupoid.systems.rigid_body import rigid_body

H, STEPS = 0.1, 100_000
INERTIA = np.array([1.0, 2.0, 3.0])
RIGID_OMEGA0 = (0.1, 1.0, 0.1)  # near the unstable middle axis: it flips over and back
TOP_OMEGA0 = (0.5, -0.3, 5.0)


@pytest.fixture(scope="module")
def rigid() -> og.Simulation:
    return og.simulate(rigid_body(Omega0=RIGID_OMEGA0), h=H, steps=STEPS)


@pytest.fixture(scope="module")
def top() -> og.Simulation:
    return og.simulate(heavy_top(Omega0=TOP_OMEGA0), h=H, steps=STEPS)


def halves(error: np.ndarray) -> tuple[float, float]:
    """max |error| over the first and over the second half of the run."""
    e, n = np.abs(error), len(error) // 2
    return float(np.max(e[:n])), float(np.max(e[n:]))


def test_trajectory_has_every_node(rigid: og.Simulation) -> None:
    assert rigid.t.shape == (STEPS + 1,) and rigid.t[-1] == pytest.approx(H * STEPS)
    assert rigid.states.shape == (STEPS + 1, 4) and rigid.velocities.shape == (STEPS + 1, 3)
    assert rigid.xi.shape == (STEPS, 3) and rigid.rk4.states.shape == (STEPS + 1, 4)
    assert np.allclose(rigid.velocities[0], RIGID_OMEGA0) and np.allclose(rigid.rk4.velocities[0],
                                                                          RIGID_OMEGA0)
    assert np.ptp(rigid.velocities[:, 1]) > 1.5  # the body flips: Omega2 changes sign


@pytest.mark.parametrize("name", ["rigid", "top"])
def test_variational_energy_error_is_bounded_and_rk4_drifts(name: str, request) -> None:
    sim = request.getfixturevalue(name)
    E0 = abs(sim.variational.energy[0])
    vi_first, vi_second = halves(sim.variational.energy_error)
    rk_first, rk_second = halves(sim.rk4.energy_error)
    assert vi_second <= 1.05 * vi_first, (vi_first, vi_second)  # no drift
    assert vi_first <= 0.2 * H**2 * E0, vi_first  # an O(h^2) oscillation
    assert rk_second >= 1.3 * rk_first, (rk_first, rk_second)  # RK4 drifts
    if name == "top":
        assert abs(sim.rk4.energy_error[-1]) >= 10 * vi_second, (sim.rk4.energy_error[-1],
                                                                 vi_second)


def test_rigid_body_interval_invariants_are_conserved_to_rounding(rigid: og.Simulation) -> None:
    """Energy and |I xi|^2 of the interval velocities: to rounding, far below RK4's drift."""
    energy = rigid.interval_energy
    assert np.allclose(energy, 0.5 * np.sum(INERTIA * rigid.xi**2, axis=1), rtol=1e-14)
    casimir = np.sum((INERTIA * rigid.xi) ** 2, axis=1)
    for invariant in (energy, casimir):
        assert np.max(np.abs(invariant - invariant[0])) <= 1e-12 * invariant[0]
    assert abs(rigid.rk4.energy_error[-1]) >= 1e3 * np.max(np.abs(energy - energy[0]))


@pytest.mark.parametrize("name,state", [("rigid", slice(0, 4)), ("top", slice(0, 3))])
def test_states_stay_on_the_group(name: str, state: slice, request) -> None:
    """|q| = 1 (rigid body) and |Gamma| = 1 (heavy top) to rounding; RK4 leaves."""
    sim = request.getfixturevalue(name)
    vi = np.abs(np.linalg.norm(sim.states[:, state], axis=1) - 1)
    rk = np.abs(np.linalg.norm(sim.rk4.states[:, state], axis=1) - 1)
    assert np.max(vi) <= 1e-12 and rk[-1] >= 1e3 * np.max(vi)


def test_heavy_top_casimir_is_bounded_and_rk4_drifts(top: og.Simulation) -> None:
    """Pi . Gamma: the midpoint rule keeps an O(h^2) oscillation (with a slow drift of a
    few per cent of it over the run); RK4's error grows to many times that."""
    C = top.variational.invariants["Pi.Gamma"]
    C_rk = top.rk4.invariants["Pi.Gamma"]
    vi_first, vi_second = halves(C - C[0])
    rk_first, rk_second = halves(C_rk - C_rk[0])
    assert vi_second <= 1.1 * vi_first and vi_first <= H**2 * abs(C[0]), (vi_first, vi_second)
    assert rk_second > rk_first and abs(C_rk[-1] - C_rk[0]) >= 5 * vi_second, (rk_first,
                                                                                rk_second)


@pytest.mark.parametrize("problem,controls", [
    (rigid_body(Omega0=(0.3, -0.2, 0.5)), [0.2, -0.1, 0.3]),
    (heavy_top(Omega0=TOP_OMEGA0), [0.05, -0.02])])
def test_controlled_flow_converges_to_rk4_at_second_order(problem: og.Problem,
                                                          controls: list[float]) -> None:
    """Same dynamics, driven: the gap to RK4 (accurate to O(h^4)) falls as h^2."""
    gaps = []
    for h in (0.02, 0.01):
        n = int(round(1.0 / h))
        U = np.outer(1 + np.linspace(0, 1, n + 1), controls)  # ramped torques
        sim = og.simulate(problem, h=h, steps=n, controls=U)
        gaps.append(np.max(np.abs(sim.velocities[-1] - sim.rk4.velocities[-1])))
    assert 3.6 <= gaps[0] / gaps[1] <= 4.4, gaps


def test_first_order_problem_is_refused() -> None:
    with pytest.raises(ConfigError, match="first-order problem.*second-order problem"):
        og.simulate(plate_ball(), h=0.01, steps=10)


@pytest.mark.parametrize("h", [0.0, -0.1, float("nan"), float("inf")])
def test_non_positive_step_is_refused(h: float) -> None:
    with pytest.raises(ConfigError, match="step h must be a finite number > 0"):
        og.simulate(rigid_body(), h=h, steps=10)


@pytest.mark.parametrize("steps", [0, -3, 2.5])
def test_fewer_than_one_step_is_refused(steps) -> None:
    with pytest.raises(ConfigError, match="steps must be an integer >= 1"):
        og.simulate(rigid_body(), h=0.1, steps=steps)


def test_bad_controls_and_free_initial_values_are_named() -> None:
    with pytest.raises(DimensionError, match="steps \\+ 1 = 11 rows of 3"):
        og.simulate(rigid_body(), h=0.1, steps=10, controls=np.zeros((10, 3)))
    with pytest.raises(ConfigError, match="initial.Omega is free.*initial=\\{'Omega'"):
        og.simulate(rigid_body(), h=0.1, steps=10, initial={"Omega": None})


def test_failed_newton_solve_says_decrease_h() -> None:
    with pytest.raises(SolverError, match="Newton did not solve.*at node \\d+.*decrease h"):
        og.simulate(heavy_top(Omega0=TOP_OMEGA0), h=5.0, steps=40)
