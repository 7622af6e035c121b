"""Writers and the command line's edges (issues 15 and 19): output files get the umask's mode,
temporary files left by a killed writer are cleaned, every output path is checked before
anything is solved (exit 2 and one line, never a traceback), `list` and `check` say what
applies, and Ctrl-C while the command starts is one line and exit code 130."""

from __future__ import annotations

import importlib
import os
import re
import signal
import stat
import subprocess
import sys
import sysconfig
import tempfile
import textwrap
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ocgroupoid.cli import app, listing
from ocgroupoid.errors import ConfigError
from ocgroupoid.solve.outputs import check_file, check_folder, remove_stale_temporaries
from ocgroupoid.solve.solution import write_atomic

ROOT = Path(__file__).resolve().parent.parent
SO3 = ROOT / "problems" / "so3_rest_to_rest.yaml"
CART_POLE = ROOT / "problems" / "cart_pole.yaml"
PROBLEMS = sorted((ROOT / "problems").glob("*.yaml"))
runner = CliRunner()


def one_line(text: str) -> str:
    return " ".join(text.split())


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def unwritable_folder(tmp_path: Path) -> Path:
    """A folder in which creating a file fails, even for root (/sys), or skip."""
    candidates = [Path("/sys")] if os.geteuid() == 0 else []
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    candidates.append(locked)
    for folder in candidates:
        try:
            fd, tmp = tempfile.mkstemp(dir=folder)
        except OSError:
            return folder
        os.close(fd)
        os.unlink(tmp)
    pytest.skip("no folder here refuses new files")


# ------------------------------------------------------------------ write_atomic


@pytest.mark.parametrize("mask", [0o022, 0o002, 0o077])
def test_write_atomic_gives_new_files_the_umask_mode(tmp_path: Path, mask: int) -> None:
    old = os.umask(mask)
    try:
        write_atomic(tmp_path / "sol.json", "{}\n")
        plain = tmp_path / "plain.json"
        plain.write_text("{}\n")
    finally:
        os.umask(old)
    mode = stat.S_IMODE((tmp_path / "sol.json").stat().st_mode)
    assert mode == 0o666 & ~mask == stat.S_IMODE(plain.stat().st_mode), oct(mode)


def test_write_atomic_keeps_the_mode_of_the_file_it_replaces(tmp_path: Path, umask_022) -> None:
    target = tmp_path / "sol.json"
    target.write_text("old\n")
    target.chmod(0o640)
    write_atomic(target, "new\n")
    assert target.read_text() == "new\n" and stat.S_IMODE(target.stat().st_mode) == 0o640


KILLED_WRITER = textwrap.dedent("""\
    import os, sys, time
    from ocgroupoid.solve import outputs
    def stuck(fd):
        print("writing", flush=True)
        time.sleep(60)
    outputs.os.fsync = stuck
    outputs.write_atomic(sys.argv[1], "half")
""")


def test_temporary_files_of_a_killed_writer_are_removed_by_the_next_write(
        tmp_path: Path) -> None:
    """SIGKILL in the middle of a write leaves `.sol.json.PID.XXXXXXXX`: the next write to
    sol.json removes it; the old file is untouched meanwhile; other files stay."""
    target = tmp_path / "sol.json"
    write_atomic(target, "old\n")
    (tmp_path / ".other.json.12345.abcdefgh").write_text("not ours to clean")
    proc = subprocess.Popen([sys.executable, "-c", KILLED_WRITER, str(target)],
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None and proc.stdout.readline().strip() == "writing"
    proc.kill()
    proc.wait()
    left = [p.name for p in tmp_path.iterdir() if p.name.startswith(".sol.json.")]
    assert len(left) == 1 and f".{proc.pid}." in left[0], left
    assert target.read_text() == "old\n"
    write_atomic(target, "new\n")
    assert target.read_text() == "new\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == [".other.json.12345.abcdefgh",
                                                          "sol.json"]


