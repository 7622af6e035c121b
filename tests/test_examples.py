"""Two problems a control engineer writes first, with their limits (issue 14): the cart-pole
swing-up and the reaction-wheel spacecraft, each from the Python API and from its problem
file (``problems/cart_pole.yaml``, ``problems/reaction_wheels.yaml``)."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid.cli import app

ROOT = Path(__file__).resolve().parent.parent
UNBOUNDED_CART_POLE = 44.70  # the figure (order4, N = 128: 44.70123)


def solve_file(name: str, tmp_path: Path, *settings: str) -> og.Solution:
    """The problem file solved by the CLI, read back from its solution JSON."""
    out = tmp_path / f"{name}.json"
    args = ["solve", str(ROOT / "problems" / f"{name}.yaml"), "--out", str(out), "-q"]
    r = CliRunner().invoke(app, args + [a for s in settings for a in ("--set", s)])
    assert r.exit_code == 0, r.output
    return og.Solution.from_json(out)


def orders(values: list[float]) -> np.ndarray:
    d = np.abs(np.diff(values))
    return np.log2(d[:-1] / d[1:])


# ------------------------------------------------------------------ cart-pole


def cart_pole(F_max: float | None = 10.0, x_max: float | None = 1.0) -> og.Problem:
    """Cart 1 kg, pole 0.1 kg on 0.5 m, g = 9.81, T = 2: from hanging at rest to upright at
    rest, x(T) free, cost int F^2 dt; |F| <= F_max, |x| <= x_max (None: no limit)."""
    G = og.Groupoid(og.Pair(1, "x", "dx"), og.Pair(1, "theta", "dtheta"))
    pb = og.Problem(G, name="cart_pole")
    M, m, l, g = 1.0, 0.1, 0.5, 9.81
    x, th, dx, dth = pb.state("x"), pb.state("theta"), pb.velocity("dx"), pb.velocity("dtheta")
    L = (0.5 * (M + m) * dx**2 + m * l * ca.cos(th) * dx * dth + 0.5 * m * l**2 * dth**2
         + m * g * l * ca.cos(th))
    F = pb.mechanics(L, actuated=["dx"], control_names=["F"])
    pb.minimize(F**2)
    if F_max is not None:
        pb.bound(F, -F_max, F_max, name="F")
    if x_max is not None:
        pb.bound(x, -x_max, x_max, name="x")
    pb.initial(x=[0.0], theta=[0.0], dx=[0.0], dtheta=[0.0])
    pb.final(theta=[np.pi], dx=[0.0], dtheta=[0.0])
    pb.horizon(2.0)
    return pb


@pytest.fixture(scope="module")
def swing_up() -> dict[int, og.Solution]:
    return {N: og.solve(cart_pole(), N=N, scheme="order4", multistart=True,
                        ipopt={"tol": 1e-10}) for N in (32, 64, 128)}


def test_cart_pole_limits_become_active_and_hold(swing_up) -> None:
    free = og.solve(cart_pole(None, None), N=64, scheme="order4", multistart=True,
                    ipopt={"tol": 1e-10})
    assert abs(free.cost - UNBOUNDED_CART_POLE) <= 5e-3, free.cost
    for N, sol in swing_up.items():
        assert sol.success, (N, sol.status)
        assert sol.cost > free.cost + 4.0, (N, sol.cost)  # 49.6 against 44.70
        d = sol.diagnostics
        assert set(d["bounds_active"]) == {"F", "x"}, d["bounds_active"]
        assert d["bound_violation_points"] <= 1e-8  # where imposed; between: the replay's
        tol = d["verdict"]["tolerances"]["bounds"]
        assert all(v <= tol[n] for n, v in d["bound_violation"].items()), d["bound_violation"]
        assert d["bound_points"] == 4 * N  # interval ends and both Gauss points
        # independently of the diagnostics: the force (its piecewise polynomial) at the
        # nodes and both Gauss points of every interval, and the track position at the nodes
        h, c = sol.T / N, np.array([0.5 - np.sqrt(3) / 6, 0.5 + np.sqrt(3) / 6])
        t = np.concatenate([sol.t, (sol.t[:-1, None] + h * c).ravel()])
        assert np.max(np.abs(sol.control(t))) <= 10 + 1e-8
        assert np.max(np.abs(sol.states["x"])) <= 1 + 1e-8
        assert d["replay"]["max_terminal_error"] <= 5e-2 * (32 / N) ** 3


def test_cart_pole_cost_converges(swing_up) -> None:
    """The bounded optimum is not smooth where a bound switches on, so the order falls
    below the scheme's four; the cost still falls monotonically and its steps shrink."""
    costs = [swing_up[N].cost for N in sorted(swing_up)]
    steps = np.abs(np.diff(costs))
    assert np.all(np.diff(costs) < 0) and steps[1] < steps[0] / 2, costs


