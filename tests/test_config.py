"""Problem files: every bad input is refused with the key, the line and the fix (issue 5)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.cli import app
from ocgroupoid.solve.solution import write_atomic
from ocgroupoid.systems.rigid_body import rigid_body

ROOT = Path(__file__).resolve().parent.parent
runner = CliRunner()

BASE = """\
model: rigid_body
parameters:
  inertia: [1.0, 2.0, 3.0]
horizon:
  T: 5.0
  N: 16
initial:
  R: identity
  Omega: [0.0, 0.0, 0.0]
final:
  R: {rotvec: [0.1, 0.2, 0.3]}
  Omega: [0.0, 0.0, 0.0]
discretization:
  retraction: cayley
"""

CUSTOM = (ROOT / "problems" / "custom_rigid_body.yaml").read_text()


def edited(line: int, text: str | None) -> str:
    """BASE with 1-based ``line`` replaced (None: removed)."""
    lines = BASE.splitlines()
    if text is None:
        del lines[line - 1]
    else:
        lines[line - 1] = text
    return "\n".join(lines) + "\n"


def refused(tmp_path: Path, content: str | bytes, *expected: str) -> str:
    f = tmp_path / "p.yaml"
    f.write_bytes(content if isinstance(content, bytes) else content.encode())
    r = runner.invoke(app, ["solve", str(f)])
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output
    assert r.exception is None or isinstance(r.exception, SystemExit)
    text = " ".join(r.output.split())
    for e in expected:
        assert e in text, f"{e!r} not in {text!r}"
    return text


CASES = {
    "unknown key": (edited(14, "  retractoin: cayley"),
                    ["p.yaml:14", "discretization.retractoin", "did you mean 'retraction'"]),
    "wrong type": (edited(5, "  T: five"), ["p.yaml:5", "horizon.T", "must be a number"]),
    "wrong type of section": (BASE.replace("horizon:\n  T: 5.0\n  N: 16\n", "horizon: 5\n"),
                              ["p.yaml:4", "horizon must be a mapping"]),
    "missing key": (edited(5, None), ["p.yaml:4", "missing key 'horizon.T'", "add it"]),
    "N < 2": (edited(6, "  N: 1"), ["p.yaml:6", "horizon.N must be >= 2", "raise it"]),
    "N not an integer": (edited(6, "  N: 16.5"), ["p.yaml:6", "horizon.N must be an integer"]),
    "T <= 0": (edited(5, "  T: -1.0"), ["p.yaml:5", "horizon.T", "T must be > 0"]),
    "NaN": (edited(3, "  inertia: [1.0, .nan, 3.0]"),
            ["p.yaml:3", "parameters.inertia", "component 1 must be finite"]),
    "inf": (edited(5, "  T: .inf"), ["p.yaml:5", "horizon.T", "T must be finite"]),
    "not a rotation": (edited(11, "  R: {matrix: [[1, 0, 0], [0, 1, 0], [0, 0, -1]]}"),
                       ["p.yaml:11", "final.R", "not a rotation",
                        "give an orthonormal matrix with det +1"]),
    "zero axis": (edited(11, "  R: {axis_angle: {axis: [0, 0, 0], angle: 1.0}}"),
                  ["p.yaml:11", "final.R", "axis is zero", "give a nonzero axis"]),
    "unknown rotation form": (edited(11, "  R: {rotvek: [0, 0, 1]}"),
                              ["p.yaml:11", "did you mean 'rotvec'"]),
    "unknown retraction": (edited(14, "  retraction: cayly"),
                           ["p.yaml:14", "discretization.retraction", "did you mean 'cayley'",
                            "cayley, exp, first_order"]),
    "unknown model": (edited(1, "model: rigid"), ["p.yaml:1", "did you mean 'rigid_body'"]),
    "invalid YAML": ("model: rigid_body\nhorizon: [unclosed\n",
                     ["p.yaml:3", "invalid YAML", "check indentation"]),
    "empty file": ("", ["empty", "model and horizon"]),
    "comment only": ("# nothing here\n", ["empty"]),
    "binary file": (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", ["binary file", ".yaml"]),
    "not a mapping": ("- 1\n- 2\n", ["top level must be a mapping"]),
}


@pytest.mark.parametrize("case", list(CASES))
def test_bad_input_names_key_line_and_fix(tmp_path, case: str) -> None:
    content, expected = CASES[case]
    refused(tmp_path, content, *expected)


def custom_with(key: str, value: str) -> str:
    lines = []
    for line in CUSTOM.splitlines():
        if line.strip().startswith(f"{key}:"):
            indent = line[: len(line) - len(line.lstrip())]
            line = f'{indent}{key}: "{value}"'
        lines.append(line)
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("key, value, expected", [
    ("lagrangian", "__import__('os').system('true')", "never allowed"),
    ("lagrangian", "Omega.T @ Omega", "attribute access '.T' is not allowed"),
    ("cost", "0.5 * dot(w, w)", "unknown name 'w'"),
    ("cost", "0.5 * dot(uu, u)", "did you mean 'u'"),
    ("cost", "[x for x in u]", "ListComp is not allowed"),
    ("cost", "open('f')", "'open' is not an allowed function"),
])
def test_forbidden_expressions_are_named(tmp_path, key: str, value: str, expected: str) -> None:
    text = custom_with(key, value)
    line = next(i + 1 for i, ln in enumerate(text.splitlines()) if ln.strip().startswith(key))
    refused(tmp_path, text, f"p.yaml:{line}", f"definition.{key}", expected)


def test_custom_rigid_body_reproduces_the_built_in() -> None:
    cfg = files.load(ROOT / "problems" / "custom_rigid_body.yaml")
    custom = og.solve(files.build(cfg), N=64)
    builtin = og.solve(rigid_body(), N=64)
    assert custom.success and builtin.success
    assert abs(custom.cost - builtin.cost) <= 1e-10
    assert custom.control_names == ["u1", "u2", "u3"]


def test_definition_only_for_custom(tmp_path) -> None:
    refused(tmp_path, BASE + "definition: {cost: '1'}\n",
            "definition is only read for model: custom")


def test_custom_without_definition(tmp_path) -> None:
    refused(tmp_path, edited(1, "model: custom"), "needs a definition section")


def test_set_errors_say_they_come_from_set(tmp_path) -> None:
    f = tmp_path / "p.yaml"
    f.write_text(BASE)
    r = runner.invoke(app, ["solve", str(f), "--set", "horizon.N=1"])
    assert r.exit_code == 2 and "--set horizon.N" in " ".join(r.output.split())
    r = runner.invoke(app, ["solve", str(f), "--set", "horizon.N"])
    assert r.exit_code == 2 and "expected KEY=VALUE" in r.output


def test_atomic_write_keeps_the_old_file_when_interrupted(tmp_path, monkeypatch) -> None:
    target = tmp_path / "sol.json"
    write_atomic(target, "good\n")

    def interrupted(src: str, dst: str) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_atomic(target, "garbage")
    assert target.read_text() == "good\n"
    assert [p.name for p in tmp_path.iterdir()] == ["sol.json"]


def test_set_overrides_lists_and_nested_keys(tmp_path) -> None:
    cfg = files.load(ROOT / "problems" / "so3_rest_to_rest.yaml",
                      ["parameters.inertia=[2, 1.5, 0.8]", "solver.ipopt.max_iter=50",
                       "final.Omega=[0, 0, null]", "name=renamed"])
    assert cfg.parameters.inertia == [2.0, 1.5, 0.8]
    assert cfg.file.solver.ipopt["max_iter"] == 50
    assert cfg.final.Omega == [0.0, 0.0, None]
    assert files.build(cfg).name == "renamed"
