"""The fourth-order scheme (issue 13): orders measured on refinements of every problem file,
discrete Euler-Lagrange residuals with IPOPT's multipliers, states on the group, the exact
cubic, and the control polynomial replayed by SciPy the way a user would."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console
from scipy.integrate import solve_ivp
from scipy.interpolate import PPoly
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.cli import app
from ocgroupoid.cli.summary import summary
from ocgroupoid.errors import ConfigError
from ocgroupoid.solve import interpolate
from ocgroupoid.systems.heavy_top import heavy_top
from ocgroupoid.systems.rigid_body import INERTIA, TARGET, rigid_body

from .test_api_general import cubic, minimum_acceleration

ROOT = Path(__file__).resolve().parent.parent
MIN_ORDER = 3.5


def orders(values: list[float]) -> np.ndarray:
    """Observed orders log2(e_N / e_2N) on grids that double."""
    v = np.abs(np.asarray(values, dtype=float))
    return np.log2(v[:-1] / v[1:])


def cost_orders(costs: list[float]) -> np.ndarray:
    """Orders of the cost from successive differences (no reference value needed)."""
    return orders(list(np.diff(costs)))


def replay_error(sol: og.Solution, key: str) -> float:
    rep = sol.diagnostics["replay"]
    assert rep["available"], rep
    return rep["terminal_error"][key]


def assert_clean(sol: og.Solution, manifold_tol: float = 1e-12) -> None:
    d = sol.diagnostics
    assert sol.success, (sol.N, sol.status)
    assert d["euler_lagrange_residual_max"] <= 1e-8, (sol.N, d["euler_lagrange_residual_max"])
    assert max(d["manifold_distance"].values()) <= manifold_tol, d["manifold_distance"]


# ------------------------------------------------------------------ so3_rest_to_rest

SO3_NS = [8, 16, 32, 64]


@pytest.fixture(scope="module")
def so3() -> dict[int, og.Solution]:
    return {N: og.solve(rigid_body(), N=N, scheme="order4") for N in SO3_NS}


def test_so3_converges_at_fourth_order(so3) -> None:
    for sol in so3.values():
        assert_clean(sol)
        assert sol.discretization["scheme"] == "order4" and sol.iterations <= 10
    costs = [so3[N].cost for N in SO3_NS]
    same_minimum(costs)
    assert np.all(cost_orders(costs) >= MIN_ORDER), (costs, cost_orders(costs))
    errors = [replay_error(so3[N], "R") for N in SO3_NS]
    assert np.all(orders(errors) >= MIN_ORDER), (errors, orders(errors))


def replay_slew(sol: og.Solution, tol: float) -> tuple[float, np.ndarray, float]:
    """As a user replays a rest-to-rest slew: PPoly of the JSON's controls.ppoly, Euler's
    equations and the quaternion kinematics in NumPy, DOP853 at ``tol``. Returns the angle
    of the final attitude from the target, the coefficients' shape and the final rate."""
    data = json.loads(sol.to_json())
    ppoly = data["controls"]["ppoly"]
    u = PPoly(np.array(ppoly["c"]), np.array(ppoly["x"]))
    I = np.array(INERTIA)

    def rhs(t: float, z: np.ndarray) -> np.ndarray:
        q, w = z[:4], z[4:]
        dq = 0.5 * np.concatenate([[-q[1:] @ w], q[0] * w + np.cross(q[1:], w)])
        dw = u(t) - np.cross(w, I * w) / I  # I dw/dt + w x I w = I u
        return np.concatenate([dq, dw])

    z = solve_ivp(rhs, (0.0, data["T"]), np.array([1.0, 0, 0, 0, 0, 0, 0]), method="DOP853",
                  rtol=tol, atol=tol).y[:, -1]
    R = og.SO3.matrix(z[:4] / np.linalg.norm(z[:4]))
    angle = float(np.linalg.norm(og.SO3.log(og.SO3.of_matrix(TARGET.T @ R))))
    return angle, np.array(ppoly["c"]).shape, float(np.linalg.norm(z[4:]))


