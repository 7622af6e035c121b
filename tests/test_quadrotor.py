"""The quadrotor (issue 28): controls of their own through a configuration-dependent force
(thrust along body z), gravity read off the pose, underactuation — checked against an
independent solver (plain CasADi Opti, quaternion Newton-Euler, Gauss-Legendre collocation,
tests/quadrotor_reference.py), for convergence at the scheme's order, robustness over N, the
replay of the true vehicle and every message of the model language (the exported C solver
of problems/quadrotor.yaml is compared with Python to 1e-8 in tests/test_codegen.py).
"""

from __future__ import annotations

import re
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import PPoly
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid.cli import app
from ocgroupoid.errors import ConfigError
from ocgroupoid.systems.quadrotor import quadrotor

from . import quadrotor_reference as ref

ROOT = Path(__file__).resolve().parent.parent
#: CasADi's names for the elements of a Problem's own symbols: never in a message
INTERNAL = re.compile(r"\b(s|q|y|dy)_\d+\b")


def extrapolated(coarse: float, fine: float, order: float) -> float:
    return (2**order * fine - coarse) / (2**order - 1)


def reference_instance(sol: og.Solution, N: int, minimum_time: bool) -> dict:
    """The independent solver on N intervals, started from our solution ``sol``."""
    X, U, T = ref.guess_from(sol, N)
    inst = ref.Instance(1.0, np.array([0.05, 0.05, 0.09]), 9.81, 20.0, 0.5, X[N, :4].copy(),
                        np.array([2.0, 1.0, 1.0]), None if minimum_time else 4.0,
                        effort=0.001 if minimum_time else 1.0)
    return ref.solve(inst, N, X, U, T)


@pytest.fixture(scope="module")
def fixed_T() -> dict[int, og.Solution]:
    pb = quadrotor()
    return {N: og.solve(pb, N=N, scheme="order4") for N in (16, 32, 64, 128)}


def test_an_independent_solver_agrees_on_the_optimal_cost(fixed_T) -> None:
    """Both extrapolated (ours at order 4 from N = 64, 128; the reference at order 6 from
    N = 16, 32), from the same minimum: agreement to 1e-6 relative (measured: 1e-9)."""
    ours = extrapolated(fixed_T[64].cost, fixed_T[128].cost, 4)
    theirs = [reference_instance(fixed_T[128], N, False) for N in (16, 32)]
    assert all(r["status"] == "Solve_Succeeded" for r in theirs)
    J_ref = extrapolated(theirs[0]["cost"], theirs[1]["cost"], 6)
    assert abs(ours - J_ref) <= 1e-6 * abs(J_ref), (ours, J_ref)


def test_order4_converges_at_fourth_order_in_cost_and_replay(fixed_T) -> None:
    Ns = sorted(fixed_T)
    J_star = extrapolated(fixed_T[64].cost, fixed_T[128].cost, 4)
    cost = [abs(fixed_T[N].cost - J_star) for N in Ns[:-1]]
    replay = [fixed_T[N].diagnostics["replay"]["max_terminal_error"] for N in Ns]
    cost_orders = np.log2(np.array(cost[:-1]) / np.array(cost[1:]))
    replay_orders = np.log2(np.array(replay[:-1]) / np.array(replay[1:]))
    assert np.all(cost_orders >= 3.5), cost_orders
    assert np.all(replay_orders >= 3.5), replay_orders
    assert all(s.success for s in fixed_T.values())


@pytest.mark.parametrize("scheme", ["order2", "order4"])
def test_both_schemes_solve_from_16_to_256_intervals(scheme: str) -> None:
    """Every N solves (IPOPT's Solve_Succeeded, every residual check passed); order4 is
    verified at every N, order2 once its plan lands within 1% of the distance covered (its
    second-order replay error is 4% at N = 16), and says which N to take before."""
    pb = quadrotor()
    for N in (16, 32, 64, 128, 256):
        sol = og.solve(pb, N=N, scheme=scheme)
        assert sol.status == "Solve_Succeeded", (N, sol.hint)
        if scheme == "order4" or N >= 64:
            assert sol.success, (N, sol.hint)
        else:
            failures = sol.diagnostics["verdict"]["failures"]
            assert failures and all(f.startswith("the plan does not land") for f in failures)
            assert "increase N to" in sol.hint