def test_cart_pole_file_is_the_api_problem(swing_up, tmp_path) -> None:
    sol = solve_file("cart_pole", tmp_path)  # its N is 64
    assert sol.success and abs(sol.cost - swing_up[64].cost) <= 1e-8 * sol.cost


# ------------------------------------------------------------------ reaction wheels


def reaction_wheels(tau_max: float | None = 0.1, rate_max: float | None = 6.5) -> og.Problem:
    """Body inertia diag(1, 2, 3), three wheels (J = 0.05) on the body axes driven by torques
    tau; rest to rest by 1 rad about (1, 2, 3) in 10 s, cost 1/2 int |tau|^2 dt."""
    G = og.Groupoid(og.LieGroupFactor(state="R", velocity="Omega"), og.Pair(3, "phi", "dphi"))
    pb = og.Problem(G, name="reaction_wheels")
    I = pb.parameter("inertia", 3, [1.0, 2.0, 3.0])
    J = pb.parameter("J", 3, [0.05, 0.05, 0.05])
    Om, dphi = pb.velocity("Omega"), pb.velocity("dphi")
    L = 0.5 * ca.dot(Om, I * Om) + 0.5 * ca.dot(J, (Om + dphi) ** 2)
    tau = pb.mechanics(L, actuated=["dphi"], control_names=["tau1", "tau2", "tau3"])
    pb.minimize(0.5 * ca.dot(tau, tau))
    if tau_max is not None:
        pb.bound(tau, -tau_max, tau_max, name="u")
    if rate_max is not None:
        pb.bound(dphi, -rate_max, rate_max, name="dphi")
    pb.initial(R=np.eye(3), Omega=[0, 0, 0], phi=[0, 0, 0], dphi=[0, 0, 0])
    pb.final(R=og.so3.from_axis_angle([1, 2, 3], 1.0), Omega=[0, 0, 0])
    pb.horizon(10.0)
    return pb


@pytest.fixture(scope="module")
def slews() -> dict[int, og.Solution]:
    return {N: og.solve(reaction_wheels(), N=N, ipopt={"tol": 1e-10}) for N in (32, 64, 128)}


def test_reaction_wheel_limits_become_active_and_hold(slews) -> None:
    free = og.solve(reaction_wheels(None, None), N=64, ipopt={"tol": 1e-10})
    for N, sol in slews.items():
        assert sol.success, (N, sol.status)
        assert sol.cost > free.cost * 1.05
        d = sol.diagnostics
        assert {"u[2]", "dphi[2]"} <= set(d["bounds_active"]), d["bounds_active"]
        assert d["bound_violation_points"] <= 1e-8  # where imposed; between: the replay's
        tol = d["verdict"]["tolerances"]["bounds"]
        assert all(v <= tol[n] for n, v in d["bound_violation"].items()), d["bound_violation"]
        assert np.max(np.abs(sol.controls)) <= 0.1 + 1e-8
        assert np.max(np.abs(sol.velocities["dphi"])) <= 6.5 + 1e-8
        assert d["euler_lagrange_residual_max"] <= 1e-8
        # momentum is conserved: Omega(T) = 0 leaves the wheels at rest too
        assert np.max(np.abs(sol.velocities["dphi"][-1])) <= 1e-6


def test_reaction_wheel_cost_converges_at_second_order(slews) -> None:
    costs = [slews[N].cost for N in sorted(slews)]
    assert np.all(orders(costs) >= 1.8), (costs, orders(costs))


def test_reaction_wheels_file_is_the_api_problem(slews, tmp_path) -> None:
    sol = solve_file("reaction_wheels", tmp_path, "discretization.scheme=order2")  # N = 64
    assert sol.success and abs(sol.cost - slews[64].cost) <= 1e-8 * sol.cost
    faster = solve_file("reaction_wheels", tmp_path, "parameters.tau_max=0.12")
    assert faster.success and faster.cost < sol.cost
    assert np.max(np.abs(faster.controls)) <= 0.12 + 1e-8