def test_stale_temporaries_of_earlier_versions_go_and_live_writers_stay(tmp_path: Path) -> None:
    target = tmp_path / "sol.json"
    old_style = tmp_path / ".sol.json.k3j_a9xz"  # mkstemp's name before the PID was in it
    live = tmp_path / f".sol.json.{os.getppid()}.abcdefgh"  # a process that is running
    unrelated = tmp_path / ".sol.json.backup"
    for p in (old_style, live, unrelated):
        p.write_text("x")
    assert remove_stale_temporaries(target) == [old_style]
    assert live.exists() and unrelated.exists()


def test_write_atomic_replaces_in_one_step(tmp_path: Path, monkeypatch) -> None:
    """Readers see the old or the new file; a failure before the rename keeps the old one and
    leaves no temporary file."""
    target = tmp_path / "sol.json"
    write_atomic(target, b"old")
    inode = target.stat().st_ino

    def broken(fd: int) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", broken)
    with pytest.raises(OSError, match="No space"):
        write_atomic(target, b"new")
    assert target.read_bytes() == b"old" and [p.name for p in tmp_path.iterdir()] == ["sol.json"]
    monkeypatch.undo()
    write_atomic(target, b"new")
    assert target.read_bytes() == b"new" and target.stat().st_ino != inode  # renamed in


# ------------------------------------------------------------------ output paths


def test_check_file_and_check_folder_name_the_option_and_the_fix(tmp_path: Path) -> None:
    regular = tmp_path / "file.txt"
    regular.write_text("x")
    cases = [
        (lambda: check_file("", "--out"), "--out is empty"),
        (lambda: check_file(Path(""), "--out"), "--out is empty"),
        (lambda: check_file(tmp_path, "--out"), "is a folder; give a file path"),
        (lambda: check_file(regular / "sol.json", "--out"), "is a file, not a folder"),
        (lambda: check_file(regular / "a" / "b.png", "--plot"), "is a file, not a folder"),
        (lambda: check_folder(regular, "--out"), "is a file, not a folder"),
        (lambda: check_folder(regular / "sub", "--out"), "is a file, not a folder"),
        (lambda: check_folder("", "--out"), "--out is empty"),
    ]
    if Path("/dev/null").exists():
        cases.append((lambda: check_file("/dev/null", "--out"), "not a regular file"))
    for call, message in cases:
        with pytest.raises(ConfigError, match=message):
            call()
    assert check_file(tmp_path / "new" / "deeper" / "sol.json") == \
        tmp_path / "new" / "deeper" / "sol.json"
    assert not (tmp_path / "new").exists()  # checking creates nothing
    assert check_folder(tmp_path / "fresh") == tmp_path / "fresh"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt"]


def test_unwritable_paths_are_refused(tmp_path: Path) -> None:
    folder = unwritable_folder(tmp_path)
    with pytest.raises(ConfigError, match="cannot write in the folder"):
        check_file(folder / "sol.json", "--out")
    with pytest.raises(ConfigError, match="cannot write in the folder"):
        check_folder(folder / "sweep", "--out")


@pytest.fixture
def no_solve(monkeypatch):
    """The solve must not start: output paths are checked first."""
    def refuse(*args, **kwargs):
        raise AssertionError("the solve started before the output paths were checked")

    # the module (the package's attribute `solve` is the function of that name)
    monkeypatch.setattr(importlib.import_module("ocgroupoid.solve"), "compile_problem", refuse)


def bad_outputs(tmp_path: Path) -> list[tuple[list[str], str]]:
    regular = tmp_path / "regular.txt"
    regular.write_text("x")
    return [
        (["--out", str(tmp_path)], "is a folder"),
        (["--out", ""], "--out is empty"),
        (["--out", str(regular / "sol.json")], "is a file, not a folder"),
        (["--plot", str(regular / "fig.png")], "is a file, not a folder"),
        (["--plot", str(regular / "deep" / "fig.png")], "is a file, not a folder"),
        (["--plot", str(tmp_path)], "is a folder"),
        (["--out", str(tmp_path / "same"), "--plot", str(tmp_path / "same")], "same file"),
    ]


def test_solve_checks_every_output_path_before_solving(tmp_path: Path, no_solve) -> None:
    for args, message in bad_outputs(tmp_path):
        r = runner.invoke(app, ["solve", str(SO3), "-q", *args])
        text = one_line(r.output)
        assert r.exit_code == 2, (args, r.output, r.exception)
        assert message in text and "Traceback" not in r.output, (args, text)
        assert not isinstance(r.exception, (AssertionError, OSError)), args


