"""Exported C code (issue 6): every problem file is exported, built with
``cc -Wall -Wextra -Werror``, run, and compared with the Python API on two instances.

One module-scoped export per problem file (N = 16); the Python reference solves the same
compiled NLP from the same start (the first geodesic guess, ``multistart=False``).
"""

from __future__ import annotations

import json
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.cli import app
from ocgroupoid.errors import ConfigError, ExportError
from ocgroupoid.export.codegen import Export, export_c, make, params_text, write_params

ROOT = Path(__file__).resolve().parent.parent
#: every problem file but the minimum-time quadrotor, whose NLP is the quadrotor's with a free
#: T (covered by quadrotor.yaml and so3_minimum_time.yaml): its build alone takes a minute
PROBLEMS = sorted(p for p in (ROOT / "problems").glob("*.yaml")
                  if p.stem != "quadrotor_min_time")
# A sphere factor, a pair factor and free final components, whatever problems/ holds: the
# heavy top with two rotors of PROBLEMS.md §2 written as a custom model.
SPHERE_AND_PAIR = """\
model: custom
name: custom_heavy_top
definition:
  groupoid:
    - {type: sphere, state: Gamma, velocity: Omega}
    - {type: pair, dim: 2, state: theta, velocity: dtheta}
  lagrangian: >-
    0.5 * ((Ibar[0] + J[0]) * Omega[0]**2 + (Ibar[1] + J[1]) * Omega[1]**2
    + Ibar[2] * Omega[2]**2 + J[0] * dtheta[0]**2 + J[1] * dtheta[1]**2)
    + J[0] * Omega[0] * dtheta[0] + J[1] * Omega[1] * dtheta[1] - mgl * Gamma[2]
  actuated: [dtheta]
  controls: [u1, u2]
  cost: "0.5 * dot(u, u)"
parameters: {Ibar: [1.1, 1.2, 0.6], J: [0.1, 0.1], mgl: [1.0]}
horizon: {T: 3.0, N: 64}
initial:
  Gamma: [0.0, 0.3894183423086505, 0.9210609940028851]   # (0, sin 0.4, cos 0.4)
  Omega: [0.0, 0.0, 5.0]
  theta: [0.0, 0.0]
  dtheta: [0.0, 0.0]
final: {Gamma: [0.0, 0.0, 1.0], Omega: [0.0, 0.0, null], dtheta: [0.0, 0.0]}
"""
ORDER4 = ["so3_rest_to_rest", "heavy_top_rotors", "plate_ball_rotating"]  # one of each kind


@dataclass(frozen=True)
class Case:
    """A problem file (or inline YAML) exported with a scheme."""

    source: Path | str
    scheme: str = "order2"
    backend: str | None = None  # None: the file's own (solver.backend)

    @property
    def id(self) -> str:
        name = self.source.stem if isinstance(self.source, Path) else "custom_heavy_top"
        name = name if self.scheme == "order2" else f"{name}-{self.scheme}"
        return name if self.backend is None else f"{name}-{self.backend}"


CASES = [Case(c) for c in [*PROBLEMS, SPHERE_AND_PAIR]] + \
    [Case(ROOT / "problems" / f"{name}.yaml", "order4") for name in ORDER4] + \
    [Case(ROOT / "problems" / "plate_ball.yaml", "rk4_euler")] + \
    [Case(ROOT / "problems" / "plate_ball.yaml", "order2", "ipopt"),  # the file's is fatrop
     Case(ROOT / "problems" / "so3_minimum_time.yaml", "order4", "fatrop")]


def case_id(case: Case) -> str:
    return case.id


def load_case(case: Case, folder: Path) -> files.Config:
    """The validated problem file of a case (inline YAML is written to ``folder``)."""
    source = case.source
    if isinstance(source, str):
        source = folder / "custom_heavy_top.yaml"
        source.write_text(case.source)
    return files.load(source, [f"discretization.scheme={case.scheme}"] +
                      ([f"solver.backend={case.backend}"] if case.backend else []))
N_TEST = 16
from .cbuild import CFLAGS  # noqa: E402

TOL = 1e-8  # the tolerance on cost and trajectory
VALGRIND = ["so3_rest_to_rest", "heavy_top_rotors", "plate_ball"]