@pytest.mark.parametrize("scheme", ["order2", "order4"])
def test_multistart_on_the_coarsest_grid(scheme: str) -> None:
    sol = og.solve(quadrotor(), N=64 if scheme == "order2" else 16, scheme=scheme,
                   multistart=True)
    assert sol.success, sol.hint
    assert len(sol.minima) >= 2  # the geodesic and the long way round at least


def test_multistart_finds_the_out_of_plane_minimum() -> None:
    """Pitching is expensive (J2 = 10 J1): the geodesic start pitches the whole way and ends
    at a costly point; the yaw excursions lead to the minimum that turns the heading and rolls
    instead, 60 times cheaper."""
    pb = quadrotor(J=(0.02, 0.2, 0.02), T=2.0,
                   gT={"rotation": "identity", "position": [3.0, 0.0, 0.0]})
    single = og.solve(pb, N=32, scheme="order4")
    multi = og.solve(pb, N=32, scheme="order4", multistart=True)
    assert multi.success, multi.hint
    assert multi.cost < single.cost / 10, (single.cost, multi.cost)
    R = multi.states["g"][:, :3, :3]
    yaw = np.degrees(np.abs(np.arctan2(R[:, 1, 0], R[:, 0, 0])))
    assert yaw.max() > 45  # out of the plane of the motion
    omega = multi.velocities["xi"][:, :3]
    assert np.abs(omega[:, 0]).max() > 2 * np.abs(omega[:, 1]).max()  # it rolls, not pitches


def test_the_minimum_time_file_solves_with_default_options(tmp_path) -> None:
    out = tmp_path / "sol.json"
    r = CliRunner().invoke(app, ["solve", str(ROOT / "problems" / "quadrotor_min_time.yaml"),
                                 "--out", str(out), "-q"])
    assert r.exit_code == 0, r.output
    sol = og.Solution.from_json(out)
    assert sol.success and sol.status == "Solve_Succeeded"
    assert 1.0 < sol.T < 1.5
    assert {"f", "tau[0]"} <= set(sol.diagnostics["bounds_active"])


def test_the_minimum_time_cost_agrees_with_the_independent_solver() -> None:
    """Bang-bang thrust and torques switch inside intervals: both methods converge at about
    second order, so the comparison is at the error both estimate (Richardson at order 2 from
    N = 64, 128 for ours), and from the same minimum."""
    pb = quadrotor()
    pb.horizon(4.0, free=True, T_min=0.5, T_max=10.0)
    pb.objective(effort=0.001, time=1.0)
    sols = {N: og.solve(pb, N=N, scheme="order4", multistart=N == 64) for N in (64,)}
    sols[128] = og.solve(pb, N=128, scheme="order4", guess=sols[64])
    ours = extrapolated(sols[64].cost, sols[128].cost, 2)
    spread = abs(sols[128].cost - sols[64].cost) / 3
    theirs = reference_instance(sols[128], 64, True)
    assert theirs["status"] == "Solve_Succeeded"
    assert abs(ours - theirs["cost"]) <= 2 * spread + 1e-6, (ours, theirs["cost"], spread)