def test_solve_refuses_an_unwritable_out(tmp_path: Path, no_solve) -> None:
    folder = unwritable_folder(tmp_path)
    r = runner.invoke(app, ["solve", str(SO3), "-q", "--out", str(folder / "sol.json")])
    assert r.exit_code == 2 and "cannot write in the folder" in one_line(r.output), r.output


def test_output_section_of_the_problem_file_is_checked_too(tmp_path: Path, no_solve) -> None:
    regular = tmp_path / "regular.txt"
    regular.write_text("x")
    f = tmp_path / "p.yaml"
    f.write_text(SO3.read_text() + f"output: {{plot: {regular / 'fig.png'}}}\n")
    r = runner.invoke(app, ["solve", str(f), "-q"])
    assert r.exit_code == 2 and "output.plot" in one_line(r.output), r.output
    assert "is a file, not a folder" in one_line(r.output)


def test_solve_plot_under_a_file_is_exit_2_in_a_real_process(tmp_path: Path) -> None:
    """The issue's case end to end: no FileExistsError traceback, and no time spent solving."""
    regular = tmp_path / "regular.txt"
    regular.write_text("x")
    r = subprocess.run([sys.executable, "-m", "ocgroupoid", "solve", str(SO3), "--plot",
                        str(regular / "fig.png")], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert "is a file, not a folder" in one_line(r.stderr)
    assert r.stdout == ""


def test_good_outputs_are_written_with_the_umask_mode(tmp_path: Path, umask_022) -> None:
    out = tmp_path / "new" / "sol.json"
    r = runner.invoke(app, ["solve", str(SO3), "-q", "--set", "horizon.N=16", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert stat.S_IMODE(out.stat().st_mode) == 0o644


def test_a_write_that_fails_after_the_solve_is_one_line(tmp_path: Path, monkeypatch) -> None:
    def full(path: object, data: object) -> None:
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(importlib.import_module("ocgroupoid.solve.solution"), "write_atomic",
                        full)
    out = tmp_path / "sol.json"
    r = runner.invoke(app, ["solve", str(SO3), "-q", "--set", "horizon.N=16", "--out", str(out)])
    assert r.exit_code == 2, r.output
    assert "No space left on device" in one_line(r.output) and "Traceback" not in r.output


def test_sweep_checks_its_folder_first(tmp_path: Path) -> None:
    regular = tmp_path / "regular.txt"
    regular.write_text("x")
    for out in (regular, regular / "sub"):
        r = runner.invoke(app, ["sweep", str(SO3), "--grid", "horizon.T=[4, 5]", "--out",
                                str(out), "-q"])
        assert r.exit_code == 2 and "is a file, not a folder" in one_line(r.output), r.output
    folder = unwritable_folder(tmp_path)
    r = runner.invoke(app, ["sweep", str(SO3), "--grid", "horizon.T=[4, 5]", "--out",
                            str(folder / "s"), "-q"])
    assert r.exit_code == 2 and "cannot write in the folder" in one_line(r.output), r.output


def test_plot_checks_its_path_before_drawing(tmp_path: Path) -> None:
    """`plot --out` a folder or under a file was a traceback (IsADirectoryError,
    FileExistsError); `og.plot(sol, path)` raises the same ConfigError."""
    import ocgroupoid as og

    sol = tmp_path / "sol.json"
    assert runner.invoke(app, ["solve", str(SO3), "-q", "--set", "horizon.N=16", "--set",
                               "solver.multistart=false", "--out", str(sol)]).exit_code == 0
    regular = tmp_path / "regular.txt"
    regular.write_text("x")
    for out, says in ((tmp_path, "is a folder"), (regular / "f.png", "is a file, not a folder")):
        r = runner.invoke(app, ["plot", str(sol), "--out", str(out)])
        assert r.exit_code == 2 and says in one_line(r.output), r.output
        assert "Traceback" not in r.output
        with pytest.raises(ConfigError, match=says):
            og.plot(og.Solution.from_json(sol), out)
    assert regular.read_text() == "x"


# ------------------------------------------------------------------ list and check


def test_list_shows_custom_and_the_problem_files_from_any_folder(tmp_path: Path,
                                                                 monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    r = runner.invoke(app, ["list"], terminal_width=400)
    assert r.exit_code == 0, r.output
    assert re.search(r"│ custom +│ your own model", r.output), r.output
    for p in PROBLEMS:
        assert p.name in r.output, p.name


def test_list_finds_the_installed_copy_of_the_problem_files(tmp_path: Path,
                                                            monkeypatch) -> None:
    """A wheel installs them under PREFIX/share/ocgroupoid/problems (pyproject data-files)."""
    data = tmp_path / "prefix"
    shipped = data / "share" / "ocgroupoid" / "problems"
    shipped.mkdir(parents=True)
    (shipped / "installed_example.yaml").write_text("model: rigid_body\n")
    monkeypatch.setattr(sysconfig, "get_path", lambda name, *a, **k: str(data))
    monkeypatch.chdir(tmp_path)
    assert shipped in listing.problem_folders()
    text = (ROOT / "pyproject.toml").read_text()
    assert '"share/ocgroupoid/problems" = ["problems/*.yaml"]' in text


def test_check_names_a_retraction_only_when_a_group_factor_uses_it() -> None:
    r = runner.invoke(app, ["check", str(CART_POLE)], terminal_width=200)  # R^n factors only
    assert r.exit_code == 0, r.output
    title = r.output.splitlines()[0]
    assert "cart_pole" in title and not any(n in title for n in ("cayley", "exp", "first_order"))
    r = runner.invoke(app, ["check", str(SO3)], terminal_width=200)
    assert r.exit_code == 0 and "cayley" in r.output.splitlines()[0], r.output


# ------------------------------------------------------------------ Ctrl-C while starting


@pytest.mark.parametrize("command", [
    [sys.executable, "-X", "importtime", "-m", "ocgroupoid", "list"],
    [sys.executable, "-X", "importtime", str(Path(sys.executable).parent / "ocgroupoid"), "list"],
], ids=["python -m ocgroupoid", "ocgroupoid script"])
def test_ctrl_c_while_importing_is_one_line_and_exit_130(command: list[str]) -> None:
    """SIGINT once ``ocgroupoid._startup`` is imported (``-X importtime`` reports it), while
    CasADi and the rest still load: one line, no traceback, exit code 130."""
    if not Path(command[3]).exists() and command[3] != "-m":
        pytest.skip("the ocgroupoid script is not installed next to this Python")
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=ROOT, preexec_fn=lambda: signal.signal(signal.SIGINT,
                                                                       signal.SIG_DFL))
    assert proc.stderr is not None
    deadline = time.monotonic() + 60
    for line in proc.stderr:
        if line.rstrip().endswith("ocgroupoid._startup") or time.monotonic() > deadline:
            break
    proc.send_signal(signal.SIGINT)
    _, rest = proc.communicate(timeout=60)
    messages = [ln for ln in rest.splitlines() if not ln.startswith("import time:")]
    assert proc.returncode == 130, rest[-2000:]
    assert messages == ["ocgroupoid: interrupted while starting"], messages


# ------------------------------------------------------------------ the tutorials


def test_tutorial_snippets_for_products_and_reading_solutions_run(tmp_path: Path) -> None:
    """The tutorials' product of factors and their Solution read-back run as written and give
    the shapes they describe."""
    text = "".join((ROOT / "docs" / "tutorials" / page).read_text()
                   for page in ("python-problem.md", "first-solve.md"))
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    product = next(b for b in blocks if "og.Groupoid(" in b)
    reading = next(b for b in blocks if "og.Solution.from_json(" in b)
    code = "\n".join([
        "import casadi as ca, numpy as np", "import ocgroupoid as og", product,
        "assert sol3.success and sol3.controls.shape == (17, 5)",
        "from ocgroupoid.systems.rigid_body import rigid_body",
        "og.solve(rigid_body(), N=8).to_json('sol.json')", reading,
        "assert sol.states['R'].shape == (9, 3, 3) and sol.control_names == ['u1', 'u2', 'u3']"])
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       cwd=tmp_path, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
