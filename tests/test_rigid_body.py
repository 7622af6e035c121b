"""so3_rest_to_rest: the compiler core end to end (issue 2)."""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np
import pytest

import ocgroupoid as og
from ocgroupoid.errors import BoundaryError, ConfigError
from ocgroupoid.nlp import make_scheme
from ocgroupoid.simulation.simulate import DiscreteFlow
from ocgroupoid.systems.rigid_body import rigid_body

from .lie_oracles import vee_skew

NS = [16, 32, 64, 128, 256, 512]


def observed_orders(values: list[float]) -> np.ndarray:
    v = np.asarray(values)
    return np.log2(v[:-1] / v[1:])


@pytest.fixture(scope="module")
def sols() -> dict[int, og.Solution]:
    pb = rigid_body()
    return {N: og.solve(pb, N=N) for N in NS}


def test_forward_flow_stays_on_so3_for_ten_thousand_steps() -> None:
    """Zero control, no target: R^T R = I to 1e-12 and the quadratic invariants conserved."""
    pb = rigid_body()
    N, T = 10_000, 100.0
    flow = DiscreteFlow(make_scheme("order2", pb, N, "cayley", "midpoint"))
    I = np.array([1.0, 2.0, 3.0])
    s, xi = flow.run(np.array([1.0, 0, 0, 0]), np.array([1.0, 0.5, -0.3]), np.zeros((N, 3)),
                     T, I)
    f = pb.groupoid.factors[0]
    assert max(f.distance(row) for row in s) <= 1e-12
    energy, casimir = 0.5 * np.sum(I * xi**2, axis=1), np.sum((I * xi) ** 2, axis=1)
    assert np.ptp(energy) <= 1e-12 and np.ptp(casimir) <= 1e-12


@pytest.mark.parametrize("N", NS)
def test_solves_with_few_iterations_and_tiny_residuals(sols, N: int) -> None:
    sol = sols[N]
    d = sol.diagnostics
    assert sol.success and sol.status == "Solve_Succeeded"
    assert sol.iterations <= 15
    assert d["euler_lagrange_residual_max"] <= 1e-8
    assert len(d["euler_lagrange_residual_per_node"]) == N - 1
    assert d["manifold_distance"]["R"] <= 1e-12
    R = sol.states["R"]
    assert np.max(np.linalg.norm(np.einsum("kji,kjl->kil", R, R) - np.eye(3), axis=(1, 2))) \
        <= 1e-12
    assert d["final_residual"]["R"] <= 1e-9


def test_cost_converges_at_second_order(sols) -> None:
    J = [sols[N].cost for N in NS]
    orders = observed_orders(list(np.abs(np.diff(J))))
    assert np.all(orders >= 1.8), orders


def test_replay_error_falls_at_second_order(sols) -> None:
    err = [sols[N].diagnostics["replay"]["terminal_error"]["R"] for N in NS]
    assert np.all(observed_orders(err) >= 1.8), err
    assert sols[128].diagnostics["replay"]["terminal_error"]["R"] <= 1e-3


def test_every_retraction_is_second_order() -> None:
    pb = rigid_body()
    for ret in ("exp", "first_order"):
        J = [og.solve(pb, N=N, retraction=ret).cost for N in (32, 64, 128, 256)]
        assert np.all(observed_orders(list(np.abs(np.diff(J)))) >= 1.8), (ret, J)


def test_parameters_change_without_rebuilding(monkeypatch) -> None:
    """Inertia, boundary values and T go through p: one compiled solver serves them all."""
    solver = og.compile_problem(rigid_body(), N=48)
    first = solver.solve()

    def no_build(*args, **kwargs):
        raise AssertionError("nlpsol was called again")

    monkeypatch.setattr(ca, "nlpsol", no_build)
    new = dict(params={"inertia": [2.0, 1.5, 0.8]}, final={"R": og.so3.from_rotvec([0, 0, 1])},
               initial={"Omega": [0.1, 0, 0]}, T=4.0)
    other = solver.solve(**new)
    monkeypatch.undo()
    reference = og.solve(rigid_body(inertia=[2.0, 1.5, 0.8], RT=og.so3.from_rotvec([0, 0, 1]),
                                    Omega0=[0.1, 0, 0], T=4.0), N=48)
    assert other.success and abs(other.cost - first.cost) > 1e-3
    assert abs(other.cost - reference.cost) <= 1e-10 * max(1.0, reference.cost)
    assert other.parameters["inertia"] == [2.0, 1.5, 0.8]