needs_cc = pytest.mark.skipif(shutil.which("cc") is None or shutil.which("make") is None,
                              reason="no C compiler (cc) or make on PATH")


@dataclass
class Built:
    """One problem file exported and built, with its Python reference."""

    name: str
    export: Export
    tr: og.Transcription
    solution: og.Solution  # Python, exported instance

    @property
    def binary(self) -> Path:
        assert self.export.binary is not None
        return self.export.binary


def second_instance(tr: og.Transcription) -> tuple[dict[str, Any], dict[str, Any]]:
    """Other physical parameters (+-10 %) and another target for every prescribed final
    state: rotations and directions moved by the tangent vector (0.1, -0.2, 0.15), poses by
    (0.1, -0.2, 0.15, 0.1, -0.2, 0.15), positions by 0.1 (free components stay free)."""
    pb, G = tr.problem, tr.problem.groupoid
    params = {name: prm.value * (1 + 0.1 * (-1.0) ** np.arange(prm.value.size))
              for name, prm in pb.params.items()}
    p = tr.pack()
    end = p[tr.layout.p_slices["end"]]
    final: dict[str, Any] = {}
    for f, ts, m in zip(G.factors, G.target_layout.slices, tr.masks.end_state):
        if not m.any():
            continue
        s = f.state_of_target(end[ts])
        if f.componentwise:
            final[f.state] = [float(v) + 0.1 if on else None for v, on in zip(s, m)]
        else:
            final[f.state] = np.asarray(f.rplus(s, np.resize([0.1, -0.2, 0.15],
                                                              f.algebra_dim)))
    return params, final


@pytest.fixture(scope="module", params=CASES, ids=case_id)
def built(request, tmp_path_factory) -> Built:
    if shutil.which("cc") is None or shutil.which("make") is None:
        pytest.skip("no C compiler (cc) or make on PATH")
    folder = tmp_path_factory.mktemp(request.param.id)
    cfg = load_case(request.param, folder)
    f = cfg.file
    d = f.discretization
    exp = export_c(files.build(cfg), folder / "c", N_TEST, d.retraction, d.rule, f.solver.ipopt,
                   build=True, cflags=CFLAGS, scheme=d.scheme, backend=f.solver.backend)
    sol = exp.solver.solve()
    return Built(request.param.id, exp, exp.solver.transcription, sol)