def test_controls_of_their_own_are_linear_and_bounded_on_the_whole_interval() -> None:
    """order4's controls of their own are linear on each interval, their variables its end
    values: the control a solution reports is one line per interval, within its bounds at
    every instant (not only at the bound points), and the bound at either end of an interval
    is a row on one variable, the form fatrop's Riccati recursion takes without regularising
    (on the motion's estimate there it crawled: tests/test_fatrop.py)."""
    from ocgroupoid import files
    cfg = files.load(ROOT / "problems" / "quadrotor_min_time.yaml",
                     ["horizon.N=16", "solver.multistart=false"])
    solver = og.compile_problem(files.build(cfg), N=16, scheme="order4")
    sol = solver.solve(multistart=False)
    assert sol.success, sol.hint
    u = PPoly(np.asarray(sol.control_ppoly["c"]), np.asarray(sol.control_ppoly["x"]))
    a, b = u.x[:-1], u.x[1:]  # every interval: the control at 1/4, 1/2, 3/4 on its chord
    for w in (0.25, 0.5, 0.75):
        chord = (1 - w) * u(a + 1e-12) + w * u(b - 1e-12)
        assert np.abs(u((1 - w) * a + w * b) - chord).max() <= 1e-9
    t = np.linspace(0.0, sol.T, 20001)
    f, tau = u(t)[:, 0], u(t)[:, 1:]
    assert f.min() >= -1e-9 and f.max() <= 20.0 + 1e-9
    assert np.abs(tau).max() <= 0.5 + 1e-9
    assert np.isclose(np.abs(tau), 0.5, atol=1e-6).mean() > 0.5  # bang-bang torques: the
    # bounds are met (on 63-88 % of the flight per torque), not idle
    tr = solver.transcription
    block = next(b for b in tr.blocks if b.name == "interval_bounds")
    z = ca.SX.sym("z", block.fun.size1_in(0))
    J = ca.jacobian(block.fun(z)[1], z[:block.n_var])
    ends = [i for i, name in enumerate(block.rows) if name.endswith(("(start)", "(end)"))]
    assert len(ends) == len(block.rows) == 2 * 4  # f and three torques at both ends, only
    assert all(J[i, :].nnz() == 1 for i in ends)


@pytest.mark.parametrize("extra, points", [(None, 2), ("f squared", 4), ("spin", 4)])
def test_bounds_on_the_controls_line_hold_at_its_ends_only(extra: str | None,
                                                           points: int) -> None:
    """Bounds affine in the controls of their own alone are lines on an interval, within
    their bounds on the whole interval once within them at its ends: order4 holds them
    there only (the Gauss-point rows would be implied). A bound that is not affine in the
    controls (f^2), or one on the motion (a body rate), keeps the four bound points."""
    pb = quadrotor()
    if extra == "f squared":
        pb.bound(pb.U[0] ** 2, None, 400.0, name="f squared")
    elif extra == "spin":
        pb.bound(pb.y[2], -10.0, 10.0, name="spin")
    tr = og.compile_problem(pb, N=8, scheme="order4").transcription
    assert tr.scheme.bound_times.size == points
    block = next(b for b in tr.blocks if b.name == "interval_bounds")
    assert len(block.rows) == points * len(tr.scheme.stages.inequality_names)


def test_the_replay_drives_the_true_vehicle() -> None:
    """The replay integrates thrust along body z and gravity: an independent integration of
    quaternion Newton-Euler with the solution's own control polynomial lands where it says."""
    sol = og.solve(quadrotor(), N=32, scheme="order4")
    u = PPoly(np.asarray(sol.control_ppoly["c"]), np.asarray(sol.control_ppoly["x"]))
    inst = ref.Instance(1.0, np.array([0.05, 0.05, 0.09]), 9.81, 20.0, 0.5, np.zeros(4),
                        np.zeros(3), 4.0)
    f = ref.rhs(inst)
    z = solve_ivp(lambda t, x: np.array(f(x, u(t))).ravel(), (0, sol.T),
                  np.concatenate([[1, 0, 0, 0], np.zeros(9)]), method="DOP853",
                  rtol=1e-12, atol=1e-12).y[:, -1]
    goal = sol.states["g"][-1]
    assert np.linalg.norm(z[4:7] - goal[:3, 3]) <= 2 * sol.diagnostics["replay"][
        "terminal_error"]["g"] + 1e-9
    assert np.linalg.norm(z[4:7] - [2.0, 1.0, 1.0]) <= 1e-3


def test_the_custom_problem_file_says_the_same() -> None:
    """The quadrotor written in a custom problem file (controls with their sizes, a force,
    the pose in the Lagrangian) solves to the built-in model's cost."""
    from ocgroupoid import files
    custom = files.load(ROOT / "tests" / "data" / "custom_quadrotor.yaml",
                        ["horizon.N=16", "solver.multistart=false"])
    built = files.load(ROOT / "problems" / "quadrotor.yaml",
                       ["horizon.N=16", "solver.multistart=false"])
    a = og.solve(files.build(custom), N=16, scheme="order4")
    b = og.solve(files.build(built), N=16, scheme="order4")
    assert a.success and b.success
    assert a.cost == pytest.approx(b.cost, rel=1e-10)
    assert a.control_names == b.control_names == ["f", "tau1", "tau2", "tau3"]


