"""The README's ``pytest -n 2`` pays a shared fixture's set-up once: conftest.py puts the
tests of one module-scoped fixture (one of its parameters) in one xdist group, and
``--dist loadgroup`` (pyproject's addopts) keeps a group on one worker. Without it, each
worker builds the same C export or reference solve again (measured: tests/test_codegen.py
233 s -> 179 s on 2 workers)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

SUITE = '''
import os
import pytest

LOG = os.environ["SETUP_LOG"]


@pytest.fixture(scope="module", params=["a", "b", "c"])
def shared(request):
    with open(LOG, "a") as f:
        f.write(request.param + "\\n")
    return request.param


@pytest.mark.parametrize("i", range(8))
def test_uses(shared, i):
    assert shared in "abc"


@pytest.mark.parametrize("i", range(8))
def test_alone(i):
    assert i >= 0
'''


def test_each_shared_set_up_runs_once_on_two_workers(tmp_path: Path) -> None:
    pytest.importorskip("xdist")
    shutil.copy(ROOT / "tests" / "conftest.py", tmp_path / "conftest.py")
    (tmp_path / "test_suite.py").write_text(SUITE)
    log = tmp_path / "setups.txt"
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "2", "-p", "no:cacheprovider",
                        "-c", str(ROOT / "pyproject.toml"), "--rootdir", str(tmp_path),
                        str(tmp_path / "test_suite.py")],
                       capture_output=True, text=True, timeout=300, cwd=tmp_path,
                       env={**os.environ, "SETUP_LOG": str(log)})
    assert r.returncode == 0, r.stdout + r.stderr
    assert "32 passed" in r.stdout, r.stdout
    assert sorted(log.read_text().split()) == ["a", "b", "c"], \
        f"a shared fixture was set up on both workers: {log.read_text().split()}"
