"""Every benchmark script runs (quick mode) and writes its JSON and PNG."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPTS = sorted(p for p in (Path(__file__).resolve().parent.parent / "scripts").glob("*.py")
                 if not p.name.startswith("_"))


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.stem)
def test_script_runs_quick(script: Path, tmp_path) -> None:
    r = subprocess.run([sys.executable, str(script), "--quick", "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    outputs = list(tmp_path.glob("*.json"))
    assert outputs, "no JSON written"
    for f in outputs:
        json.loads(f.read_text())
    assert list(tmp_path.glob("*.png")), "no PNG written"


@pytest.mark.parametrize("name, args, says", [
    ("bench_setting", ["--set", "solver.ipopt.mumps_mem_percent=abc"], "mumps_mem_percent"),
    ("bench_setting", ["--set", "horizon.no_such_key=1"], "no_such_key"),
    ("bench_setting", ["--schemes", "order9"], "unknown scheme 'order9'"),
    ("bench_setting", ["--N", "64,x"], "--N: '64,x' is not a comma-separated list of integers"),
    ("bench_setting", ["--N", "0"], "--N: N must be at least 2"),
    ("bench_checks", ["--scheme", "order9"], "unknown scheme 'order9'"),
    ("bench_checks", ["--scheme", "order4,order6"], "--scheme takes one method"),
    ("bench_checks", ["--N", "64,x"], "--N: '64,x' is not a comma-separated list of integers"),
    ("bench_checks", ["--N", "0"], "--N: N must be at least 2"),
])
def test_bench_scripts_refuse_bad_input_in_one_line(name: str, args: list[str], says: str,
                                                    tmp_path: Path) -> None:
    """Every input is checked before anything is built: one line naming it, exit 2, no
    traceback and nothing written."""
    script = next(p for p in SCRIPTS if p.stem == name)
    r = subprocess.run([sys.executable, str(script), *args, "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, r.stdout + r.stderr
    assert says in r.stderr and "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and not list(tmp_path.iterdir())