# ------------------------------------------------------------------ messages


def messages(pb_factory, action) -> str:
    with pytest.raises(ConfigError) as err:
        action(pb_factory())
    text = str(err.value)
    assert not INTERNAL.search(text), text
    return text


def se3_problem() -> og.Problem:
    return og.Problem(og.LieGroupFactor(og.SE3, state="g", velocity="xi"), name="q")


def test_messages_name_the_users_symbols() -> None:
    other = se3_problem()
    text = messages(se3_problem, lambda pb: pb.minimize(ca.sumsqr(other.velocity("xi"))))
    assert "symbols of another Problem" in text
    text = messages(se3_problem, lambda pb: pb.minimize(ca.sumsqr(other.node_state("g"))))
    assert "symbols of another Problem" in text
    text = messages(se3_problem, lambda pb: pb.minimize(ca.SX.sym("thrust") ** 2))
    assert "'thrust', declared outside this problem" in text

    def rate_in_terminal(pb: og.Problem) -> None:
        pb.terminal_cost(ca.sumsqr(pb.acceleration("xi")))
    text = messages(se3_problem, rate_in_terminal)
    assert "may not depend on the rate of xi (xi_dot)" in text

    def lagrangian_with_control(pb: og.Problem) -> None:
        f = pb.control("f")
        pb.mechanics(f * ca.sumsqr(pb.velocity("xi")), force=ca.vertcat(0, 0, 0, 0, 0, f))
    text = messages(se3_problem, lagrangian_with_control)
    assert "the Lagrangian may not depend on the control f" in text


def test_controls_are_checked_where_they_are_declared() -> None:
    def unused(pb: og.Problem) -> None:
        f = pb.control("f")
        pb.control("tau", 3)
        pb.mechanics(ca.sumsqr(pb.velocity("xi")), force=ca.vertcat(0, 0, 0, 0, 0, f))
    assert "does not depend on the controls ['tau']" in messages(se3_problem, unused)

    def dependent(pb: og.Problem) -> None:
        a, b = pb.control("a"), pb.control("b")
        pb.mechanics(ca.sumsqr(pb.velocity("xi")), force=ca.vertcat(0, 0, 0, 0, 0, a + b))
    assert "not independent" in messages(se3_problem, dependent)

    def no_force(pb: og.Problem) -> None:
        pb.control("f")
        pb.mechanics(ca.sumsqr(pb.velocity("xi")), actuated="xi")
    assert "pass the generalised force" in messages(se3_problem, no_force)

    def both(pb: og.Problem) -> None:
        f = pb.control("f")
        pb.mechanics(ca.sumsqr(pb.velocity("xi")), input_matrix=ca.DM.eye(6),
                     force=ca.vertcat(0, 0, 0, 0, 0, f))
    assert "not both" in messages(se3_problem, both)

    def wrong_size(pb: og.Problem) -> None:
        f = pb.control("f")
        pb.mechanics(ca.sumsqr(pb.velocity("xi")), force=ca.vertcat(0, 0, f))
    with pytest.raises(og.DimensionError, match="one generalised force per actuated"):
        wrong_size(se3_problem())

    def first_order(_: og.Problem) -> None:
        og.Problem(og.LieGroupFactor(og.SE2, state="g", velocity="xi"), order=1).control("u")
    assert "velocities are the controls" in messages(se3_problem, first_order)

    def taken(pb: og.Problem) -> None:
        pb.control("xi")
    assert "already a parameter, state, velocity or control" in messages(se3_problem, taken)


def test_a_non_smooth_cost_gets_the_smooth_form() -> None:
    """A thrust magnitude written as a norm: its derivative at zero force is NaN."""
    G = og.Groupoid(og.LieGroupFactor(og.SO3, state="R", velocity="Omega"),
                    og.Pair(3, state="p", velocity="v"))
    pb = og.Problem(G, name="norm_at_rest")
    u = pb.mechanics(0.5 * ca.sumsqr(pb.velocity("Omega")) + 0.5 * ca.sumsqr(pb.velocity("v")),
                     actuated=["Omega", "v"])
    pb.minimize((ca.norm_2(u[3:]) - 1) ** 2 + ca.sumsqr(u[:3]))
    pb.initial(R=np.eye(3), Omega=[0, 0, 0], p=[0, 0, 0], v=[0, 0, 0])
    pb.final(R=np.eye(3), Omega=[0, 0, 0], p=[1, 0, 0], v=[0, 0, 0])
    pb.horizon(2.0)
    sol = og.solve(pb, N=16)
    assert not sol.success and sol.status == "Invalid_Number_Detected"
    assert "the cost takes a square root or norm" in sol.hint
    assert "sqrt(sumsqr(F) + eps**2)" in sol.hint