def run(binary: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([str(binary), *args], capture_output=True, text=True, timeout=120)


def c_solution(binary: Path, *args: str) -> og.Solution:
    r = run(binary, *args)
    assert r.returncode in (0, 1), r.stderr
    return og.Solution.from_json(r.stdout)


def assert_same(c: og.Solution, py: og.Solution) -> None:
    """The C solution is the Python one: status, cost and trajectory to 1e-8."""
    assert (c.status, c.success) == (py.status, py.success)
    assert c.N == py.N and c.T == pytest.approx(py.T, abs=1e-15)
    assert abs(c.cost - py.cost) <= TOL * max(1.0, abs(py.cost)), (c.cost, py.cost)
    np.testing.assert_allclose(c.t, py.t, rtol=0, atol=1e-12)
    assert set(c.states) == set(py.states)
    for name in py.states:
        np.testing.assert_allclose(c.states[name], py.states[name], rtol=0, atol=TOL,
                                   err_msg=name)
    for name in py.velocities:
        np.testing.assert_allclose(c.velocities[name], py.velocities[name], rtol=0, atol=TOL,
                                   err_msg=name)
    np.testing.assert_allclose(c.controls_t, py.controls_t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(c.controls, py.controls, rtol=0, atol=TOL)
    assert c.discretization["scheme"] == py.discretization["scheme"]
    np.testing.assert_allclose(c.control_ppoly["x"], py.control_ppoly["x"], rtol=0, atol=1e-12)
    assert c.control_ppoly["c"].shape == py.control_ppoly["c"].shape
    largest = float(np.max(np.abs(py.control_ppoly["c"]), initial=0.0))
    np.testing.assert_allclose(c.control_ppoly["c"], py.control_ppoly["c"], rtol=0,
                               atol=TOL * max(1.0, largest))
    assert c.control_names == py.control_names
    np.testing.assert_allclose(c.x, py.x, rtol=0, atol=TOL)
    np.testing.assert_allclose(c.p, py.p, rtol=0, atol=1e-14)
    for key in ("Phi", "final"):
        assert (key in c.multipliers) == (key in py.multipliers)
        if key in py.multipliers:
            lam = np.asarray(py.multipliers[key])
            np.testing.assert_allclose(np.asarray(c.multipliers[key]), lam, rtol=0,
                                       atol=1e-6 * max(1.0, float(np.max(np.abs(lam)))))


# ------------------------------------------------------------------ the generated graphs


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_packing_inverts_the_values_of_p(case: Case, tmp_path: Path) -> None:
    """pack(values_of(p)) = p on the exported instance and on a second one: a parameter
    file (the values) describes an instance completely."""
    cfg = load_case(case, tmp_path)
    f = cfg.file
    tr = og.compile_problem(files.build(cfg), N_TEST, f.discretization.retraction,
                    f.discretization.rule, f.solver.ipopt).transcription
    for p in (tr.pack(), tr.pack(*second_instance(tr))):
        packed, bad = (np.array(v).ravel() for v in tr.values.pack_function(
            tr.values.values_of(p)))
        np.testing.assert_allclose(packed, p, rtol=0, atol=1e-15)
        assert not bad.any()


def test_pack_flags_values_outside_their_domain() -> None:
    """A zero quaternion, T <= 0: flagged per key, not silently packed."""
    tr = og.compile_problem(_rigid_body(), N=4).transcription
    values = tr.values.values_of(tr.pack())
    keys = [b.key for b in tr.values.blocks]
    for key, value in (("initial.R", 0.0), ("T", -1.0)):
        bad_values = values.copy()
        bad_values[tr.values.blocks[keys.index(key)].values] = value
        _, bad = tr.values.pack_function(bad_values)
        assert np.flatnonzero(np.array(bad).ravel()).tolist() == [keys.index(key)]
        with pytest.raises(ConfigError, match=key):
            tr.values.pack(bad_values)


def _rigid_body() -> og.Problem:
    from ocgroupoid.systems.rigid_body import rigid_body
    return rigid_body()


# ------------------------------------------------------------------ built and run


@needs_cc
def test_c_solution_matches_python(built: Built) -> None:
    """`DIR/solve` (no argument): the exported instance, same status, cost and trajectory."""
    c = c_solution(built.binary)
    assert_same(c, built.solution)
    assert c.discretization["start"] == built.solution.discretization["start"]


@needs_cc
def test_same_binary_solves_a_second_instance(built: Built, tmp_path: Path) -> None:
    """Other physical parameters and target, read from a parameter file whose quaternions
    are scaled by -2 (normalised on reading): matches Python's solve of that instance."""
    params, final = second_instance(built.tr)
    py = built.export.solver.solve(params=params, final=final)
    layout = built.tr.values
    values = layout.values_of(built.tr.pack(params=params, final=final))
    for b in layout.blocks:
        if b.kind == "rotation":
            values[b.values] *= -2.0
    path = tmp_path / "second.txt"
    path.write_text(params_text(layout, values, "second instance"))
    c = c_solution(built.binary, str(path))
    assert not np.allclose(c.p, built.solution.p)
    assert_same(c, py)


@needs_cc
def test_parameter_file_keys_default_to_the_exported_instance(built: Built,
                                                                tmp_path: Path) -> None:
    path = tmp_path / "T_only.txt"
    T = 1.25 * float(built.solution.T)
    path.write_text(f"# only the horizon\nT {T!r}\n")
    c = c_solution(built.binary, str(path))
    py = built.export.solver.solve(T=T)
    if built.tr.problem.T_free:  # T is the initial guess of the horizon the NLP solves for
        assert abs(c.T - T) > 0.1
    else:
        assert c.T == T
    assert_same(c, py)


@needs_cc
@pytest.mark.parametrize("text, message", [
    ("T 1 2\n", "T takes 1 number"),
    ("T nan\n", "'nan' is not a number (key T)"),
    ("T 1e999\n", "T: 1e999 is too large for a float (beyond 1.8e+308)"),
    ("T abc\n", "'abc' is not a number"),
    ("T -1\n", "T = -1 is outside [1e-06, 1e+06], the range of times"),
    ("bogus 1\n", "unknown key 'bogus'"),
    ("T 1\nT 2\n", "given twice"),
])
def test_driver_rejects_bad_parameter_files(built: Built, tmp_path: Path, text: str,
                                            message: str) -> None:
    path = tmp_path / "bad.txt"
    path.write_text(text)
    r = run(built.binary, str(path))
    assert r.returncode == 2, r.stdout + r.stderr
    assert message in r.stderr and r.stdout == ""


@needs_cc
def test_driver_help_and_missing_file(built: Built, tmp_path: Path) -> None:
    r = run(built.binary, "--help")
    assert r.returncode == 0 and all(b.key in r.stdout for b in built.tr.values.blocks)
    r = run(built.binary, str(tmp_path / "missing.txt"))
    assert r.returncode == 2 and "cannot open" in r.stderr


API_PROGRAM = r"""
#include <math.h>
#include <stdio.h>
#include "ocg_model.h"
#include "ocg_solver.h"

int main(void) {
  double p[OCG_NP], bad_p[OCG_NP], x[OCG_NX], values[OCG_NV];
  size_t rows, cols, i;
  int block = -1, code;
  ocg_result *r = ocg_result_new();
  if (!r) return 99;
  printf("pack %d\n", ocg_pack(ocg_default_values, OCG_NV, p, OCG_NP, NULL));
  printf("unsolved_output %d\n", ocg_output(r, OCG_X, &rows, &cols) == NULL);
  printf("short %d\n", ocg_solve(p, OCG_NP - 1, NULL, 0, r));
  printf("long %d\n", ocg_solve(p, OCG_NP + 1, NULL, 0, r));
  printf("null %d\n", ocg_solve(NULL, OCG_NP, NULL, 0, r));
  for (i = 0; i < OCG_NP; ++i) bad_p[i] = p[i];
  bad_p[0] = NAN;
  printf("nan %d\n", ocg_solve(bad_p, OCG_NP, NULL, 0, r));
  bad_p[0] = p[0];
  bad_p[OCG_P_T] = INFINITY;
  printf("inf %d\n", ocg_solve(bad_p, OCG_NP, NULL, 0, r));
  bad_p[OCG_P_T] = 0.0;
  printf("horizon %d\n", ocg_solve(bad_p, OCG_NP, NULL, 0, r));
  printf("x0_length %d\n", ocg_solve(p, OCG_NP, p, OCG_NP, r));
  for (i = 0; i < OCG_NV; ++i) values[i] = ocg_default_values[i];
  values[OCG_NV - 1] = -1.0;
  code = ocg_pack(values, OCG_NV, p, OCG_NP, &block);
  printf("pack_domain %d %d\n", code, block);
  values[OCG_NV - 1] = NAN;
  printf("pack_nan %d\n", ocg_pack(values, OCG_NV, p, OCG_NP, NULL));
  printf("pack_length %d\n", ocg_pack(values, OCG_NV - 1, p, OCG_NP, NULL));
  ocg_pack(ocg_default_values, OCG_NV, p, OCG_NP, NULL);
  printf("unsolved_after_errors %d\n", ocg_output(r, OCG_X, NULL, NULL) == NULL);
  code = ocg_solve(p, OCG_NP, NULL, 0, r);
  printf("cold %d %s %.17g %d\n", code, ocg_status_name(r), ocg_cost(r), ocg_iterations(r));
  const double *xs = ocg_output(r, OCG_X, &rows, &cols);
  printf("x_shape %zu %zu\n", rows, cols);
  for (i = 0; i < OCG_NX; ++i) x[i] = xs[i];
  x[0] = NAN;
  printf("x0_nan %d\n", ocg_solve(p, OCG_NP, x, OCG_NX, r));
  x[0] = xs[0];
  code = ocg_solve(p, OCG_NP, x, OCG_NX, r);
  printf("warm %d %s %.17g %d\n", code, ocg_status_name(r), ocg_cost(r), ocg_iterations(r));
  ocg_output(r, OCG_STATES, &rows, &cols);
  printf("states_rows %zu\n", rows);
  code = ocg_solve_warm(p, OCG_NP, r, r);
  printf("dual %d %s %.17g %d\n", code, ocg_status_name(r), ocg_cost(r), ocg_iterations(r));
  ocg_output(r, OCG_LAM_X, &rows, &cols);
  printf("lam_x_shape %zu %zu\n", rows, cols);
  ocg_result *fresh = ocg_result_new();
  printf("warm_unsolved %d\n", ocg_solve_warm(p, OCG_NP, fresh, r));
  printf("warm_null %d\n", ocg_solve_warm(p, OCG_NP, NULL, r));
  printf("warm_length %d\n", ocg_solve_warm(p, OCG_NP - 1, r, fresh));
  printf("still_solved %d\n", ocg_success(r));
  ocg_result_free(fresh);
  ocg_result_free(r);
  return 0;
}
"""


@needs_cc
def test_c_api_returns_error_codes_and_warm_starts(built: Built, tmp_path: Path) -> None:
    """Wrong lengths, NULL, NaN/Inf, T <= 0 give negative codes (no crash, the result stays
    unsolved); a warm start from the solution converges to the same cost."""
    folder = built.export.folder
    (folder / "api.c").write_text(API_PROGRAM)
    exe = make(folder, CFLAGS, target="api")
    r = run(exe)
    assert r.returncode == 0, r.stderr
    out = {line.split()[0]: line.split()[1:] for line in r.stdout.splitlines()}
    assert out["pack"] == ["0"] and out["unsolved_output"] == ["1"]
    for key, code in (("short", -2), ("long", -2), ("null", -1), ("nan", -3), ("inf", -3),
                      ("horizon", -4), ("x0_length", -2), ("pack_nan", -3),
                      ("pack_length", -2), ("x0_nan", -3)):
        assert out[key] == [str(code)], (key, out[key])
    layout = built.tr.values
    assert out["pack_domain"] == ["-4", str(len(layout.blocks) - 1)]  # the T key
    assert out["unsolved_after_errors"] == ["1"]
    py = built.solution
    assert py.status == "Solve_Succeeded", py.hint  # every exported problem file solves
    verified = str(0 if py.success else 1)  # the C verdict is Python's (at N_TEST = 16 a
    # plan may miss by more than the 1% landing tolerance: then both say so)
    code, status, cost, _ = out["cold"]
    assert (code, status) == (verified, py.status)
    assert abs(float(cost) - py.cost) <= TOL * max(1.0, abs(py.cost))
    assert out["x_shape"] == ["1", str(built.tr.nx)]
    code, status, cost, _ = out["warm"]
    assert (code, status) == (verified, "Solve_Succeeded")  # a warm start from the solution
    assert abs(float(cost) - py.cost) <= TOL * max(1.0, abs(py.cost))
    assert out["states_rows"] == [str(N_TEST + 1)]
    # a primal-dual warm start from the solution (fatrop: primal only): the same cost, in
    # no more iterations than the primal warm start
    code, status, cost, iterations = out["dual"]
    assert (code, status) == (verified, "Solve_Succeeded")
    assert abs(float(cost) - py.cost) <= TOL * max(1.0, abs(py.cost))
    assert int(iterations) <= int(out["warm"][3])
    if built.tr.backend == "ipopt":
        assert int(iterations) <= 2, out["dual"]
    assert out["lam_x_shape"] == ["1", str(built.tr.nx)]
    assert (out["warm_unsolved"], out["warm_null"], out["warm_length"]) == (["-7"], ["-1"],
                                                                             ["-2"])
    assert out["still_solved"] == ["1" if py.success else "0"]  # unchanged by the errors


@needs_cc
@pytest.mark.parametrize("built", [Case(ROOT / "problems" / f"{name}.yaml") for name in VALGRIND]
                         + [Case(ROOT / "problems" / "heavy_top_rotors.yaml", "order4"),
                            Case(ROOT / "problems" / "plate_ball.yaml", "order2", "ipopt")],
                         indirect=True, ids=[*VALGRIND, "heavy_top_rotors-order4",
                                             "plate_ball-ipopt"])
def test_valgrind_runs_the_driver_clean(built: Built, tmp_path: Path) -> None:
    """No invalid reads or writes and no definite leaks (one file per built-in model, and
    a fatrop export). BLASFEO's 4x4 kernels, inside fatrop, load whole register panels and
    read up to 3 doubles past a matrix they allocated themselves (results masked): those
    reads, and only reads whose innermost frame is in libblasfeo, are suppressed."""
    if shutil.which("valgrind") is None:
        pytest.skip("valgrind is not installed: memory check not run")
    suppressions = tmp_path / "blasfeo.supp"
    suppressions.write_text("".join(
        f"{{\n   blasfeo-panel-read-{kind}\n   Memcheck:{kind}\n   obj:*libblasfeo.so*\n"
        "   ...\n}\n" for kind in ("Addr8", "Addr16", "Addr32")))
    r = subprocess.run(["valgrind", "--error-exitcode=99", "--leak-check=full",
                        f"--suppressions={suppressions}",
                        "--errors-for-leak-kinds=definite", "--show-leak-kinds=definite",
                        str(built.binary)], capture_output=True, text=True, timeout=600)
    assert r.returncode == (0 if built.solution.success else 1), r.stderr[-4000:]
    assert "ERROR SUMMARY: 0 errors" in r.stderr
    assert json.loads(r.stdout)["status"] == built.solution.status


@needs_cc
def test_failed_solve_prints_the_json_and_exits_1(tmp_path: Path) -> None:
    """IPOPT stopped by max_iter: exit code 1, success false, the status Python reports."""
    exp = export_c(_rigid_body(), tmp_path / "fail", N=8, ipopt={"max_iter": 1}, build=True,
                   cflags=CFLAGS)
    py = exp.solver.solve()
    r = run(exp.binary)
    assert r.returncode == 1 and "solver failed: Maximum_Iterations_Exceeded" in r.stderr
    c = og.Solution.from_json(r.stdout)
    assert (c.success, c.status, c.iterations) == (False, py.status, py.iterations) \
        == (False, "Maximum_Iterations_Exceeded", 1)
    assert abs(c.cost - py.cost) <= TOL * max(1.0, abs(py.cost))


# ------------------------------------------------------------------ export API and CLI


def test_export_names_the_problem_with_the_bad_input(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="Problem or a compiled CompiledProblem"):
        export_c("so3_rest_to_rest", tmp_path)  # type: ignore[arg-type]
    with pytest.raises(ExportError, match="no libipopt in"):
        export_c(_rigid_body(), tmp_path, N=4, ipopt_lib=tmp_path)


def test_exported_folder_layout_and_parameter_file(tmp_path: Path) -> None:
    exp = export_c(_rigid_body(), tmp_path / "out", N=4)
    names = {p.name for p in exp.folder.iterdir()}
    assert {"Makefile", "README.md", "main.c", "ocg_solver.h", "ocg_solver.c",
            "ocg_ipopt_hooks.h", "ocg_generated.c", "ocg_generated.h", "ocg_model.h",
            "ocg_model.c", "params.txt"} <= names
    readme = (exp.folder / "README.md").read_text()
    assert "| `initial.R` | 4 |" in readme and "@" not in readme
    tr = exp.solver.transcription
    path = write_params(tmp_path / "p.txt", tr, tr.pack(T=3.0))
    assert "T 3  #" in path.read_text()
    assert (exp.folder / "params.txt").read_text().count("\ninitial.R ") == 1


@pytest.mark.parametrize("backend", ["ipopt", "fatrop"])
def test_what_a_solve_runs_once_is_generated_apart_and_compiled_at_opt_once(
        tmp_path: Path, backend: str) -> None:
    """The guess, the packing and the verdict's checks (with fatrop also its maps to and
    from the stage form) are in generated_once.c, which make compiles with OPT_ONCE (-Og)
    after CFLAGS; what runs at every iteration, and the read-out, stay in generated.c at OPT.
    ``make OPT_ONCE=`` compiles it as the rest."""
    if shutil.which("make") is None:
        pytest.skip("make is not installed")
    folder = export_c(_rigid_body(), tmp_path / "c", N=4, backend=backend).folder

    def defined(file: str) -> set[str]:
        text = (folder / file).read_text()
        return {n for n in ("gen_guess", "gen_pack", "gen_verify", "gen_post", "gen_nlpsol",
                            "fatrop_in", "fatrop_out", "fatrop_nlp_hess_l")
                if f"int ocg_{n}(const casadi_real** arg" in text}

    once = {"gen_guess", "gen_pack", "gen_verify"} | (
        {"fatrop_in", "fatrop_out"} if backend == "fatrop" else set())
    assert defined("ocg_generated_once.c") == once
    assert defined("ocg_generated.c") == {"gen_post", "gen_nlpsol" if backend == "ipopt"
                                          else "fatrop_nlp_hess_l"}

    def compile_lines(*args: str) -> dict[str, str]:
        out = subprocess.run(["make", "-n", "-C", str(folder), "CFLAGS=-O1", *args],
                             capture_output=True, text=True, check=True).stdout
        return {line.split(" -c ")[1].split()[0]: line for line in out.splitlines()
                if " -c " in line}

    lines = compile_lines()
    assert lines["ocg_generated_once.c"].split(" -c ")[0].endswith("-O1 -Og")
    assert all("-Og" not in line for name, line in lines.items()
               if name != "ocg_generated_once.c")
    assert "-Og" not in compile_lines("OPT_ONCE=")["ocg_generated_once.c"]


def test_a_fatrop_export_runs_the_driver_not_casadis_nlpsol(tmp_path: Path,
                                                            monkeypatch) -> None:
    """With solver.backend fatrop the export writes fatrop's driver and its tables, in time
    linear in N, and builds no fatrop nlpsol of CasADi's (whose build grows as N²): the
    solvers are the driver's, no warm twin is generated, and the README names the files."""
    import casadi as ca

    plugins: list[str] = []
    nlpsol = ca.nlpsol

    def recorded(name, plugin, *args, **kwargs):
        plugins.append(plugin)
        return nlpsol(name, plugin, *args, **kwargs)

    monkeypatch.setattr(ca, "nlpsol", recorded)
    exp = export_c(_rigid_body(), tmp_path / "c", N=4, backend="fatrop")
    assert exp.solver.transcription.backend == "fatrop"
    assert "fatrop" not in plugins and "ipopt" in plugins  # IPOPT: the Python fallback's
    names = {p.name for p in exp.folder.iterdir()}
    assert {"ocg_fatrop_solver.c", "ocg_fatrop_solver.h", "ocg_fatrop_ocp.c",
            "ocg_fatrop_ocp.h", "ocg_fatrop_guard.c", "ocg_fatrop_guard.h"} <= names
    assert not any("generated_warm" in n for n in names)
    driver = (exp.folder / "ocg_fatrop_ocp.c").read_text()
    assert '#include "ocg_fatrop_ocp.h"' in driver and "void ocg_fatrop_solve(" in driver
    readme = (exp.folder / "README.md").read_text()
    assert "`ocg_fatrop_solver.c/.h`" in readme and "generated_warm" not in readme
    assert "@" not in readme
    makefile = (exp.folder / "Makefile").read_text()
    assert "ocg_fatrop_ocp.o" in makefile and "generated_warm" not in makefile


def test_a_fatrop_export_refuses_options_c_cannot_hold(tmp_path: Path) -> None:
    """A non-finite fatrop option would be no C literal: the export says which, and how."""
    with pytest.raises(ExportError, match="fatrop's option tol_acceptable = inf"):
        export_c(og.compile_problem(_rigid_body(), N=4, backend="fatrop",
                                    fatrop={"tol_acceptable": float("inf")}),
                 tmp_path / "c")


@needs_cc
def test_cli_export_c_builds_a_runnable_solver(tmp_path: Path) -> None:
    out = tmp_path / "so3"
    r = CliRunner().invoke(app, ["export-c", str(ROOT / "problems" / "so3_rest_to_rest.yaml"),
                                 "--out", str(out), "--set", "horizon.N=16", "--build"])
    assert r.exit_code == 0, r.output
    assert "exported to" in r.output and (out / "solve").is_file()
    sol = c_solution(out / "solve")
    assert sol.success and sol.N == 16


def test_cli_export_c_reports_bad_files(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text((ROOT / "problems" / "so3_rest_to_rest.yaml").read_text()
                   .replace("model: rigid_body", "model: rigid_bodyy"))
    r = CliRunner().invoke(app, ["export-c", str(bad), "--out", str(tmp_path / "x")])
    assert r.exit_code == 2 and "unknown model" in r.output
