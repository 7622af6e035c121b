"""Faults outside sweeps (issue 30): SIGTERM handled as Ctrl-C, problems beyond the scale
double precision resolves refused at `check`, N beyond what time allows refused up front,
and every backend bounded in time (no loop on NaN)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PROBLEMS = ROOT / "problems"


# -- SIGTERM (item 9) --------------------------------------------------------------------------

#: the command line, telling on stderr when the first start begins (then SIGTERM is sent)
TELL_AND_RUN = """\
import sys
from ocgroupoid.solve import solver
guesses = solver.Solver.guesses
def told(*args, **kwargs):
    print("solving", file=sys.stderr, flush=True)
    return guesses(*args, **kwargs)
solver.Solver.guesses = told
from ocgroupoid.cli import main
sys.argv = ["ocgroupoid", *sys.argv[1:]]
main()
"""


def test_sigterm_writes_the_best_point_so_far_and_says_so(tmp_path: Path) -> None:
    out = tmp_path / "sol.json"
    proc = subprocess.Popen(
        [sys.executable, "-c", TELL_AND_RUN, "solve", str(PROBLEMS / "heavy_top_rotors.yaml"),
         "--set", "horizon.N=128", "--set", "solver.multistart=200", "--out", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    assert proc.stderr is not None
    deadline = time.monotonic() + 120
    for line in proc.stderr:
        if line.strip() == "solving" or time.monotonic() > deadline:
            break
    time.sleep(0.5)
    proc.send_signal(signal.SIGTERM)
    _, rest = proc.communicate(timeout=120)
    assert proc.returncode == 143, rest[-2000:]
    assert "terminated (SIGTERM): the best point so far is in" in " ".join(rest.split())
    assert "Traceback" not in rest
    sol = json.loads(out.read_text())
    assert sol["status"] == "interrupted" and sol["success"] is False
    assert os.path.getsize(out) > 1000
