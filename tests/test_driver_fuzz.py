"""The exported driver reads parameter files as strictly as Python reads problem files (issue
30, items 6 and 7): malformed files (NUL bytes, /dev/zero, huge lines, control characters,
numbers beyond a double or outside their ranges, seeded mutations of params.txt) never exit
0, each is refused at once with one message, the messages of the ranges are Python's word for
word, and under valgrind (where installed) the refusals are clean too."""

from __future__ import annotations

import random
import shutil
import subprocess
from pathlib import Path

import pytest

import ocgroupoid as og
from ocgroupoid.export.codegen import EXPORT_IPOPT, export_c, positive_parameters
from ocgroupoid.model.ranges import FILE_BYTES, block_range
from ocgroupoid.systems import MODELS
from ocgroupoid.systems.rigid_body import rigid_body

from .cbuild import CFLAGS

SEED = 30
MUTANTS = 40
#: the cases that also run under valgrind (~1-2 s each), with /dev/zero
VALGRIND_CASES = ("a NUL after the number", "a huge line of digits",
                  "a huge line of zeros, within the size cap", "a huge key", "T 1e300",
                  "a hex float", "a subnormal", "a quaternion of 1e308", "inertias 1e13 apart")

pytestmark = pytest.mark.skipif(shutil.which("cc") is None or shutil.which("make") is None,
                                reason="no C compiler (cc) or make on PATH")


@pytest.fixture(scope="module")
def driver(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, og.Transcription]:
    """The rigid-body slew exported (N = 16: verified) and built with -Werror."""
    root = tmp_path_factory.mktemp("driver")
    exp = export_c(og.compile_problem(rigid_body(), N=16, ipopt=EXPORT_IPOPT), root / "c",
                   build=True, cflags=CFLAGS,
                   positive=positive_parameters(MODELS["rigid_body"].parameters))
    assert exp.binary is not None
    return exp.binary, exp.solver.transcription


def run(binary: Path, path: str, valgrind: bool = False) -> subprocess.CompletedProcess:
    prefix = ["valgrind", "-q", "--error-exitcode=99", "--leak-check=full",
              "--errors-for-leak-kinds=definite"] if valgrind else []
    return subprocess.run([*prefix, str(binary), path], capture_output=True, timeout=120)


#: (label, bytes of the file): every one is bad for sure
CASES: list[tuple[str, bytes]] = [
    ("a file of 1000 NUL bytes", b"\0" * 1000),
    ("a NUL after the number", b"T 6\0 garbage\n"),
    ("a NUL before the key", b"\0inertia -1 2 3\n"),
    ("a huge line of digits", b"T " + b"9" * (FILE_BYTES + 10) + b"\n"),
    ("a huge line of zeros, within the size cap", b"T " + b"0" * 500_000 + b"5\n"),
    ("more than the size cap of comments", b"T 5\n" + b"#" * (FILE_BYTES + 1)),
    ("a huge key", b"k" * 100_000 + b" 1\n"),
    ("T 1e300", b"T 1e300\n"),
    ("T 1e7", b"T 1e7\n"),
    ("a hex float", b"T 0x1.4p2\n"),
    ("a subnormal", b"T 4.9e-324\n"),
    ("a quaternion of 1e308", b"final.R 1e308 0 0 0\n"),
    ("T 1e-7", b"T 1e-7\n"),
    ("T nan", b"T nan\n"),
    ("T inf", b"T inf\n"),
    ("T infinity", b"T infinity\n"),
    ("T -0", b"T -0\n"),
    ("a number with two dots", b"T 1.2.3\n"),
    ("an exponent without digits", b"T 1e\n"),
    ("a comma decimal", b"T 1,5\n"),
    ("an inertia of 0", b"inertia 1 0 3\n"),
    ("an inertia of -1", b"inertia -1 2 3\n"),
    ("an inertia of 1e20", b"inertia 100000000000000000000 2 3\n"),
    ("inertias 1e13 apart", b"inertia 1e-6 1 1e7\n"),
    ("an angular velocity of 1e13", b"final.Omega 0 1e13 0\n"),
    ("a zero quaternion", b"final.R 0 0 0 0\n"),
    ("a control character", b"T 5\x01\n"),
    ("a form feed", b"T\x0c5\n"),
    ("DEL", b"T 5\x7f\n"),
    ("not UTF-8", b"T 5 # \xff\xfe\n"),
    ("a lone continuation byte", b"T \x80\n"),
    ("an unknown key", b"bogus 1\n"),
    ("a key twice", b"T 1\nT 2\n"),
    ("too few numbers", b"inertia 1 2\n"),
    ("too many numbers", b"T 1 2\n"),
    ("a number of 400 digits", b"T 0." + b"1" * 400 + b"\n"),
]


