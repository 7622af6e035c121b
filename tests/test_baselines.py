"""The baselines (RK4 multiple shooting on quaternions, matrices, Euler angles): built from the
same Problem, solved and diagnosed like our schemes, fourth order, and failing where their
coordinates do (issue 16)."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.errors import ConfigError
from ocgroupoid.lie import so3
from ocgroupoid.nlp.schemes import BASELINES, SCHEMES
from ocgroupoid.nlp.schemes.coordinates import coordinates, quaternion_of_matrix
from ocgroupoid.systems.rigid_body import rigid_body

ROOT = Path(__file__).resolve().parents[1]
SO3 = ROOT / "problems" / "so3_rest_to_rest.yaml"


def solve_file(path: Path, *sets: str) -> og.Solution:
    cfg = files.load(path, list(sets))
    d = cfg.file.discretization
    return og.solve(files.build(cfg), cfg.file.horizon.N, d.retraction, d.rule,
                    cfg.file.solver.ipopt, d.scheme, d.steps, multistart=False)


@pytest.mark.parametrize("scheme", BASELINES)
def test_every_baseline_solves_the_so3_slew_and_lands(scheme: str) -> None:
    sol = solve_file(SO3, f"discretization.scheme={scheme}", "horizon.N=64")
    assert sol.success, sol.hint  # at N = 32 the matrices drift off SO(3) by 1.4e-6
    assert sol.discretization["scheme"] == scheme
    errors = sol.diagnostics["replay"]["terminal_error"]
    assert max(errors.values()) < 1e-6  # fourth order at N = 64: ~1e-8
    assert "euler_lagrange_residual_max" not in sol.diagnostics  # not variational
    reference = solve_file(SO3, "discretization.scheme=order4", "horizon.N=64").cost
    assert abs(sol.cost - reference) < 1e-3 * reference


def test_the_quaternion_baseline_is_fourth_order_and_drifts_off_the_group() -> None:
    """Replay errors fall by ~16 per halving of h; |q| - 1 is never enforced."""
    errs, drift = [], []
    for N in (8, 16, 32):
        sol = og.compile_problem(rigid_body(), N=N, scheme="rk4_quat").solve(multistart=False)
        errs.append(sol.diagnostics["replay"]["terminal_error"]["R"])
        drift.append(sol.diagnostics["manifold_distance"]["R"])
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(orders > 3.5), (errs, orders)
    assert drift[0] > 1e-9 and drift[-1] < drift[0]


def test_the_matrix_baseline_reports_its_own_drift_off_so3() -> None:
    """The read-out (a quaternion of R) is on SO(3) whatever R is; the verdict measures
    |R^T R - I| on the baseline's own variables."""
    sol = solve_file(SO3, "discretization.scheme=rk4_matrix", "horizon.N=16")
    assert sol.status == "Solve_Succeeded" and not sol.success
    assert "rotation matrices are off SO(3) by" in sol.hint
    assert sol.diagnostics["manifold_distance"]["R"] < 1e-12  # invisible in the read-out


def test_euler_angles_fail_through_gimbal_lock_where_ours_do_not() -> None:
    """A slew of 2 rad about body y passes a pitch of 90 degrees: the Euler baseline fails
    (or misses by orders of magnitude more) and says why; order2 and order4 with Cayley,
    and the quaternion baseline, solve it."""
    RT = so3.from_rotvec(np.array([0.0, 2.0, 0.0]))
    sols = {s: og.compile_problem(rigid_body(RT=RT), N=16, scheme=s).solve(multistart=False)
            for s in ("order2", "order4", "rk4_quat", "rk4_euler")}
    for s in ("order2", "order4", "rk4_quat"):
        assert sols[s].success, (s, sols[s].hint)
    euler = sols["rk4_euler"]
    assert not euler.success
    assert "gimbal lock" in euler.hint and "rk4_quat, order2 or order4" in euler.hint
    miss = euler.diagnostics.get("replay", {}).get("terminal_error", {}).get("R", np.inf)
    ours = {s: sols[s].diagnostics["replay"]["terminal_error"]["R"] for s in sols}
    assert miss > 1e4 * max(ours["order4"], ours["rk4_quat"])  # the same order, measured 1e6
    assert miss > 10 * ours["order2"]  # even the second-order scheme, measured 40x


