"""The exported C loop (DIR/mpc) against Python's og.mpc beyond so3, bounds active.

The free flyer (|tau_i|, |f_i| <= 0.45) and the reaction wheels (|tau_i| <= 0.1, wheel rates
<= 6.5 rad/s) as tests/test_mpc.py sets them up, and the quadrotor with its thrust limit
lowered to f <= 10 N (the plan climbs at it for its first samples; hovering takes 9.81 N):
N = 12, a receding horizon for 20 samples, the mismatched parameter x 1.05, no noise; one
export per model (-O0: the loop is compared, not timed) for both loops.

Converged re-solves: C's controls, states, statuses and iterations are Python's to 1e-8
(measured: to the bit on the reaction wheels and the quadrotor, 2.9e-16 on the free flyer),
and the plans keep their bounds at the points where they are imposed to 1e-6 (measured: 0).

Real-time iterations with the projected Hessian: C's Jacobi rotations stand for numpy's eigh,
and the QPs (Hessian eigenvalues down to 1e-8 of the largest entry) turn their rounding
differences into control differences of (measured) 8.0e-10 on the free flyer, 1.2e-8 on the
reaction wheels and 3.9e-8 on the quadrotor; the states follow, the wheel rates amplifying the
torques' by h / J = 17 (0.83 s over 0.05 kg m^2): 2.3e-10, 3.7e-7 and 6.4e-8; the steps' bound
violations (the free flyer's bound rows are nonlinear: 3.4e-4 in both) to 5.4e-13.
Tolerances: :data:`RTI_TOL`, about four times those. The statuses and HPIPM's iteration
counts are equal.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.export import export_c

from .cbuild import CFLAGS_QUICK
from .test_export_mpc import TOL, assert_same_path
from .test_mpc import MODELS as PYTHON_MODELS

N = 12
STEPS = 20
#: (file, overrides, the bounded control's limit, the mismatched parameter): the Python
#: test's models, and the quadrotor's thrust bounded by 10 N
MODELS = {**PYTHON_MODELS,
          "quadrotor": ("problems/quadrotor.yaml", ["parameters.f_max=10.0"], 10.0, "J")}
#: the RTI's measured differences (module docstring) times about four: controls, states
RTI_TOL = {"free_flyer": (4e-9, 1e-9), "reaction_wheels": (5e-8, 1.5e-6),
           "quadrotor": (1.5e-7, 2.5e-7)}


@pytest.fixture(scope="module", params=list(MODELS))
def exported(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
             ) -> tuple[str, og.Problem, Path]:
    name = request.param
    path, sets, _, _ = MODELS[name]
    problem = files.build(files.load(path, [f"horizon.N={N}", *sets]))
    folder = tmp_path_factory.mktemp(f"{name}_mpc")
    done = export_c(problem, folder, N=N, build=True, cflags=CFLAGS_QUICK, mpc=True)
    assert done.mpc is not None
    return name, problem, done.mpc


def run(exported: tuple[str, og.Problem, Path], rti: bool) -> tuple[og.MpcResult, dict]:
    """Python's loop and C's: STEPS samples, the model's parameter x 1.05."""
    name, problem, driver = exported
    key = MODELS[name][3]
    r = subprocess.run([str(driver), "--steps", str(STEPS), "--mismatch", f"{key}=1.05",
                        *(["--rti", "--hessian", "projected"] if rti else [])],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return og.mpc(problem, N, STEPS, mismatch={key: 1.05}, rti=rti), json.loads(r.stdout)


def assert_same_steps(py: og.MpcResult, c: dict) -> None:
    """Every step solved in both, with the same statuses and iterations."""
    assert c["summary"]["failed_steps"] == 0 == py.failed_steps
    assert [s["status"] for s in c["steps"]] == [s.status for s in py.steps]
    assert [s["iterations"] for s in c["steps"]] == [s.iterations for s in py.steps]


def test_c_loop_applies_pythons_controls_with_bounds_active(
        exported: tuple[str, og.Problem, Path]) -> None:
    """Converged re-solves: C's controls and states are Python's to 1e-8, the statuses and
    iterations equal; a bound is active (an applied control at its limit) and C's plans keep
    them at their points to 1e-6, as Python's."""
    py, c = run(exported, rti=False)
    assert_same_path(py, c)
    assert_same_steps(py, c)
    limit = MODELS[exported[0]][2]
    assert np.max(np.abs(np.array([s["control"] for s in c["steps"]]))) > limit - 1e-3
    assert c["summary"]["bound_violation_max"] <= 1e-6
    assert abs(c["summary"]["bound_violation_max"] - py.bound_violation_max) <= TOL


def test_c_rti_loop_applies_pythons_controls_with_bounds_active(
        exported: tuple[str, og.Problem, Path]) -> None:
    """Real-time iterations (projected Hessian): C's controls and states are Python's to
    :data:`RTI_TOL` (module docstring), every QP solved in both, with HPIPM's iterations
    equal (the count the export's hpipm_iterations hands from the generated QP); the
    steps' bound violations are Python's to the control tolerance."""
    py, c = run(exported, rti=True)
    control_tol, state_tol = RTI_TOL[exported[0]]
    assert_same_path(py, c, control_tol, state_tol)
    assert_same_steps(py, c)
    assert all(s["iterations"] > 0 for s in c["steps"][1:])  # HPIPM's, read from C
    violations = np.array([[s["bound_violation"] for s in c["steps"]],
                           [s.bound_violation for s in py.steps]])
    assert np.max(np.abs(violations[0] - violations[1])) <= control_tol