def test_control_polynomial_replayed_by_scipy_lands_on_target(so3) -> None:
    """N = 64 lands within 1e-6 rad of the target, at rest (order2 at N = 256 misses by
    ~4e-5)."""
    angle, shape, rate = replay_slew(so3[64], 1e-12)
    assert shape == (4, 64, 3)  # cubic on each of the N intervals
    assert angle <= 1e-6 and rate <= 1e-6


def test_controls_are_the_polynomial_at_their_samples(so3) -> None:
    sol = so3[16]
    np.testing.assert_allclose(sol.control(sol.controls_t[:-1]), sol.controls[:-1], rtol=0,
                               atol=1e-12)  # each sample from the piece that starts there


def test_order4_steps_with_exp_whatever_the_retraction() -> None:
    """The quadratic scheme's increments are exponential coordinates (tau(tau^-1(exp W)) =
    exp W): the answer does not depend on the retraction asked for."""
    costs = [og.solve(rigid_body(), N=12, scheme="order4", retraction=r).cost
             for r in ("cayley", "exp", "first_order")]
    assert max(costs) - min(costs) <= 1e-12


def test_multipliers_sit_at_the_gauss_points_and_enter_the_residual(so3) -> None:
    sol = og.solve(heavy_top(), N=16, scheme="order4", multistart=True)
    t = np.asarray(sol.multipliers["t"])
    h = sol.T / 16
    assert t.size == 32 and np.allclose(t[:2] / h, [0.5 - np.sqrt(3) / 6, 0.5 + np.sqrt(3) / 6])
    assert np.asarray(sol.multipliers["Phi"]).shape == (32, 3)
    assert sol.diagnostics["euler_lagrange_residual_max"] <= 1e-8


# ------------------------------------------------------------------ heavy_top_rotors

HT_NS = [32, 64, 128, 256]


def same_minimum(costs: list[float]) -> None:
    """A refinement measures one minimum: its costs agree far closer than two minima do (the
    local minima of these problems lie at least 15% apart: 22.8 / 27.9 for the heavy top,
    3.27 / 3.93 for the plate-ball)."""
    assert max(costs) - min(costs) <= 0.05 * min(costs), costs


