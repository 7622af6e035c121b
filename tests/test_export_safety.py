"""`export-c` is safe to point anywhere (issue 19, item 8 and item 1's Makefile note): it
refuses a folder holding files it did not write (unless --force), writes every file
atomically, pastes any problem name into the Makefile, the C sources and the README without
letting it run anything, and the exported driver validates its parameter file as Python
validates problem files (same ranges, same messages, exit code 2)."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.cli import app
from ocgroupoid.errors import ConfigError, ExportError
from ocgroupoid.export import codegen
from ocgroupoid.export.codegen import (
    EXPORT_IPOPT,
    MANIFEST,
    export_c,
    plain_name,
    positive_parameters,
)
from ocgroupoid.export.literals import c_ints, c_string
from ocgroupoid.files import source
from ocgroupoid.systems import MODELS
from ocgroupoid.systems.rigid_body import rigid_body

ROOT = Path(__file__).resolve().parent.parent
SO3 = ROOT / "problems" / "so3_rest_to_rest.yaml"
from .cbuild import CFLAGS  # noqa: E402

runner = CliRunner()
# A name as hostile as a file name or a `name:` key can make it: a line break and a make
# assignment that runs a command, a comment end, quotes, a trigraph, a placeholder, a
# backslash at the end, non-ASCII.
EVIL = 'slew\nX := $(shell touch {canary}) */ "q" ??/ @N@ #ü\\'

needs_cc = pytest.mark.skipif(shutil.which("cc") is None or shutil.which("make") is None,
                              reason="no C compiler (cc) or make on PATH")


def one_line(text: str) -> str:
    return " ".join(text.split())


def so3_solver(N: int = 4, name: str | None = None) -> og.CompiledProblem:
    """The rigid-body slew compiled for export; ``name`` is set afterwards (the compiled
    Functions keep their own safe names: only the export sees it)."""
    solver = og.compile_problem(rigid_body(), N=N, ipopt=EXPORT_IPOPT)
    if name is not None:
        solver.transcription.problem.name = name
    return solver


@pytest.fixture(scope="module")
def evil(tmp_path_factory) -> tuple[codegen.Export, Path, str]:
    """One export with the hostile name, built with -Werror (the only compile here)."""
    if shutil.which("cc") is None or shutil.which("make") is None:
        pytest.skip("no C compiler (cc) or make on PATH")
    root = tmp_path_factory.mktemp("evil")
    canary = root / "pwned"
    name = EVIL.format(canary=canary)
    exp = export_c(so3_solver(N=16, name=name), root / "c", build=True, cflags=CFLAGS,
                   positive=positive_parameters(MODELS["rigid_body"].parameters))
    return exp, canary, name


def run(binary: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([str(binary), *args], capture_output=True, text=True, timeout=120)


# ------------------------------------------------------------------ the folder


def test_export_c_refuses_a_folder_it_did_not_write(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    for name in ("README.md", "Makefile", "main.c"):
        (out / name).write_text(f"my own {name}\n")
    r = runner.invoke(app, ["export-c", str(SO3), "--out", str(out), "--set", "horizon.N=4"])
    assert r.exit_code == 2, r.output
    text = one_line(r.output)
    assert "not written by export-c" in text and "--force" in text and "README.md" in text
    for name in ("README.md", "Makefile", "main.c"):
        assert (out / name).read_text() == f"my own {name}\n"
    assert sorted(p.name for p in out.iterdir()) == ["Makefile", "README.md", "main.c"]
    with pytest.raises(ExportError, match="not written by export-c"):
        export_c(rigid_body(), out, N=4)


def test_export_c_force_overwrites_and_a_file_is_not_a_folder(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "README.md").write_text("mine\n")
    r = runner.invoke(app, ["export-c", str(SO3), "--out", str(out), "--set", "horizon.N=4",
                            "--force"])
    assert r.exit_code == 0, r.output
    assert "exported C solver" in (out / "README.md").read_text()
    regular = tmp_path / "regular"
    regular.write_text("x")
    for target in (regular, regular / "sub"):
        r = runner.invoke(app, ["export-c", str(SO3), "--out", str(target)])
        assert r.exit_code == 2 and "is a file, not a folder" in one_line(r.output), r.output


def test_export_c_rewrites_its_own_export_but_not_edits(tmp_path: Path) -> None:
    """An earlier export is overwritten without --force; the user's own files next to it
    stay; a file edited since the export is refused (the message names it)."""
    out = tmp_path / "out"
    export_c(so3_solver(), out)
    (out / "api.c").write_text("/* mine */\n")
    (out / "solve").write_bytes(b"a build product")
    before = json.loads((out / MANIFEST).read_text())["files"]
    export_c(so3_solver(N=6), out)
    assert "N=6" in (out / "Makefile").read_text().splitlines()[0]
    assert (out / "api.c").read_text() == "/* mine */\n" and (out / "solve").exists()
    assert set(json.loads((out / MANIFEST).read_text())["files"]) == set(before)
    (out / "params.txt").write_text("T 2\n")
    with pytest.raises(ExportError, match="params.txt was changed since export-c wrote it"):
        export_c(so3_solver(), out)
    assert (out / "params.txt").read_text() == "T 2\n"
    export_c(so3_solver(), out, force=True)
    assert (out / "params.txt").read_text() != "T 2\n"


def test_export_c_writes_each_file_atomically(tmp_path: Path, monkeypatch) -> None:
    """A failure in the middle leaves whole files (old or new), no temporary file, and a
    folder the next export accepts."""
    out = tmp_path / "out"
    export_c(so3_solver(), out)
    old = {p.name: p.read_bytes() for p in out.iterdir()}
    calls = []
    real = codegen.write_atomic

    def failing(path, data):
        calls.append(Path(path).name)
        if len(calls) == 5:
            raise OSError(28, "No space left on device")
        real(path, data)

    monkeypatch.setattr(codegen, "write_atomic", failing)
    with pytest.raises(OSError, match="No space"):
        export_c(so3_solver(N=6), out)
    monkeypatch.undo()
    assert sorted(p.name for p in out.iterdir()) == sorted(old)  # no .NAME.PID.XXXX left
    changed = [name for name in old if (out / name).read_bytes() != old[name]]
    assert changed and len(changed) < len(old) - 1
    assert calls[0] == MANIFEST  # recorded before the files: the next export accepts them
    export_c(so3_solver(N=6), out)
    assert "N=6" in (out / "Makefile").read_text().splitlines()[0]


def test_export_c_checks_its_folder_before_compiling(tmp_path: Path, monkeypatch) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")

    def no_compile(*args, **kwargs):
        raise AssertionError("compiled before the folder was checked")

    monkeypatch.setattr(codegen.CompiledProblem, "__init__", no_compile)
    with pytest.raises(ExportError, match="not written by export-c"):
        export_c(rigid_body(), out, N=4)


# ------------------------------------------------------------------ names


def test_names_are_escaped_for_c_and_reduced_for_comments() -> None:
    assert c_string('a"b\\c\n??/ü') == '"a\\"b\\\\c\\012\\?\\?/\\303\\274"'
    plain = plain_name("x\n$(shell rm -rf ~) */ #\\")
    assert "\n" not in plain and "$" not in plain and "*/" not in plain
    assert "\\" not in plain and "#" not in plain
    assert codegen._fill("@A@ @B@", {"A": "@B@", "B": "b"}) == "@B@ b"


def test_long_int_arrays_are_wrapped_and_never_empty() -> None:
    """C has no empty initializer; a long one is 16 numbers a line."""
    assert c_ints(np.array([], dtype=int)) == "0"
    text = c_ints(np.arange(40))
    lines = text.split("\n")
    assert len(lines) == 3 and lines[0].count(",") == 16
    assert [int(v) for v in text.replace("\n", "").split(",")] == list(range(40))


@needs_cc
def test_a_hostile_name_runs_nothing_at_make_and_survives_to_the_json(evil) -> None:
    exp, canary, name = evil
    folder = exp.folder
    r = subprocess.run(["make", "-C", str(folder), "clean", "all"], capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    assert not canary.exists()
    first = (folder / "Makefile").read_text().splitlines()[0]
    assert first.startswith("# Exported by") and "shell" in first and "$" not in first
    for text_file in ("README.md", "params.txt", "ocg_model.c"):
        assert "$(shell" not in (folder / text_file).read_text(), text_file
    inside = [ln for ln in (folder / "ocg_model.h").read_text().splitlines() if "shell" in ln]
    assert len(inside) == 2 and inside[0].startswith("/* Generated") and "$" not in inside[0]
    assert inside[1].startswith('#define OCG_PROBLEM "slew\\012X := $(shell')  # a C string
    c = run(exp.binary)
    assert c.returncode == 0, c.stderr
    assert json.loads(c.stdout)["problem"] == name


# ------------------------------------------------------------------ the driver


def python_message(override: str) -> str:
    """The message the problem files give for ``--set override``, after the key's section."""
    with pytest.raises(ConfigError) as err:
        files.load(SO3, [override])
    return str(err.value).rsplit("parameters.", 1)[1]


