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
