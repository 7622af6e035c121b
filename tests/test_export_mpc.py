"""The closed loop in exported C (ocgroupoid.export.mpc, DIR/mpc) against Python's og.mpc.

The rigid body on SO(3) of tests/test_mpc.py (so3_rest_to_rest, N = 16, |u_i| <= 0.45),
its plant's inertia 5 % larger, no noise, converged re-solves: C runs the same arithmetic
(the Functions of ocgroupoid.nlp.loop, generated; the shift's fractional stages computed in
C with stages_after's operations) and the same IPOPT from the same points, so its applied
controls are Python's to 1e-8 (measured: equal to the bit, receding and shrinking; IPOPT's
tol is the default 1e-10 in both). With --rti the C loop takes one real-time iteration per
sample on the generated Functions of ocgroupoid.nlp.rti and HPIPM's generated QP: Python's
og.mpc(rti=True, hessian=...). With the exact Hessian it is Python's to the bit (measured,
both horizons); with the projected one (the default) C's Jacobi rotations stand for numpy's
eigh, and the QP, whose Hessian keeps eigenvalues down to 1e-8 of its largest entry, turns
their rounding differences into control differences of 1.4e-9 receding and 1.6e-10
shrinking (measured; 4.5e-9 on the free flyer, receding).
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.errors import ConfigError
from ocgroupoid.export import export_c

from .cbuild import CFLAGS

FILE = "problems/so3_rest_to_rest.yaml"
N = 16
STEPS = 2 * N  # the default of both loops
COMPARED = 20
SETS = [f"horizon.N={N}", "bounds={u: [-0.45, 0.45]}"]
MISMATCH = {"inertia": 1.05}
TOL = 1e-8


@pytest.fixture(scope="module")
def problem() -> og.Problem:
    return files.build(files.load(FILE, SETS))


@pytest.fixture(scope="module")
def driver(problem: og.Problem, tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("so3_mpc")
    done = export_c(problem, folder, N=N, build=True, cflags=CFLAGS, mpc=True)
    assert done.mpc == folder / "mpc"
    return done.mpc


@pytest.fixture(scope="module")
def runs(problem: og.Problem, driver: Path) -> tuple[og.MpcResult, dict]:
    r = subprocess.run([str(driver), "--steps", str(STEPS), "--mismatch", "inertia=1.05"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return og.mpc(problem, N, STEPS, mismatch=MISMATCH), json.loads(r.stdout)


def assert_same_path(py: og.MpcResult, c: dict, control_tol: float = TOL,
                     state_tol: float = TOL) -> None:
    """The first :data:`COMPARED` applied controls (all, if fewer) and every plant state of
    the C loop are Python's to ``control_tol`` and ``state_tol``."""
    compared = min(COMPARED, len(py.steps))
    u_py = np.array([s.control for s in py.steps])[:COMPARED]
    u_c = np.array([s["control"] for s in c["steps"]])[:COMPARED]
    assert u_c.shape == u_py.shape == (compared, len(py.control_names))
    assert np.max(np.abs(u_c - u_py)) <= control_tol
    assert np.max(np.abs(np.array(c["trajectory"]["z"]) - py.z)) <= state_tol


def test_c_loop_applies_pythons_controls(runs: tuple[og.MpcResult, dict]) -> None:
    """The first 20 applied controls of C's loop are Python's to 1e-8, and so are the
    plant's states, statuses and iterations (the warm starts work alike)."""
    py, c = runs
    assert_same_path(py, c)
    assert [s["status"] for s in c["steps"]] == [s.status for s in py.steps]
    assert [s["iterations"] for s in c["steps"]] == [s.iterations for s in py.steps]
    assert max(s.iterations for s in py.steps[2:]) < py.steps[0].iterations  # warm