@pytest.fixture(scope="module")
def top() -> dict[int, og.Solution]:
    """Multi-start at N = 32, then each grid started from the previous solution."""
    pb = heavy_top()
    solver = og.compile_problem(pb, N=HT_NS[0], scheme="order4")
    out = {HT_NS[0]: solver.solve(multistart=True)}
    for N in HT_NS[1:]:
        prev = out[N // 2]
        guess = interpolate(solver.transcription, prev.x, prev.p, N)
        solver = og.compile_problem(pb, N=N, scheme="order4")
        out[N] = solver.solve(guess=guess)
    return out


def test_heavy_top_converges_at_fourth_order(top) -> None:
    for sol in top.values():
        assert_clean(sol, manifold_tol=1e-12)
    costs = [top[N].cost for N in HT_NS]
    same_minimum(costs)
    assert top[HT_NS[0]].cost < 23.0  # the best minimum known (the natural guess gives ~27.9)
    assert np.all(cost_orders(costs) >= MIN_ORDER), (costs, cost_orders(costs))
    for key in ("Gamma", "Omega", "dtheta"):
        errors = [replay_error(top[N], key) for N in HT_NS]
        assert np.all(orders(errors) >= MIN_ORDER), (key, errors, orders(errors))
    drift = [top[N].diagnostics["conserved_drift"]["Pi.Gamma"] for N in HT_NS]
    assert np.all(orders(drift) >= MIN_ORDER), drift  # the Casimir at the nodes


def test_heavy_top_continues_from_an_order2_solution(top) -> None:
    """An order2 solution, interpolated, starts order4 on a finer grid: same minimum."""
    coarse = og.compile_problem(heavy_top(), N=32)
    sol2 = coarse.solve(multistart=True)
    guess = interpolate(coarse.transcription, sol2.x, sol2.p, 64)
    sol4 = og.compile_problem(heavy_top(), N=64, scheme="order4").solve(guess=guess)
    assert sol4.success and sol4.cost == pytest.approx(top[64].cost, rel=1e-9)


def test_order4_from_the_long_way_round_continues_through_order2() -> None:
    """From the great circle the long way round, order4 on N=64 alone fails (IPOPT: 39 s,
    cost 2206); ``continuation=["order2"]`` solves order2 on the same grid first and order4
    from it: verified, in the minimum the natural guess finds (0.3 s), and without a
    Richardson estimate from a grid of another scheme."""
    solver = og.compile_problem(heavy_top(), N=64, scheme="order4")
    tr = solver.transcription
    p = tr.pack()
    natural = solver.solve(multistart=False)
    far = next(g for g in solver.guesses(tr, p, True) if g.label == "great circle, long way")
    sol = solver.solve(guess=far, continuation=["order2"])
    assert sol.success and sol.discretization["scheme"] == "order4"
    assert sol.cost == pytest.approx(natural.cost, rel=1e-9)
    assert "error_estimate" not in sol.diagnostics
    assert sol.diagnostics["minima_grid"] == {"N": 64, "scheme": "order2"}
    assert "minima_grid" not in natural.diagnostics
    coarse_too = solver.solve(multistart=False, continuation=[32, "order2"])
    assert coarse_too.success and coarse_too.cost == pytest.approx(natural.cost, rel=1e-9)
    assert coarse_too.diagnostics["error_estimate"]["N"] == [32, 64]  # order4's grids
    assert coarse_too.diagnostics["minima_grid"] == {"N": 32, "scheme": "order4"}


def test_a_failed_order4_solve_is_rescued_through_order2() -> None:
    """From the great circle the long way round order4 on N=64 fails (here at an iteration
    limit of 60, about 1 s; without one IPOPT fails after 39 s). The solve then solves order2
    on the same grid from the same start, and order4 from its solution: verified in the
    natural minimum, the rescue told in the diagnostics and its time counted. A rescue that
    fails too says so in the hint; asking for order2 first leaves nothing to rescue."""
    solver = og.compile_problem(heavy_top(), N=64, scheme="order4", ipopt={"max_iter": 60})
    tr = solver.transcription
    p = tr.pack()
    natural = solver.solve(multistart=False)
    assert natural.success and "rescue" not in natural.diagnostics
    far = next(g for g in solver.guesses(tr, p, True) if g.label == "great circle, long way")
    sol = solver.solve(guess=far)
    assert sol.success and sol.cost == pytest.approx(natural.cost, rel=1e-9)
    rescue = sol.diagnostics["rescue"]
    assert rescue["rescued"] and rescue["scheme"] == "order2"
    assert rescue["failed"] == "Maximum_Iterations_Exceeded"
    assert len(rescue["iterations"]) == 2 and sol.iterations == rescue["iterations"][1]
    assert sol.ipopt_seconds_total > sol.solve_seconds + rescue["seconds"] / 2
    console = Console(width=300, record=True)
    console.print(summary(sol))
    table = console.export_text()
    assert "(a rescue through order2)" in table and "│ rescued " in table
    assert "then order4 from its solution: order2 Solve_Succeeded in" in table
    asked = solver.solve(guess=far, continuation=["order2"])
    assert asked.success and "rescue" not in asked.diagnostics
    hopeless = og.compile_problem(heavy_top(), N=64, scheme="order4",
                                  ipopt={"max_iter": 5}).solve(guess=far)
    assert not hopeless.success and not hopeless.diagnostics["rescue"]["rescued"]
    assert "tried order2 on the same grid first" in hopeless.hint


@pytest.mark.parametrize("continuation, expected", [
    (["order2", "order4"], "must differ from each other and from the solve's own (order4)"),
    (["order3"], "unknown scheme 'order3'; choose one of order2, order4")])
def test_continuation_schemes_are_checked(continuation: list, expected: str) -> None:
    with pytest.raises(ConfigError, match=re.escape(expected)):
        og.compile_problem(heavy_top(), N=8, scheme="order4").solve(continuation=continuation)


def test_order2_rules_are_refused_by_order4() -> None:
    with pytest.raises(ConfigError, match="rule 'lie_poisson'.*order2.*Gauss points"):
        og.compile_problem(heavy_top(), N=8, scheme="order4", rule="lie_poisson")


# ------------------------------------------------------------------ reaction wheels

RW_NS = [8, 16, 32]


def test_fully_actuated_landing_is_the_node_steps_sixth_order() -> None:
    """The wheels' torques drive the body's velocity exactly, so the replay integrates the
    plan's own velocity and misses its final attitude by the node-to-node Magnus step's error
    alone: sixth order (N = 8, 16, 32: 3.4e-8, 5.5e-10, 6.9e-12; the fourth-order step
    missed by 3.0e-5, 1.9e-6, 1.2e-7)."""
    cfg = files.load(ROOT / "problems" / "reaction_wheels.yaml",
                     ["discretization.scheme=order4", "solver.multistart=false"])
    pb = files.build(cfg)
    errors = []
    for N in RW_NS:
        sol = og.compile_problem(pb, N=N, scheme="order4").solve()
        assert sol.success, (N, sol.status)
        assert replay_error(sol, "Omega") <= 1e-12
        errors.append(replay_error(sol, "R"))
    assert np.all(orders(errors) >= 5.5), (errors, orders(errors))
    assert errors[-1] <= 1e-10, errors


# ------------------------------------------------------------------ plate-ball files

PB_NS = [8, 16, 32, 64]


@pytest.mark.parametrize("name", ["plate_ball", "plate_ball_rotating"])
def test_plate_ball_converges_at_fourth_order(name: str) -> None:
    cfg = files.load(ROOT / "problems" / f"{name}.yaml", ["discretization.scheme=order4"])
    pb = files.build(cfg)
    sols = {N: og.compile_problem(pb, N=N, scheme="order4").solve(multistart=True) for N in PB_NS}
    for sol in sols.values():
        assert_clean(sol)
    costs = [sols[N].cost for N in PB_NS]
    same_minimum(costs)
    assert np.all(cost_orders(costs) >= MIN_ORDER), (costs, cost_orders(costs))
    errors = [sols[N].diagnostics["replay"]["max_terminal_error"] for N in PB_NS]
    assert np.all(orders(errors) >= MIN_ORDER), (errors, orders(errors))
    ppoly = sols[16].control_ppoly  # linear on each interval, through the stage samples
    assert ppoly["c"].shape == (2, 16, 2) and ppoly["x"].size == 17


# ------------------------------------------------------------------ exact cases


@pytest.mark.parametrize("N", [2, 3, 8, 32])
def test_minimum_acceleration_cubic_is_exact(N: int) -> None:
    """The optimal path is a cubic, its velocity a quadratic: inside the scheme's space, with
    the cost integrated exactly, so every N reproduces it (not just converges to it)."""
    sol = og.solve(minimum_acceleration(), N=N, scheme="order4")
    assert sol.success
    assert np.max(np.abs(sol.states["q"] - cubic(sol.t))) <= 1e-10
    assert sol.diagnostics["replay"]["terminal_error"]["q"] <= 1e-10
    assert sol.diagnostics["euler_lagrange_residual_max"] <= 1e-10


@pytest.mark.parametrize("scheme, N, coefficients, landing", [("order4", 16, 4, 1e-4),
                                                             ("order6", 8, 7, 1e-6)])
def test_cli_solves_with_the_gauss_schemes(tmp_path, scheme: str, N: int, coefficients: int,
                                           landing: float) -> None:
    """order4 (a cubic per interval) and order6 (degree 6) from the command line."""
    out = tmp_path / "sol.json"
    r = CliRunner().invoke(app, ["solve", str(ROOT / "problems" / "so3_rest_to_rest.yaml"), "-q",
                                 "--set", f"discretization.scheme={scheme}", "--set",
                                 f"horizon.N={N}", "--out", str(out)])
    assert r.exit_code == 0, r.output
    sol = json.loads(out.read_text())
    assert sol["discretization"]["scheme"] == scheme and sol["N"] == N
    assert np.array(sol["controls"]["ppoly"]["c"]).shape == (coefficients, N, 3)
    assert sol["diagnostics"]["replay"]["terminal_error"]["R"] <= landing