def mutants(params: bytes, count: int, seed: int = SEED) -> list[tuple[str, bytes]]:
    """Seeded mutations of the exported params.txt that are bad for sure."""
    rng = random.Random(seed)
    lines = [ln for ln in params.split(b"\n") if ln and not ln.startswith(b"#")]
    out = []
    for i in range(count):
        text = bytearray(params)
        kind = rng.choice(["nul", "control", "token", "range"])
        if kind == "nul":
            text.insert(rng.randrange(len(text)), 0)
        elif kind == "control":
            text.insert(rng.randrange(len(text)), rng.choice([1, 8, 11, 12, 27, 127]))
        else:
            line = rng.choice(lines)
            key = line.split()[0]
            n = len(line.split(b"#")[0].split()) - 1
            bad = rng.choice([b"0x1p3", b"nan", b"-inf", b"1e999", b"1e-999", b"1.5e", b"--1",
                              b"1e+", b"\xce\xa9"]) if kind == "token" else \
                rng.choice([b"1e13", b"-1e13", b"1e300"])
            numbers = [b"0.5"] * n
            numbers[rng.randrange(n)] = bad
            if key == b"T" and kind == "range":
                numbers = [rng.choice([b"1e7", b"1e-7", b"-1"])]
            text = bytearray(params.replace(line, key + b" " + b" ".join(numbers)))
        out.append((f"mutant {i} ({kind})", bytes(text)))
    return out


def test_no_malformed_parameter_file_is_solved(driver, tmp_path: Path) -> None:
    binary, _ = driver
    params = (binary.parent / "params.txt").read_bytes()
    cases = [*CASES, *mutants(params, MUTANTS)]
    failures = []
    for i, (label, data) in enumerate(cases):
        path = tmp_path / f"case{i}.txt"
        path.write_bytes(data)
        r = run(binary, str(path))
        stderr = r.stderr.decode(errors="replace")
        if r.returncode != 2 or r.stdout or len(stderr.splitlines()) != 1 or \
                not stderr.startswith("error: "):
            failures.append(f"{label}: exit {r.returncode}, stderr {stderr[:300]!r}")
    assert not failures, "\n".join(failures)
    assert run(binary, str(binary.parent / "params.txt")).returncode == 0  # the good one


def test_dev_zero_and_a_folder_are_refused_at_once(driver, tmp_path: Path) -> None:
    binary, _ = driver
    for path, message in (("/dev/zero", "a NUL byte: this is a binary file"),
                          (str(tmp_path), "is a folder")):
        r = run(binary, path)
        assert r.returncode == 2 and message in r.stderr.decode(), r.stderr


@pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind is not installed")
def test_refusals_are_clean_under_valgrind(driver, tmp_path: Path) -> None:
    binary, _ = driver
    failures = []
    cases = [("/dev/zero", b""), *[c for c in CASES if c[0] in VALGRIND_CASES]]
    assert len(cases) == len(VALGRIND_CASES) + 1
    for i, (label, data) in enumerate(cases):
        path = "/dev/zero" if label == "/dev/zero" else str(tmp_path / f"v{i}.txt")
        if label != "/dev/zero":
            Path(path).write_bytes(data)
        r = run(binary, path, valgrind=True)
        if r.returncode != 2:  # 99: valgrind found an error; 0: solved
            failures.append(f"{label}: exit {r.returncode}: {r.stderr.decode()[-800:]}")
    assert not failures, "\n".join(failures)


@pytest.mark.parametrize("key, numbers", [
    ("T", [1e7]), ("T", [1e-7]), ("T", [-1.0]), ("inertia", [1.0, 0.0, 3.0]),
    ("inertia", [-2.5, 1.0, 1.0]), ("inertia", [1e20, 2.0, 3.0]),
    ("inertia", [1e-13, 1.0, 1.0]), ("inertia", [1e-6, 1.0, 1e7]),
    ("final.Omega", [0.0, -3e12, 0.0]), ("final.R", [1e308, 0.0, 0.0, 0.0]),
])
def test_range_messages_are_pythons(driver, tmp_path: Path, key: str, numbers: list[float]
                                    ) -> None:
    """The driver's message for a number out of its range is Range.problem's, generated into
    the driver from the same table (ocg_ranges)."""
    binary, tr = driver
    block = next(b for b in tr.values.blocks if b.key == key)
    python = block_range(block.key, block.kind, key in positive_parameters(
        MODELS["rigid_body"].parameters)).problem(key, numbers)
    assert python is not None
    path = tmp_path / "p.txt"
    path.write_text(f"{key} {' '.join(repr(v) for v in numbers)}\n")
    r = run(binary, str(path))
    assert r.returncode == 2 and r.stderr.decode() == f"error: {path}:1: {python}\n"
