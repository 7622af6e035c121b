"""Bounds, path inequalities, free final time and adaptive steps (issue 14)."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.cli import app
from ocgroupoid.errors import ConfigError
from ocgroupoid.systems.plate_ball import plate_ball
from ocgroupoid.systems.rigid_body import rigid_body

ROOT = Path(__file__).resolve().parent.parent
THETA, A = 2.0, 0.5  # a rotation about e3 by THETA with |du3/dt| <= A: T* = 2 sqrt(THETA/A)
T_STAR = 2 * np.sqrt(THETA / A)


def orders(values: list[float]) -> np.ndarray:
    v = np.abs(np.asarray(values, dtype=float))
    return np.log2(v[:-1] / v[1:])


def controls(pb: og.Problem) -> ca.SX:
    return ca.vertcat(*[c for _, c in pb.controls])


# ------------------------------------------------------------------ minimum time


def minimum_time(T_guess: float = 5.0) -> og.Problem:
    """Rest to rest about the principal axis e3, only its torque actuated (the unactuated
    Euler equations keep Omega_1 = Omega_2 = 0), |u3| <= A, minimum time: a double
    integrator, bang-bang with one switch at T/2. Degenerate by design: the linearisation
    cannot move R or Omega off the e3 rotation, so their final components about e1, e2 are
    implied (:func:`solved_but_degenerate`)."""
    pb = og.Problem(og.LieGroupFactor(state="R", velocity="Omega"), name="minimum_time")
    I = pb.parameter("inertia", 3, [1.0, 2.0, 3.0])
    Om = pb.velocity("Omega")
    u = pb.mechanics(0.5 * ca.dot(Om, I * Om), actuated=[2], input_matrix=I[2],
                     control_names=["u3"])
    pb.bound(u, -A, A, name="u3")
    pb.minimize_time()
    pb.initial(R=np.eye(3), Omega=[0, 0, 0])
    pb.final(R=og.so3.from_axis_angle([0, 0, 1], THETA), Omega=[0, 0, 0])
    pb.horizon(T_guess, free=True, T_min=0.5, T_max=20.0)
    return pb


def solved_but_degenerate(sol: og.Solution) -> bool:
    """IPOPT solved and every check of the verdict passed but the rank test: the final
    conditions about e1, e2 of :func:`minimum_time` are implied (LICQ fails there)."""
    failures = sol.diagnostics["verdict"]["failures"]
    return (sol.status == "Solve_Succeeded" and len(failures) >= 1
            and all("is implied by" in f for f in failures))


@pytest.mark.parametrize("scheme", ["order2", "order4", "order6"])
def test_minimum_time_error_falls_with_uniform_steps(scheme: str) -> None:
    """Odd N: no node on the switch at T/2, so T carries an error that falls with N; the
    controls stay within the bound. order4 and order6 integrate this double integrator
    exactly, so their plans cannot beat the true minimum time (order2's central differences
    can)."""
    errors = []
    for N in (9, 17, 33, 65):
        sol = og.solve(minimum_time(), N=N, scheme=scheme)
        assert solved_but_degenerate(sol), (N, sol.status, sol.hint)
        if scheme != "order2":
            assert sol.T >= T_STAR - 1e-8
        errors.append(abs(sol.T - T_STAR))
        t = np.linspace(0, sol.T, 2001)
        assert np.max(np.abs(sol.control(t))) <= A + 1e-8
        assert sol.diagnostics["bound_violation_max"] <= 1e-8
    assert np.all(np.diff(errors) < 0) and errors[-1] <= 2e-3, errors


@pytest.mark.parametrize("scheme, N", [("order4", 9), ("order4", 17), ("order4", 33),
                                       ("order6", 9), ("order6", 17)])
def test_adaptive_steps_put_a_node_on_the_switch(scheme: str, N: int) -> None:
    """A uniform solve finds the switch; the phased solve moves a node onto it: T exact."""
    sol = og.solve(minimum_time(), N=N, scheme=scheme, steps="adaptive")
    assert solved_but_degenerate(sol), (sol.status, sol.hint)
    assert abs(sol.T - T_STAR) <= 1e-6, sol.T
    assert np.min(np.abs(sol.t - T_STAR / 2)) <= 1e-6  # a node at the switch
    u = sol.control(np.linspace(0, sol.T, 4001))
    assert np.max(np.abs(u)) <= A + 1e-8
    early, late = sol.control(np.array([0.1, 0.4]) * sol.T), sol.control(
        np.array([0.6, 0.9]) * sol.T)
    assert np.allclose(np.abs(early), A) and np.allclose(np.abs(late), A)
    assert np.sign(early[0]) == -np.sign(late[0])  # one switch
    assert sol.diagnostics["replay"]["max_terminal_error"] <= 1e-8


def test_adaptive_steps_continue_through_order2() -> None:
    """order2 cannot place adaptive steps nor hold bounds between its nodes; as a start on
    the way (``continuation: [order2]``, and the rescue of a failed order4) it is solved on
    uniform steps with the bounds at its nodes, and order4 then places the steps: T exact,
    as without it; and holds the bounds at its extra points."""
    sol = og.solve(minimum_time(), N=17, scheme="order4", steps="adaptive",
                   continuation=["order2"])
    assert solved_but_degenerate(sol), (sol.status, sol.hint)
    assert sol.diagnostics["adaptive"]["used"]
    assert abs(sol.T - T_STAR) <= 1e-6, sol.T
    more = og.solve(minimum_time(), N=17, scheme="order4", bound_points=2,
                    continuation=["order2"])
    plain = og.solve(minimum_time(), N=17, scheme="order4", bound_points=2)
    assert solved_but_degenerate(more), (more.status, more.hint)
    assert more.T == pytest.approx(plain.T, rel=1e-8)
    assert more.diagnostics["bound_points"] == plain.diagnostics["bound_points"]


def test_adaptive_steps_need_interval_stages() -> None:
    with pytest.raises(ConfigError, match="adaptive steps.*order4"):
        og.compile_problem(minimum_time(), N=8, scheme="order2", steps="adaptive")


# ------------------------------------------------------------------ bounded slew


@pytest.fixture(scope="module")
def bounded() -> dict[int, og.Solution]:
    sols = {}
    for N in (16, 32, 64, 128):
        pb = rigid_body()
        pb.bound(controls(pb), -0.3, 0.3, name="u")
        sols[N] = og.solve(pb, N=N)
    return sols


def test_bounded_slew_touches_and_holds_the_bound(bounded) -> None:
    free = og.solve(rigid_body(), N=64).cost
    for N, sol in bounded.items():
        assert sol.success, sol.status
        assert sol.cost > free
        assert sol.diagnostics["bound_violation_max"] <= 1e-8
        t = np.linspace(0, sol.T, 4001)  # order2's control: linear between the nodes
        assert np.max(np.abs(sol.control(t))) <= 0.3 + 1e-8
        assert np.max(np.abs(sol.controls)) >= 0.3 - 1e-8  # it touches the bound
        assert sol.diagnostics["bounds_active"], N
        assert sol.diagnostics["euler_lagrange_residual_max"] <= 1e-8


def test_bounded_slew_converges_at_second_order(bounded) -> None:
    costs = [bounded[N].cost for N in sorted(bounded)]
    assert np.all(orders(np.diff(costs)) >= 1.8), (costs, orders(np.diff(costs)))


def test_parameter_bounds_change_without_rebuilding(monkeypatch) -> None:
    pb = rigid_body()
    umax = pb.parameter("umax", 1, 0.3)
    pb.bound(controls(pb), -umax, umax, name="u")
    solver = og.compile_problem(pb, N=24)
    first = solver.solve()
    monkeypatch.setattr(ca, "nlpsol", lambda *a, **k: (_ for _ in ()).throw(AssertionError))
    tighter = solver.solve(params={"umax": 0.29})  # 0.25 is infeasible in T = 5
    assert first.success and tighter.success and tighter.cost > first.cost
    assert np.max(np.abs(tighter.controls)) <= 0.29 + 1e-8


# ------------------------------------------------------------------ path inequalities

SENSOR = np.array([0.452, 0.867, -0.209]) / np.linalg.norm([0.452, 0.867, -0.209])


@pytest.mark.parametrize("scheme", ["order2", "order4"])
def test_keep_out_cone_holds_at_every_node(scheme: str) -> None:
    """The sensor axis R e1 of the unconstrained slew passes through SENSOR; a 30 degree
    cone around it must be left out. (An attitude is a second-order state: the best path
    grazes the cone, at one node or two, rather than sliding along it.)"""
    free = og.solve(rigid_body(), N=64, scheme=scheme).cost
    pb = rigid_body()
    R = pb.node_state("R")
    cos = np.cos(np.radians(30))
    pb.bound(ca.dot(R[:, 0], ca.DM(SENSOR)), upper=cos, name="keep_out")
    sol = og.solve(pb, N=64, scheme=scheme, multistart=True)
    assert sol.success and sol.cost > free * 1.05
    assert np.max(sol.states["R"][:, :, 0] @ SENSOR) <= cos + 1e-9  # every node outside
    assert "keep_out" in sol.diagnostics["bounds_active"]
    assert sol.diagnostics["replay"]["max_terminal_error"] <= 1e-2


def test_a_first_order_state_bound_is_active_on_an_arc() -> None:
    """The rolling ball kept outside a disc on the plate: its path slides along the circle
    (a first-order state constraint) over several consecutive intervals. The order2 rule of
    first-order problems imposes it at the interval midpoints."""
    centre, radius = np.array([0.5, 0.25]), 0.3
    pb = plate_ball(Omega_p=1.0)
    xy = pb.state("xy")
    pb.bound(ca.sumsqr(xy - ca.DM(centre)), lower=radius**2, name="disc")
    sol = og.solve(pb, N=64, multistart=True)
    assert sol.success, sol.status
    nodes = sol.states["xy"]
    dist = np.linalg.norm((nodes[1:] + nodes[:-1]) / 2 - centre, axis=1)  # the midpoints
    assert np.min(dist) >= radius - 1e-9
    on = dist <= radius + 1e-6
    assert np.max(np.convolve(on, np.ones(4, int), "valid")) == 4, dist  # an arc
    assert sol.cost > og.solve(plate_ball(Omega_p=1.0), N=64, multistart=True).cost


# ------------------------------------------------------------------ problem files


def edit(text: str, tmp_path: Path) -> Path:
    path = tmp_path / "p.yaml"
    path.write_text(text)
    return path


BASE = (ROOT / "problems" / "so3_rest_to_rest.yaml").read_text()


def test_problem_file_bounds_free_time_and_objective(tmp_path) -> None:
    text = BASE.replace("horizon:\n  T: 5.0\n  N: 64",
                        "horizon:\n  T: free\n  N: 32\n  T_min: 1.0\n  T_max: 20.0\n"
                        "  T_guess: 6.0") + \
        "bounds: {u: [-0.3, 0.3], Omega: [[null, 1.0], [-1.0, 1.0], [null, null]]}\n" \
        "objective: {effort: 1.0, time: 0.1}\n"
    text = text.replace("[null, null]]", "[-2.0, null]]")
    cfg = files.load(edit(text, tmp_path))
    pb = files.build(cfg)
    assert pb.T_free and pb.T_bounds == (1.0, 20.0) and pb.weights["time"] == 0.1
    assert [b.name for b in pb.inequalities] == ["u", "Omega"]
    sol = og.solve(pb, N=32)
    assert sol.success and 1.0 < sol.T < 20.0
    assert np.max(np.abs(sol.controls)) <= 0.3 + 1e-8


@pytest.mark.parametrize("text, message", [
    ("bounds: {R: [-1, 1]}\n", "no components to bound"),
    ("bounds: {wheel: [-1, 1]}\n", "unknown name 'wheel'"),
    ("bounds: {u: [1, -1]}\n", "lower 1.0 > upper -1.0"),
    ("bounds: {u: [[-1, 1], [-1, 1]]}\n", "3 of them"),
    ("objective: {time: 1.0}\n", "needs a free final time"),
    ("objective: {effort: -1.0}\n", "must be >= 0"),
])
def test_problem_file_bounds_errors_name_the_key(tmp_path, text: str, message: str) -> None:
    r = CliRunner().invoke(app, ["check", str(edit(BASE + text, tmp_path))])
    assert r.exit_code == 2, r.output
    assert message in " ".join(r.output.split())


def test_free_time_needs_its_range(tmp_path) -> None:
    r = CliRunner().invoke(app, ["check", str(edit(BASE.replace("T: 5.0", "T: free"),
                                                   tmp_path))])
    assert r.exit_code == 2 and "T_min and T_max" in " ".join(r.output.split())


@pytest.mark.parametrize("text, message", [
    ("bounds: {u: [-umax, 1]}\n", "unknown name 'umax'"),
    ("bounds: {u: [-inertia, 1]}\n", "not a scalar"),
    ("bounds: {u: ['0.5 +', 1]}\n", "not a valid expression"),
])
def test_parameter_bounds_in_files_are_checked(tmp_path, text: str, message: str) -> None:
    r = CliRunner().invoke(app, ["check", str(edit(BASE + text, tmp_path))])
    assert r.exit_code == 2, r.output
    assert message in " ".join(r.output.split())


def test_a_parameter_bound_in_a_file_follows_the_parameter(tmp_path) -> None:
    text = BASE + "bounds: {u: [\"-0.1 - inertia[0] / 5\", 0.3]}\n"
    path = edit(text, tmp_path)
    lows = []
    for inertia in (1.0, 0.5):
        cfg = files.load(path, [f"parameters.inertia=[{inertia}, 2.0, 3.0]"])
        tr = og.compile_problem(files.build(cfg), N=8).transcription
        lows.append(float(np.min(np.array(tr.bounds_function(tr.pack())[0]))))
    assert lows == pytest.approx([-0.3, -0.2])


def test_check_counts_degrees_of_freedom_over_equalities() -> None:
    """Bounds add inequality rows, never remove degrees of freedom; no bound row is taken
    for a redundant equality."""
    from ocgroupoid.solve.checks import check
    pb = rigid_body()
    pb.bound(controls(pb), -0.3, 0.3, name="u")
    bounded, free = check(pb, N=16), check(rigid_body(), N=16)
    assert bounded.degrees_of_freedom == free.degrees_of_freedom
    assert bounded.inequalities == 3 * 17 and free.inequalities == 0
    assert bounded.redundant == [] and bounded.constraints["bounds"] == 3 * 17


def test_adaptive_steps_are_not_exported(tmp_path) -> None:
    with pytest.raises(ConfigError, match="adaptive steps.*uniform"):
        og.export_c(minimum_time(), tmp_path, N=8, scheme="order4", steps="adaptive")


# ------------------------------------------------------------------ terminal costs


def soft_landing(weight: float = 12.0) -> og.Problem:
    """A double integrator from rest to rest in T = 1, ``1/2 int u^2 dt + weight/2 (x(T) -
    1)^2`` with x(T) free: rest to rest by a costs 6 a^2, so a* = weight / (12 + weight)
    and the optimum is 6 a*^2 + weight/2 (a* - 1)^2 (a* = 1/2, cost 3 for weight 12)."""
    pb = og.Problem(og.Pair(1, "x", "v"), name="soft_landing")
    x, v = pb.state("x"), pb.velocity("v")
    u = pb.mechanics(0.5 * v**2, actuated="v", control_names=["u"])
    pb.minimize(0.5 * u**2)
    pb.terminal_cost(weight / 2 * (x - 1) ** 2)
    pb.initial(x=[0.0], v=[0.0])
    pb.final(v=[0.0])
    pb.horizon(1.0)
    return pb


@pytest.mark.parametrize("scheme", ["order2", "order4"])
def test_terminal_cost_balances_effort_and_landing(scheme: str) -> None:
    errors = []
    for N in (8, 16, 32):
        sol = og.solve(soft_landing(), N=N, scheme=scheme)
        assert sol.success, sol.status
        errors.append(abs(sol.cost - 3.0))
        assert abs(sol.states["x"][-1, 0] - 0.5) <= 10 * errors[-1] + 1e-9
    if scheme == "order4":  # the cubic optimum lies in its piecewise-quadratic velocities
        assert max(errors) <= 1e-9, errors
    else:
        assert np.all(orders(errors) >= 1.8), errors


def test_terminal_cost_in_a_custom_model_file(tmp_path) -> None:
    text = """\
model: custom
definition:
  groupoid: [{type: pair, dim: 1, state: x, velocity: v}]
  lagrangian: "0.5 * v**2"
  actuated: [v]
  cost: "0.5 * u[0]**2"
  terminal_cost: "weight / 2 * (x[0] - 1)**2"
parameters: {weight: 12.0}
horizon: {T: 1.0, N: 16}
initial: {x: [0.0], v: [0.0]}
final: {v: [0.0]}
"""
    cfg = files.load(edit(text, tmp_path))
    sol = og.solve(files.build(cfg), N=16)
    api = og.solve(soft_landing(), N=16)
    assert sol.success and abs(sol.cost - api.cost) <= 1e-10
    heavier = og.solve(files.build(files.load(edit(text, tmp_path), ["parameters.weight=36"])),
                       N=16)
    assert abs(heavier.states["x"][-1, 0] - 0.75) <= 1e-2  # a* = 36 / 48