def test_baselines_are_listed_as_baselines() -> None:
    for name in BASELINES:
        for cls in SCHEMES[name].values():
            assert cls.summary.startswith("baseline (to measure against)")
            assert not cls.variational and cls.accuracy == 4


def test_a_problem_without_continuous_dynamics_has_no_baseline() -> None:
    pb = og.Problem(og.LieGroupFactor(og.SO3, "R", "Omega"), name="kinematic")
    pb.minimize(ca.sumsqr(pb.y) + ca.sumsqr(pb.dy))
    pb.horizon(1.0)
    pb.initial(R=np.eye(3), Omega=[0, 0, 0])
    pb.final(R=so3.from_rotvec(np.array([0.3, 0.0, 0.0])), Omega=[0, 0, 0])
    with pytest.raises(ConfigError, match="rk4_quat integrates the continuous dynamics"):
        og.compile_problem(pb, N=8, scheme="rk4_quat")


# ------------------------------------------------------------------ coordinates


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3))
def test_coordinates_round_trip_on_so3(v: list[float]) -> None:
    """stored(of_stored(q)) is q up to sign, for matrices and for Euler angles (away from
    the gimbal-lock pitch); Shepperd's graph agrees with the numeric conversion."""
    q = og.SO3.exp(np.array(v))
    q = np.array(q, dtype=float).ravel()
    factor = og.LieGroupFactor(og.SO3, "R", "Omega")
    for name in ("matrix", "euler"):
        c = coordinates(name, factor)
        z = np.array(ca.DM(c.of_stored(ca.DM(q)))).ravel()
        if name == "euler" and abs(abs(z[1]) - np.pi / 2) < 1e-3:
            continue
        back = np.array(ca.DM(c.stored(ca.DM(z)))).ravel()
        assert min(np.linalg.norm(back - q), np.linalg.norm(back + q)) < 1e-9
    R = og.SO3.matrix(q)
    mine = np.array(ca.DM(quaternion_of_matrix(ca.DM(R)))).ravel()
    assert np.allclose(mine, og.SO3.of_matrix(R), atol=1e-12)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-1.2, 1.2), min_size=3, max_size=3),
       st.lists(st.floats(-2.0, 2.0), min_size=3, max_size=3),
       st.sampled_from(["right", "left"]))
def test_coordinate_rates_agree_with_the_group(v: list[float], w: list[float],
                                               side: str) -> None:
    """d/dt of each coordinate, mapped back, is the stored form's rate (finite differences
    of stored(z + dt z') against state_rate)."""
    factor = og.LieGroupFactor(og.SO3, "R", "Omega", side=side)
    q = np.array(og.SO3.exp(np.array(v)), dtype=float).ravel()
    y = np.array(w)
    qs, ys = ca.SX.sym("q", 4), ca.SX.sym("y", 3)
    want = np.array(ca.Function("rate", [qs, ys], [factor.state_rate(qs, ys)])(q, y)).ravel()
    for name in ("matrix", "euler"):
        c = coordinates(name, factor)
        zs = ca.SX.sym("z", c.size)
        F = ca.Function("F", [qs, zs, ys], [c.of_stored(qs), c.rate(zs, ys), c.stored(zs)])
        z = np.array(F(q, np.zeros(c.size), y)[0]).ravel()
        zdot = np.array(F(q, z, y)[1]).ravel()
        dt = 1e-6
        plus = np.array(F(q, z + dt * zdot, y)[2]).ravel()
        minus = np.array(F(q, z - dt * zdot, y)[2]).ravel()
        sign = np.sign(plus @ q)
        assert np.allclose(sign * (plus - minus) / (2 * dt), want, atol=1e-6), name