# ------------------------------------------------------------------ guesses and continuation


def test_a_solution_is_a_guess_on_another_grid_and_scheme() -> None:
    pb = quadrotor()
    coarse = og.solve(pb, N=16, scheme="order2")
    cold = og.solve(pb, N=32, scheme="order4")
    warm = og.solve(pb, N=32, scheme="order4", guess=coarse)
    assert warm.success and warm.cost == pytest.approx(cold.cost, rel=1e-9)
    assert warm.discretization["start"].startswith("interpolated from a solution")
    same = og.solve(pb, N=32, scheme="order4", guess=warm)  # the same NLP: its own point
    assert same.success and same.iterations < cold.iterations
    assert same.cost == pytest.approx(cold.cost, rel=1e-9)
    with pytest.raises(ConfigError, match="shaped"):  # not velocities of this problem
        og.solve(pb, N=16, guess=np.zeros((3, 5)))


def test_velocities_of_another_grid_are_resampled() -> None:
    """A Guess (or an array) of interval velocities made for the final grid starts the
    coarse grid of a continuation too, resampled onto it: the same minimum as the velocities
    given on the final grid alone; a wrong dim y is still an error."""
    from ocgroupoid.solve.guesses import resampled

    pb = quadrotor()
    solver = og.compile_problem(pb, N=32, scheme="order4")
    first = solver.guesses(solver.transcription, solver.transcription.pack(), False)[0]
    alone = solver.solve(guess=first, multistart=False)
    through = solver.solve(guess=first, multistart=False, continuation=[8])
    assert alone.success and through.success
    assert through.cost == pytest.approx(alone.cost, rel=1e-9)
    coarse = og.solve(pb, N=8, scheme="order4", guess=first)
    assert coarse.success and coarse.discretization["start"].endswith("(from N=32)")
    line = np.linspace(0.0, 1.0, 4)[:, None] * np.ones((1, 6))
    assert np.allclose(resampled(line, 8, 6)[:, 0], np.interp(
        (np.arange(8) + 0.5) / 8, (np.arange(4) + 0.5) / 4, line[:, 0]))
    assert resampled(line, 8, 5) is None and resampled(np.full((4, 6), np.nan), 8, 6) is None
    with pytest.raises(ConfigError, match=r"or \(M, 6\) on another grid"):
        og.solve(pb, N=8, guess=og.Guess("flat", np.zeros(6)))


def test_continuation_reports_a_grid_that_lands_above_the_coarse_minimum(monkeypatch) -> None:
    """The first interpolation onto the fine grid is spoiled (the long way round): the fine
    grid lands above the minimum the coarse grid found; the solver bridges through the
    doublings, keeps the better solution and says so."""
    from ocgroupoid.solve import compiled as solver_module, multipliers
    from ocgroupoid.systems.rigid_body import rigid_body

    real = solver_module.interpolate
    calls = {"n": 0}

    def spoiled(coarse, x, p, N):  # type: ignore[no-untyped-def]
        calls["n"] += 1
        g = real(coarse, x, p, N)
        if calls["n"] == 1:
            g.xi = -g.xi * 1.5  # the other way round
        return g

    monkeypatch.setattr(solver_module, "interpolate", spoiled)  # the bridge's
    monkeypatch.setattr(multipliers, "interpolate", spoiled)  # the next grid's start
    pb = rigid_body()
    sol = og.compile_problem(pb, N=64).solve(continuation=[16])
    notes = sol.diagnostics.get("continuation", [])
    assert notes and "landed at cost" in notes[0] and "kept" in notes[0], notes
    direct = og.solve(pb, N=64)
    assert sol.cost == pytest.approx(direct.cost, rel=1e-9)
    assert "continuation: N=64 interpolated from N=16" in sol.hint