def test_c_loop_reaches_the_target_like_python(runs: tuple[og.MpcResult, dict]) -> None:
    """After 2N samples both loops are as close to the target (to 1e-8), far closer than
    the 2.5 rad they started from; no step failed, the bounds held; the JSON has the keys
    of Python's mpc.json."""
    py, c = runs
    s = c["summary"]
    assert s["failed_steps"] == 0 == py.failed_steps
    for key, value in py.terminal_error.items():
        assert abs(s["terminal_error"][key] - value) <= TOL
    assert s["terminal_error"]["R"] < 0.05
    assert s["bound_violation_max"] <= 1e-6
    assert abs(s["tracking_error_max"] - py.tracking_error_max) <= TOL
    assert set(py.to_dict()) == set(c)
    assert c["bounds"] == py.bounds and len(c["bounds"]) == 3  # |u_i| <= 0.45
    assert set(c["settings"]) - {"language"} == set(py.settings)
    assert {k: c["settings"][k] for k in py.settings} == py.settings  # order4 steps with exp
    assert set(py.summary()) == set(s)
    assert set(c["steps"][0]) == set(py.steps[0].as_dict()) | {"tracking_error_max"}
    timing = s["timing"]["step"]
    assert timing["count"] == STEPS - 1 and 0 < timing["median"] <= timing["max"]