@needs_cc
@pytest.mark.parametrize("numbers, override", [
    ("1 0 3", "parameters.inertia=[1, 0, 3]"),
    ("-1 2 3", "parameters.inertia=[-1, 2, 3]"),
    ("1 2 -2.5e-3", "parameters.inertia=[1, 2, -2.5e-3]"),
])
def test_driver_refuses_inertia_outside_the_python_range(evil, tmp_path: Path, numbers: str,
                                                         override: str) -> None:
    exp = evil[0]
    path = tmp_path / "p.txt"
    path.write_text(f"# inertia as a parameter file\ninertia {numbers}\n")
    r = run(exp.binary, str(path))
    expected = python_message(override)  # e.g. "inertia: component 1 must be > 0, got 0.0"
    assert r.returncode == 2 and r.stdout == "", r.stderr
    assert f"{path}:2: {expected}" in r.stderr, (r.stderr, expected)


def yaml_refusal(literal: str) -> str:
    """What the problem files say of a number literal a double does not hold, after it."""
    with pytest.raises(source.Refusal) as err:
        source.parse_yaml(f"x: {literal}")
    return err.value.message.split(literal, 1)[1]


@needs_cc
@pytest.mark.parametrize("text, key, literal, yaml", [
    ("inertia 1 2 1e-400\n", "inertia", "1e-400", "1.0e-400"),
    ("T 1e-320\n", "T", "1e-320", "1.0e-320"),
    ("T 4.9e-324\n", "T", "4.9e-324", "4.9e-324"),  # a double, but a subnormal one
    ("T 1e400\n", "T", "1e400", "1.0e+400"),
    ("inertia 1 2 -1e400\n", "inertia", "-1e400", "-1.0e+400"),
])
def test_driver_refuses_numbers_a_double_does_not_hold(evil, tmp_path: Path, text: str,
                                                       key: str, literal: str,
                                                       yaml: str) -> None:
    """With the problem files' message (issue 30, item 7: 4.9e-324 was "an underflow")."""
    path = tmp_path / "p.txt"
    path.write_text(text)
    r = run(evil[0].binary, str(path))
    assert r.returncode == 2 and r.stdout == "", r.stderr
    assert f"{path}:1: {key}: {literal}{yaml_refusal(yaml)}" in r.stderr, r.stderr


