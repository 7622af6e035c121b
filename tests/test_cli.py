"""The command line on the shipped problem files."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ocgroupoid.cli import app

ROOT = Path(__file__).resolve().parent.parent
SO3 = ROOT / "problems" / "so3_rest_to_rest.yaml"
runner = CliRunner()


def test_python_m_solves_the_canonical_problem(tmp_path) -> None:
    out = tmp_path / "sol.json"
    r = subprocess.run([sys.executable, "-m", "ocgroupoid", "solve", str(SO3), "--set",
                        "horizon.N=32", "--out", str(out)], capture_output=True, text=True,
                       cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    for word in ("Solve_Succeeded", "cost", "iterations", "build time", "solve time"):
        assert word in r.stdout
    sol = json.loads(out.read_text())
    assert sol["success"] and sol["N"] == 32 and sol["T"] == 5.0
    assert {"problem", "status", "cost", "stats", "controls", "states", "multipliers",
            "diagnostics"} <= set(sol)
    assert len(sol["controls"]["t"]) == len(sol["controls"]["u"]) == 33


def test_set_overrides_nested_keys_and_rotations(tmp_path) -> None:
    out = tmp_path / "sol.json"
    r = runner.invoke(app, ["solve", str(SO3), "-q", "--set", "horizon.N=24", "--set",
                            "final.R={rotvec: [0, 0, 1]}", "--set",
                            "parameters.inertia=[2, 1.5, 0.8]", "--out", str(out)])
    assert r.exit_code == 0, r.output
    sol = json.loads(out.read_text())
    assert sol["N"] == 24 and sol["parameters"]["inertia"] == [2.0, 1.5, 0.8]
    assert abs(sol["states"]["R"][-1][0][1] + 0.8414709848) < 1e-6


def test_bad_input_exits_2_without_traceback(tmp_path) -> None:
    r = runner.invoke(app, ["solve", str(SO3), "--set", "horizon.N=1"])
    assert r.exit_code == 2
    assert "horizon.N" in r.output and "Traceback" not in r.output


@pytest.mark.parametrize("content, message", [
    ("", "empty"),
    ("model: [unclosed", "invalid YAML"),
])
def test_unreadable_files(tmp_path, content: str, message: str) -> None:
    f = tmp_path / "p.yaml"
    f.write_text(content)
    r = runner.invoke(app, ["solve", str(f)])
    assert r.exit_code == 2 and message in r.output


def test_list_names_the_models() -> None:
    r = runner.invoke(app, ["list"])
    assert r.exit_code == 0 and "rigid_body" in r.output