@pytest.fixture(scope="module", params=["projected", "exact"])
def rti_runs(request: pytest.FixtureRequest, problem: og.Problem, driver: Path
             ) -> tuple[str, og.MpcResult, dict]:
    hessian = request.param
    r = subprocess.run([str(driver), "--steps", str(STEPS), "--mismatch", "inertia=1.05",
                        "--rti", "--hessian", hessian], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    return (hessian, og.mpc(problem, N, STEPS, mismatch=MISMATCH, rti=True, hessian=hessian),
            json.loads(r.stdout))


def test_c_rti_loop_applies_pythons_controls(rti_runs: tuple[str, og.MpcResult, dict]
                                             ) -> None:
    """The first 20 controls of C's real-time iterations are Python's (rti=True, the same
    Hessian) to 1e-8, and so are the plant's states; every QP solved in both (in C only with
    HPIPM's defaults set: export.functions.hpipm_defaults), with the same statuses and
    HPIPM's iterations (export.functions.hpipm_iterations); the settings say rti and the
    Hessian; the driver times the QPs."""
    hessian, py, c = rti_runs
    assert_same_path(py, c)
    assert [s["status"] for s in c["steps"]] == [s.status for s in py.steps]
    assert [s["iterations"] for s in c["steps"]] == [s.iterations for s in py.steps]
    assert c["summary"]["failed_steps"] == 0 == py.failed_steps
    assert (c["settings"]["mode"], c["settings"]["qp"], c["settings"]["hessian"]) == (
        "rti", "hpipm", hessian)
    assert c["summary"]["terminal_error"]["R"] < 0.05
    timing = c["summary"]["timing"]
    assert 0 < timing["qp"]["median"] <= timing["feedback"]["median"]


@pytest.fixture(scope="module", params=[("converged", 1), ("rti", 3)])
def shrinking_runs(request: pytest.FixtureRequest, problem: og.Problem, driver: Path
                   ) -> tuple[str, int, og.MpcResult, dict]:
    mode, min_horizon = request.param
    # both spellings: --horizon shrinking, and --shrinking as `ocgroupoid mpc` takes it
    how = ["--horizon", "shrinking"] if mode == "converged" else ["--shrinking"]
    r = subprocess.run([str(driver), *how, "--min-horizon", str(min_horizon),
                        "--mismatch", "inertia=1.05", *(["--rti"] if mode == "rti" else [])],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return (mode, min_horizon, og.mpc(problem, N, horizon="shrinking", min_horizon=min_horizon,
                                      mismatch=MISMATCH, rti=mode == "rti"),
            json.loads(r.stdout))


def test_c_shrinking_loop_applies_pythons_controls(
        shrinking_runs: tuple[str, int, og.MpcResult, dict]) -> None:
    """A shrinking horizon (p's T the time left at every sample, the shift's fractional
    stages those of T - h over T): C's controls and states are Python's to 1e-8 over all N
    samples, converged and RTI (measured: to the bit converged, 1.6e-10 with RTI's projected
    Hessian), and so are the statuses and iterations (IPOPT's, HPIPM's) — with min_horizon 3
    the last two samples hold the last plan in both (status "hold", left out of the
    timing)."""
    mode, min_horizon, py, c = shrinking_runs
    assert_same_path(py, c)
    statuses = [s["status"] for s in c["steps"]]
    assert statuses == [s.status for s in py.steps] and len(statuses) == N
    assert statuses.count("hold") == min_horizon - 1
    assert (c["settings"]["horizon"], c["settings"]["min_horizon"], c["settings"]["mode"],
            c["settings"]["steps"]) == ("shrinking", min_horizon, mode, N)
    assert c["summary"]["failed_steps"] == 0 == py.failed_steps
    timed = c["summary"]["timing"]["step"]["count"]
    assert timed == N - min_horizon == py.timing()["step"]["count"]
    assert set(py.to_dict()) == set(c)
    for key, value in py.terminal_error.items():
        assert abs(c["summary"]["terminal_error"][key] - value) <= TOL
    assert [s["iterations"] for s in c["steps"]] == [s.iterations for s in py.steps]


def test_a_fatrop_export_runs_the_loop_as_python_does(problem: og.Problem,
                                                      tmp_path: Path) -> None:
    """With solver.backend fatrop the C loop re-solves through fatrop's driver, warm started
    from the last plan's primal point and keeping fatrop's solver from sample to sample: its
    controls and plant states are Python's fatrop loop's to 1e-8, every step solved."""
    done = export_c(problem, tmp_path / "c", N=N, build=True, cflags=CFLAGS, mpc=True,
                    backend="fatrop")
    assert done.mpc is not None and (tmp_path / "c" / "ocg_fatrop_ocp.c").is_file()
    r = subprocess.run([str(done.mpc), "--steps", str(STEPS), "--mismatch", "inertia=1.05"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    c = json.loads(r.stdout)
    py = og.mpc(problem, N, STEPS, mismatch=MISMATCH, backend="fatrop")
    assert_same_path(py, c)
    assert c["summary"]["failed_steps"] == 0 == py.failed_steps
    assert {s["status"] for s in c["steps"]} == {"Solve_Succeeded"}


def test_c_driver_refuses_bad_input(driver: Path) -> None:
    """An unknown parameter, a bad factor, horizon or count: exit 2 and a message saying
    what to write."""
    for args, said in ((["--mismatch", "mass=2"], "no parameter"),
                       (["--mismatch", "inertia=-1"], "> 0"), (["--steps", "0"], ">= 1"),
                       (["--hessian", "gauss-newton"], "projected or exact"),
                       (["--horizon", "sliding"], "receding or shrinking"),
                       (["--min-horizon", "0"], ">= 1"),
                       (["--horizon", "shrinking", "--steps", str(N + 1)], f"at most {N}")):
        r = subprocess.run([str(driver), *args], capture_output=True, text=True, timeout=60)
        assert r.returncode == 2 and said in r.stderr, (args, r.stderr)


@pytest.mark.parametrize("file, sets, said", [
    ("problems/so3_minimum_time.yaml", ["horizon.N=8"], "final time is free"),
    ("problems/dubins_car.yaml", ["horizon={T: 6.0, N: 8}", "objective={effort: 1.0, time: 0.0}",
                                  "discretization={scheme: order2}"],
     "no continuous second-order dynamics"),
])
def test_a_problem_without_a_loop_is_refused_as_in_python(file: str, sets: list[str],
                                                          said: str, tmp_path: Path) -> None:
    """mpc=True on a free final time or a first-order problem: Python's message; without
    mpc=True the export goes on without the loop."""
    pb = files.build(files.load(file, sets))
    with pytest.raises(ConfigError, match=said) as python:
        og.mpc(pb, 8, 2)
    with pytest.raises(ConfigError, match=said) as exported:
        export_c(pb, tmp_path / "a", N=8, mpc=True)
    assert str(python.value) in str(exported.value)
    done = export_c(pb, tmp_path / "b", N=8)
    assert done.mpc is None and not (done.folder / "mpc_main.c").exists()