@needs_cc
def test_driver_refuses_a_folder_as_its_parameter_file(evil, tmp_path: Path) -> None:
    r = run(evil[0].binary, str(tmp_path))
    assert r.returncode == 2 and r.stdout == "", r.stderr
    assert f"{tmp_path} is a folder; give a parameter file" in r.stderr
    good = tmp_path / "p.txt"
    good.write_text("inertia 1.5 2 3.25\n")  # positive inertias still solve
    assert run(evil[0].binary, str(good)).returncode == 0


def test_cli_export_carries_the_model_ranges_into_the_driver(tmp_path: Path) -> None:
    """`export-c` flags the parameters the model's schema requires positive."""
    assert positive_parameters(MODELS["rigid_body"].parameters) == ["inertia"]
    assert positive_parameters(MODELS["heavy_top"].parameters) == ["Ibar", "J"]
    assert positive_parameters(MODELS["plate_ball"].parameters) == ["r"]
    out = tmp_path / "out"
    r = runner.invoke(app, ["export-c", str(SO3), "--out", str(out), "--set", "horizon.N=4"])
    assert r.exit_code == 0, r.output
    source = (out / "ocg_model.c").read_text()
    assert '{"inertia", 0, 3, "principal moments of inertia", 1}' in source
    assert '{"T", ' in source and source.count(", 1}") == 1
    with pytest.raises(ConfigError, match="not parameters of"):
        export_c(so3_solver(), tmp_path / "other", positive=["mass"])
