"""The command line: every shipped problem file checks and solves; exit codes (issue 5)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid.cli import app
from ocgroupoid.systems.rigid_body import rigid_body

ROOT = Path(__file__).resolve().parent.parent
SO3 = ROOT / "problems" / "so3_rest_to_rest.yaml"
PROBLEMS = sorted((ROOT / "problems").glob("*.yaml"))
runner = CliRunner()

INFEASIBLE = """\
model: custom
definition:
  order: 1
  groupoid: [{type: pair, dim: 2, state: p, velocity: v}]
  cost: "0.5 * dot(v, v)"
  constraints: {on_circle: "dot(p, p) - 1"}     # stay on the unit circle ...
  controls: {vx: "v[0]", vy: "v[1]"}
horizon: {T: 1.0, N: 16}
initial: {p: [1.0, 0.0]}
final: {p: [2.0, 0.0]}                          # ... and end off it
"""


@pytest.mark.parametrize("problem", PROBLEMS, ids=lambda p: p.stem)
def test_every_problem_file_checks_and_solves(problem: Path, tmp_path) -> None:
    r = runner.invoke(app, ["check", str(problem)])
    assert r.exit_code == 0, r.output
    assert "degrees of freedom" in r.output and "redundant" in r.output
    out = tmp_path / "sol.json"
    r = runner.invoke(app, ["solve", str(problem), "--out", str(out)])
    assert r.exit_code == 0, r.output
    sol = json.loads(out.read_text())
    assert sol["success"] and sol["status"] == "Solve_Succeeded"
    assert sol["diagnostics"]["euler_lagrange_residual_max"] <= 1e-8


def test_python_m_solves_the_canonical_problem(tmp_path) -> None:
    out = tmp_path / "sol.json"
    r = subprocess.run([sys.executable, "-m", "ocgroupoid", "solve", str(SO3), "--out",
                        str(out)], capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    for word in ("Solve_Succeeded", "cost", "iterations", "build time",
                 "solver time, this solution", "(ipopt)", "solver time, every run",
                 "5 starts",
                 "EL residual", "replay terminal error"):
        assert word in r.stdout
    sol = json.loads(out.read_text())
    assert sol["success"] and sol["N"] == 64 and sol["T"] == 5.0
    assert {"problem", "status", "cost", "stats", "controls", "states", "multipliers",
            "diagnostics"} <= set(sol)
    # the default scheme (order4): the control at the nodes and at both Gauss points
    assert sol["discretization"]["scheme"] == "order4"
    assert len(sol["controls"]["t"]) == len(sol["controls"]["u"]) == 3 * 64 + 1
    # the first solve of a fresh clone lands within 1e-6 rad (issue 29; order2 missed by 7e-4)
    assert sol["diagnostics"]["replay"]["max_terminal_error"] <= 1e-6


def test_resolve_with_changed_inertia_matches_the_api(tmp_path) -> None:
    costs = {}
    changed = ["--set", "parameters.inertia=[2, 1.5, 0.8]"]
    for label, extra in (("default", []), ("changed", changed)):
        out = tmp_path / f"{label}.json"
        r = runner.invoke(app, ["solve", str(SO3), "-q", "--set", "horizon.N=24", "--set",
                                "final.R={rotvec: [0.5, -0.4, 1.0]}", "--set",
                                "solver.multistart=false",  # one start, as og.solve's default
                                *extra, "--out", str(out)])
        assert r.exit_code == 0, r.output
        costs[label] = json.loads(out.read_text())
    changed = costs["changed"]
    assert changed["N"] == 24 and changed["parameters"]["inertia"] == [2.0, 1.5, 0.8]
    target = og.so3.from_rotvec([0.5, -0.4, 1.0])
    assert np.allclose(changed["states"]["R"][-1], target, atol=1e-9)
    api = og.solve(rigid_body(inertia=[2.0, 1.5, 0.8], RT=target), N=24, scheme="order4").cost
    assert abs(changed["cost"] - api) <= 1e-10 * api
    assert abs(changed["cost"] - costs["default"]["cost"]) > 1e-3 * changed["cost"]


def test_infeasible_problem_exits_1_and_writes_failure(tmp_path) -> None:
    f = tmp_path / "infeasible.yaml"
    f.write_text(INFEASIBLE)
    out = tmp_path / "sol.json"
    r = runner.invoke(app, ["solve", str(f), "--out", str(out), "--set",
                            "solver.multistart=false", "--set", "discretization.scheme=order2"])
    assert r.exit_code == 1
    text = " ".join(r.output.split())
    assert "Infeasible_Problem_Detected" in text and "ocgroupoid check" in text
    sol = json.loads(out.read_text())
    assert sol["success"] is False and sol["status"] == "Infeasible_Problem_Detected"
    assert sol["hint"]


def test_infeasible_problem_is_not_verified_by_a_perturbed_start(tmp_path) -> None:
    """Multi-start (the default) meets a zigzag whose midpoints alone stay on the circle: IPOPT
    solves that discrete artefact, the verdict catches it (exit 1, success false)."""
    f = tmp_path / "infeasible.yaml"
    f.write_text(INFEASIBLE)
    out = tmp_path / "sol.json"
    r = runner.invoke(app, ["solve", str(f), "--out", str(out)])
    assert r.exit_code == 1
    sol = json.loads(out.read_text())
    assert sol["success"] is False
    assert "check the final values" in sol["hint"]


def test_check_names_a_redundant_boundary_condition(tmp_path) -> None:
    f = tmp_path / "redundant.yaml"
    f.write_text(INFEASIBLE.replace('{on_circle: "dot(p, p) - 1"}', '{stopped: "v"}')
                 .replace("final: {p: [2.0, 0.0]}", "final: {p: [1.0, 0.0]}"))
    r = runner.invoke(app, ["check", str(f)])
    assert r.exit_code == 2
    assert "final.p" in " ".join(r.output.split()) and "redundant" in r.output


def test_check_names_a_condition_implied_only_on_the_feasible_set() -> None:
    """Issue 15: with zero total momentum Omega(T) = 0 implies dphi(T) = 0; at a generic
    point the rows are independent ("redundant: none" before), at a short solve they are not."""
    wheels = SO3.parent / "reaction_wheels.yaml"
    r = runner.invoke(app, ["check", str(wheels), "--set", "final.dphi=[0, 0, 0]"])
    assert r.exit_code == 2
    text = " ".join(r.output.split())
    assert "final.dphi is implied by" in text and "final.Omega" in text
    clean = runner.invoke(app, ["check", str(wheels)])
    assert clean.exit_code == 0 and "redundant" in clean.output and "implied" not in clean.output


def test_plot_writes_a_png(tmp_path) -> None:
    out = tmp_path / "sol.json"
    assert runner.invoke(app, ["solve", str(SO3), "-q", "--set", "horizon.N=16", "--out",
                               str(out)]).exit_code == 0
    png = tmp_path / "fig.png"
    r = runner.invoke(app, ["plot", str(out), "--out", str(png)])
    assert r.exit_code == 0 and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    r = runner.invoke(app, ["plot", str(tmp_path / "missing.json"), "--out", str(png)])
    assert r.exit_code == 2 and "no such file" in r.output
    (tmp_path / "bad.json").write_text("{not json")
    r = runner.invoke(app, ["plot", str(tmp_path / "bad.json"), "--out", str(png)])
    assert r.exit_code == 2 and "not a solution file" in r.output


HELP = {  # each command's help names what it does and every option it takes
    "solve": ["problem file", "--set", "--out", "--plot", "--quiet"],
    "check": ["no solve", "--set"],
    "plot": ["solution JSON", "--out"],
    "list": ["models", "schemes"],
    "export-c": ["C project", "--out", "--build", "--set", "--cflags"],
}


@pytest.mark.parametrize("command", list(HELP))
def test_every_command_documents_its_options(command: str) -> None:
    r = runner.invoke(app, [command, "--help"], terminal_width=200)
    assert r.exit_code == 0, r.output
    text = " ".join(r.output.split())
    for word in HELP[command]:
        assert word in text, (command, word)


def test_top_level_help_lists_every_command() -> None:
    r = runner.invoke(app, ["--help"], terminal_width=200)
    assert r.exit_code == 0 and all(c in r.output for c in HELP)


def test_list_names_the_models_schemes_and_problem_files(monkeypatch) -> None:
    from ocgroupoid.nlp.schemes import SCHEME_NAMES
    from ocgroupoid.systems import MODELS

    monkeypatch.chdir(ROOT)
    r = runner.invoke(app, ["list"], terminal_width=200)
    assert r.exit_code == 0
    for name in [*MODELS, *SCHEME_NAMES, "cayley", "first_order", *(p.name for p in PROBLEMS)]:
        assert name in r.output, name