def test_structure_changes_are_refused() -> None:
    solver = og.compile_problem(rigid_body(), N=16)
    with pytest.raises(BoundaryError, match="build a new Transcription"):
        solver.solve(final={"Omega": None})


def test_multistart_finds_the_long_way_round() -> None:
    """A 160 degree slew with the body spinning the other way: the cheap path turns long."""
    pb = rigid_body(RT=og.so3.from_axis_angle([0, 0, 1], 2.8), Omega0=[0, 0, -3.0], T=2.0,
                    name="long_way")
    solver = og.compile_problem(pb, N=64)
    plain = solver.solve(multistart=False)
    multi = solver.solve(multistart=True)
    assert plain.success and multi.success
    assert multi.cost < 0.5 * plain.cost
    costs = [m["cost"] for m in multi.minima]
    assert len(costs) >= 2 and min(costs) == pytest.approx(multi.cost)
    assert any(abs(c - plain.cost) <= 1e-6 * plain.cost for c in costs)
    assert multi.discretization["start"] == "long way round"


def test_continuation_matches_direct_solve() -> None:
    pb = rigid_body()
    direct = og.solve(pb, N=128)
    cont = og.compile_problem(pb, N=128).solve(continuation=[16, 32])
    assert cont.success
    assert cont.discretization["start"] == "interpolated from N=32, with its multipliers"
    assert cont.cost == pytest.approx(direct.cost, rel=1e-9)


def test_a_failed_grid_is_not_continued_from(monkeypatch) -> None:
    """A coarse grid that fails (here made to: its points replaced by garbage) is not the
    next grid's start: the next grid starts from the guesses, as a direct solve does (same
    iterations, same cost), and the note says so."""
    pb = rigid_body()
    solver = og.compile_problem(pb, N=32)
    direct = solver.solve(multistart=False)
    solve_starts = solver._starts

    def failing(tr, starts, p, *rest):
        level, report = solve_starts(tr, starts, p, *rest)
        if tr.N == 16:
            level = [replace(r, x=np.full_like(r.x, 1e3), success=False,
                             status="Maximum_Iterations_Exceeded") for r in level]
        return level, report

    monkeypatch.setattr(solver, "_starts", failing)
    sol = solver.solve(multistart=False, continuation=[16])
    assert sol.success and sol.discretization["start"] == direct.discretization["start"]
    assert sol.iterations == direct.iterations
    assert sol.cost == pytest.approx(direct.cost, rel=1e-12)
    assert sol.diagnostics["continuation"] == [
        "continuation: order2 on N=16 failed (Maximum_Iterations_Exceeded); the next grid "
        "starts from the guesses, not from it"]
    assert "error_estimate" not in sol.diagnostics  # no estimate from a failed grid


def test_terminal_condition_has_no_root_at_a_half_turn() -> None:
    """A final R at relative rotation pi satisfies skew(R_T^T R) = 0 but not our condition."""
    pb = rigid_body()
    tr = og.compile_problem(pb, N=16).transcription
    p = tr.pack()
    RT = pb.groupoid.factors[0].matrix(p[tr.layout.p_slices["end"]])
    fake = pb.groupoid.factors[0].parse_state(RT @ og.so3.from_axis_angle([1, -1, 2], np.pi))
    assert np.allclose(vee_skew(RT.T @ pb.groupoid.factors[0].matrix(fake)), 0, atol=1e-12)
    with np.errstate(divide="ignore"):
        c = np.asarray(tr.scheme.stages.chart(fake, p[tr.layout.p_slices["end"]])).ravel()
    assert np.min(np.abs(c)) > 1e6


def test_solution_json_round_trip(tmp_path, sols) -> None:
    sol = sols[16]
    path = tmp_path / "sol.json"
    sol.to_json(path)
    back = og.Solution.from_json(path)
    assert back.cost == sol.cost and back.status == sol.status and back.N == 16
    assert np.allclose(back.states["R"], sol.states["R"])
    assert np.allclose(back.controls, sol.controls) and np.allclose(back.controls_t, sol.controls_t)
    assert back.controls.shape == (17, 3)
    assert np.allclose(back.x, sol.x)
    assert list(tmp_path.iterdir()) == [path]  # the temporary file was renamed away


def test_bad_discretisation_is_named() -> None:
    with pytest.raises(ConfigError, match="N must be an integer >= 2"):
        og.compile_problem(rigid_body(), N=1)
    with pytest.raises(ConfigError, match="unknown retraction 'cay'"):
        og.compile_problem(rigid_body(), N=8, retraction="cay")
    with pytest.raises(ConfigError, match="horizon T must be finite and > 0"):
        rigid_body(T=-1.0)
