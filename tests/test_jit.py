"""Re-solves made fast (issue 18): compiled evaluation (solver.jit) gives the same solve as the
virtual machine, with a library cached per structure and a clear error without a C compiler;
a primal-dual warm start reaches the cold solution in fewer iterations."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.bench.methods import Method
from ocgroupoid.bench.timing import Setting
from ocgroupoid.errors import ConfigError
from ocgroupoid.systems.heavy_top import heavy_top
from ocgroupoid.systems.rigid_body import rigid_body
from ocgroupoid.verify.diagnostics import replay_of

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"

needs_cc = pytest.mark.skipif(not any(shutil.which(c) for c in ("cc", "gcc", "clang")),
                              reason="no C compiler on PATH")


@pytest.fixture(autouse=True)
def own_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("OCGROUPOID_JIT_CACHE", str(tmp_path / "jit"))
    return tmp_path / "jit"


@needs_cc
@pytest.mark.parametrize("factory, scheme", [(rigid_body, "order2"), (rigid_body, "order4"),
                                             (heavy_top, "order2"), (rigid_body, "rk4_quat")])
def test_a_compiled_solve_equals_the_virtual_machine_solve(factory, scheme: str) -> None:
    vm = og.compile_problem(factory(), N=24, scheme=scheme).solve(multistart=False)
    solver = og.compile_problem(factory(), N=24, scheme=scheme, jit=True)
    assert solver.transcription.jit and solver.transcription.jit_compiled
    jit = solver.solve(multistart=False)
    assert jit.status == vm.status and jit.iterations == vm.iterations
    assert abs(jit.cost - vm.cost) <= 1e-10 * max(1.0, abs(vm.cost))
    assert np.max(np.abs(jit.x - vm.x)) <= 1e-10 * max(1.0, float(np.max(np.abs(vm.x))))


@needs_cc
def test_the_library_is_cached_per_structure(own_cache: Path) -> None:
    first = og.compile_problem(rigid_body(), N=16, jit=True).transcription
    again = og.compile_problem(rigid_body(inertia=[3.0, 2.0, 1.0]), N=16, jit=True)
    assert first.jit_compiled and not again.transcription.jit_compiled  # values are inputs
    other = og.compile_problem(rigid_body(), N=20, jit=True).transcription
    assert other.jit_compiled  # another N is another structure
    assert len(list(own_cache.glob("ocg_jit_*.so"))) == 2
    assert not list(own_cache.glob(".*"))  # no half-written library left


def test_without_a_compiler_jit_says_what_to_do(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", "/nonexistent")
    monkeypatch.delenv("CC", raising=False)
    with pytest.raises(ConfigError, match="solver.jit needs a C compiler"):
        og.compile_problem(rigid_body(), N=12, jit=True)


@needs_cc
def test_problem_file_key_reaches_the_solver(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from ocgroupoid.cli import app

    so3 = Path(__file__).resolve().parents[1] / "problems" / "so3_rest_to_rest.yaml"
    out = tmp_path / "sol.json"
    r = CliRunner().invoke(app, ["solve", str(so3), "-q", "--set", "solver.jit=true", "--set",
                                 "horizon.N=16", "--set", "solver.multistart=false",
                                 "--out", str(out)])
    assert r.exit_code == 0, r.output
    bad = CliRunner().invoke(app, ["solve", str(so3), "--set", "solver.jit=3"])
    assert bad.exit_code == 2 and "solver.jit" in bad.output


def test_a_primal_dual_warm_start_reaches_the_cold_solution_in_fewer_iterations() -> None:
    """Issue 18: re-solves with new values start from the previous solution's point and
    multipliers (IPOPT's warm_start_init_point); same cost as a cold solve."""
    from ocgroupoid.lie import so3

    solver = og.compile_problem(rigid_body(), N=32)
    prev = solver.solve()
    axis = np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0)
    for k in (1, 2, 3):
        final = {"R": so3.from_rotvec(axis * 2.5 * (1 + 0.02 * k))}
        cold = solver.solve(final=final)
        warm = solver.solve(final=final, warm=prev)
        assert warm.success and warm.discretization["start"] == "warm start"
        assert abs(warm.cost - cold.cost) <= 1e-8 * cold.cost
        assert warm.iterations < cold.iterations, (warm.iterations, cold.iterations)
        prev = warm
    with pytest.raises(ConfigError, match="same compiled problem"):
        og.compile_problem(rigid_body(), N=16).solve(warm=prev)


def test_a_warm_start_is_heard_and_stopped_like_a_cold_one() -> None:
    """A primal-dual warm start (a re-solve, a sweep's neighbour, IPOPT's polish after
    fatrop) hears its listener at every iteration, which stops it by returning True: so a
    warm solve keeps its deadline and Ctrl-C."""
    from ocgroupoid.lie import so3
    from ocgroupoid.nlp.program import Guess

    solver = og.compile_problem(rigid_body(), N=24)
    tr = solver.transcription
    prev = solver.solve(multistart=False)
    axis = np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0)
    p = tr.pack(final={"R": so3.from_rotvec(axis * 2.6)})
    warm = Guess("warm start", np.zeros((0, 0)), prev.x, prev.lam_g, prev.lam_x)
    heard: list[int] = []
    r = tr.solve(warm, p, lambda i, f, g: heard.append(i) is not None)
    assert r.success and heard == list(range(r.iterations + 1)), (heard, r.iterations)
    stopped = tr.solve(warm, p, lambda i, f, g: i >= 1)
    assert stopped.status == "User_Requested_Stop" and stopped.iterations == 1



@needs_cc
@pytest.mark.parametrize("name, N", [("so3_minimum_time", 8), ("dubins_car", 8),
                                     ("reaction_wheels", 16)])
def test_the_compiled_replay_reports_what_the_graphs_report(name: str, N: int) -> None:
    """With jit the replay's RK4 substep and samples of the bounds are machine code: on a
    solution, its report (terminal errors, the substeps its doublings chose, the running cost,
    the bounds' worst violations, the constraints along it) is the one CasADi's evaluation of
    the same graphs gives, to rounding."""
    cfg = files.load(PROBLEMS / f"{name}.yaml", ["solver.multistart=false"])
    method = Method(cfg.file.discretization.scheme, jit=True)
    solver = Setting.of(cfg.file).compile(files.build(cfg), method, N)
    sol = solver.solve()
    tr = solver.transcription
    replay = replay_of(tr)
    out = tr.readout(sol.x, sol.p, sol.lam_g)
    assert replay.compiled
    compiled = replay.run(out, sol.control_ppoly, sol.p)
    assert [key[-1] for key in replay._kernels] == [True]  # no graph evaluated
    assert {fn.class_name() for fn in replay._substep(*next(iter(replay._kernels))[:2],
                                                      compiled=True)} == {"External"}
    replay.compiled = False
    graphs = replay.run(out, sol.control_ppoly, sol.p)
    assert compiled["available"] and compiled["substeps"] == graphs["substeps"]
    for key in ("max_terminal_error", "running_cost", "integration_error"):
        assert compiled[key] == pytest.approx(graphs[key], rel=1e-12, abs=1e-15), key
    np.testing.assert_allclose(compiled["final_state"], graphs["final_state"], rtol=1e-12,
                               atol=1e-15)
    for key in ("bound_violation_max", "constraint_residual_max"):
        assert (key in compiled) == (key in graphs), key
        if key in compiled:
            assert compiled[key] == pytest.approx(graphs[key], rel=1e-9, abs=1e-14), key
    assert "bound_violation_max" in compiled  # every one of the three has bounds
