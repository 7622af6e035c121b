"""Faults outside sweeps (issue 30): SIGTERM handled as Ctrl-C, problems beyond the scale
double precision resolves refused at `check`, N beyond what time allows refused up front,
and every backend bounded in time (no loop on NaN)."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.cli import app
from ocgroupoid.nlp import isolated

from .interrupts import sigint_after

ROOT = Path(__file__).resolve().parent.parent
PROBLEMS = ROOT / "problems"
runner = CliRunner()


# -- SIGTERM (item 9) --------------------------------------------------------------------------

#: the command line, telling on stderr when the first start begins (then SIGTERM is sent)
TELL_AND_RUN = """\
import sys
from ocgroupoid.solve import compiled
guesses = compiled.CompiledProblem.guesses
def told(*args, **kwargs):
    print("solving", file=sys.stderr, flush=True)
    return guesses(*args, **kwargs)
compiled.CompiledProblem.guesses = told
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


# -- every backend bounded in time, never a loop on NaN (item 10) ------------------------------

def test_the_first_order_plate_ball_on_fatrop_returns(tmp_path: Path) -> None:
    """The case that looped for more than 600 s printing "nlp_g failed: NaN detected": fatrop's
    inertia correction never ends on the "long way round" start; it is stopped after repeated
    NaN and IPOPT solves that start. With IPOPT's default regularisation factor (the file
    sets 0.1, under which IPOPT takes that start to another start's minimum, 3.2022, listed
    under that start's label) the start's own minimum (3.4339) shows it was solved."""
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "ocgroupoid", "solve",
                        str(PROBLEMS / "plate_ball.yaml"), "--set",
                        "discretization.retraction=first_order", "--set", "horizon.N=16",
                        "--set", "solver.ipopt.perturb_dec_fact=0.3333333333333333",
                        "--out", str(tmp_path / "sol.json")],
                       capture_output=True, text=True, timeout=90, cwd=ROOT)
    seconds = time.perf_counter() - t0
    # solved; not verified: at N = 16 the first-order rule's long steps miss (issue 31)
    assert r.returncode == 1 and "does not land" in r.stderr, r.stderr[-2000:]
    sol = og.Solution.from_json(tmp_path / "sol.json")
    assert sol.status == "Solve_Succeeded" and sol.starts == 11
    assert "long way round" in [m["label"] for m in sol.minima]
    assert "NaN detected" not in r.stderr and seconds < 30


#: where fatrop runs: guarded in the caller's process (``fatrop_guard.c``), or in the helper
WHERE = pytest.mark.parametrize("guarded", [True, False], ids=["in-process", "helper"])


def hanging_heavy_top(max_seconds: float, jit: bool = False, guarded: bool = True
                      ) -> tuple[og.CompiledProblem, og.Guess]:
    """The heavy top with the first-order retraction on fatrop, and a start on which fatrop
    loops forever (once more NaN than :data:`~ocgroupoid.nlp.isolated.NAN_LIMIT` is let
    through); fatrop through its own C interface (``fatrop_ocp``), its Functions compiled
    with ``jit``, else evaluated by CasADi (through CasADi's nlpsol where no C compiler
    builds the interface); guarded in this process where it can be (Linux), or in the
    helper process."""
    cfg = files.load(PROBLEMS / "heavy_top_rotors.yaml", [
        "discretization.retraction=first_order", "horizon.N=16", "solver.backend=fatrop"])
    f, d = cfg.file, cfg.file.discretization
    solver = og.compile_problem(files.build(cfg), 16, d.retraction, d.rule, f.solver.ipopt,
                                d.scheme, backend="fatrop", max_seconds=max_seconds, jit=jit)
    tr = solver.transcription
    compiler = any(shutil.which(c) for c in ("cc", "gcc", "clang"))
    assert tr.fatrop.direct is not None or not compiler
    assert tr.fatrop.guarded == (tr.fatrop.direct is not None and sys.platform == "linux")
    tr.fatrop.guarded &= guarded
    guess = next(g for g in solver.guesses(tr, tr.pack(), True)
                 if g.label == "great circle, long way")
    return solver, guess


def ran_where(solver: og.CompiledProblem, guarded: bool) -> None:
    """fatrop ran where it was meant to: guarded in this process (its driver kept the
    solve's record here), or in the helper (the record stayed in the helper)."""
    fatrop = solver.transcription.fatrop
    assert fatrop is not None
    if fatrop.direct is None:  # no C compiler: CasADi's nlpsol, in the helper
        return
    assert (fatrop.direct.times is not None) == fatrop.guarded
    assert fatrop.guarded or not guarded or sys.platform != "linux"


@WHERE
def test_fatrop_stops_at_the_time_limit(monkeypatch, guarded: bool) -> None:
    monkeypatch.setattr(isolated, "NAN_LIMIT", 10 ** 9)  # only the deadline is left
    solver, guess = hanging_heavy_top(max_seconds=2.0, guarded=guarded)
    t0 = time.perf_counter()
    sol = solver.solve(guess=guess, replay=False)
    assert time.perf_counter() - t0 < 15
    assert sol.status == "Maximum_WallTime_Exceeded" and not sol.success
    assert "solver.max_seconds" in sol.hint and sol.backend == "fatrop"
    ran_where(solver, guarded)


@WHERE
def test_a_stuck_fatrop_run_fails_before_the_deadline_and_ipopt_solves_the_start(
        monkeypatch, guarded: bool) -> None:
    """A fatrop run longer than its iterations can take (``stuck_after``) is stuck: it fails
    there, not at the deadline, and IPOPT solves the start with the time left."""
    from ocgroupoid.nlp.backends import fatrop
    monkeypatch.setattr(isolated, "NAN_LIMIT", 10 ** 9)  # only the time is left to stop it
    monkeypatch.setattr(fatrop, "STUCK_FLOOR", 0.5)
    monkeypatch.setattr(fatrop, "STUCK_SECONDS", 1e-6)
    solver, guess = hanging_heavy_top(max_seconds=60.0, guarded=guarded)
    tr = solver.transcription
    assert tr.fatrop is not None
    assert tr.fatrop.stuck_after == pytest.approx(0.5 + 1e-6 * tr.fatrop.max_iter * tr.nx)
    t0 = time.perf_counter()
    r = tr.solve(guess, tr.pack())
    assert time.perf_counter() - t0 < 30
    assert r.backend == "ipopt after fatrop" and r.status != "Maximum_WallTime_Exceeded"
    assert r.earlier[0][:2] == ("fatrop", fatrop.FAILED)
    ran_where(solver, guarded)


@WHERE
@pytest.mark.parametrize("jit", [False, True], ids=["vm", "jit"])
def test_fatrop_stops_on_repeated_nan_and_ipopt_solves_the_start(jit: bool, guarded: bool
                                                                 ) -> None:
    solver, guess = hanging_heavy_top(max_seconds=60.0, jit=jit, guarded=guarded)
    t0 = time.perf_counter()
    r = solver.transcription.solve(guess, solver.transcription.pack())
    assert time.perf_counter() - t0 < 10
    assert r.backend == "ipopt after fatrop" and r.status != "Maximum_WallTime_Exceeded"
    assert r.earlier[0][:2] == ("fatrop", "Fatrop_Failed")
    assert solver.transcription.fatrop.nans >= isolated.NAN_LIMIT
    ran_where(solver, guarded)


@WHERE
def test_ctrl_c_stops_fatrop_at_once(monkeypatch, guarded: bool) -> None:
    monkeypatch.setattr(isolated, "NAN_LIMIT", 10 ** 9)
    solver, guess = hanging_heavy_top(max_seconds=60.0, guarded=guarded)
    t0 = time.perf_counter()
    with sigint_after(1.0):
        sol = solver.solve(guess=guess, replay=False)
    assert sol.status == "interrupted" and time.perf_counter() - t0 < 10
    ran_where(solver, guarded)


@pytest.mark.parametrize("backend", ["ipopt", "fatrop"])
def test_max_seconds_bounds_a_multistart(backend: str) -> None:
    """A limit far below what 40 starts need: the solve returns by it, with the best point
    of the starts it ran and the status of the one the limit stopped."""
    cfg = files.load(PROBLEMS / "heavy_top_rotors.yaml", ["horizon.N=128"])
    f, d = cfg.file, cfg.file.discretization
    solver = og.compile_problem(files.build(cfg), 128, d.retraction, d.rule, f.solver.ipopt,
                        backend=backend, max_seconds=0.4)
    t0 = time.perf_counter()
    sol = solver.solve(multistart=40, replay=False)
    assert time.perf_counter() - t0 < 0.4 + 5  # + the diagnostics
    assert sol.starts < 40


@pytest.mark.parametrize("value, message", [
    ("0", "outside (0, 604800]"), ("-1", "outside (0, 604800]"),
    ("1.0e+9", "outside (0, 604800]"), ("abc", "must be a number"), ("true", "must be a number")])
def test_max_seconds_is_validated(value: str, message: str) -> None:
    r = runner.invoke(app, ["check", str(PROBLEMS / "so3_rest_to_rest.yaml"), "--set",
                            f"solver.max_seconds={value}"])
    assert r.exit_code == 2 and message in " ".join(r.output.split()), r.output
    assert "solver.max_seconds" in r.output


# -- the helper process ------------------------------------------------------------------------

def _sleep(seconds: float) -> float:
    time.sleep(seconds)
    return seconds


def _nan_forever(_: object) -> None:
    while True:
        sys.stderr.write("WARNING: f failed: NaN detected for output g\n")
        sys.stderr.flush()
        time.sleep(0.001)


def _die(_: object) -> None:
    os._exit(3)


def _fail(_: object) -> None:
    raise ValueError("no")


def test_the_helper_answers_and_is_stopped_every_way() -> None:
    helper = isolated.Isolated(_sleep)
    assert helper.call(0.01, 10) == 0.01 and helper.call(0.02, 10) == 0.02
    pid = helper.pid
    t0 = time.perf_counter()
    assert helper.call(100, 0.5) == isolated.Stopped("time")
    assert time.perf_counter() - t0 < 5 and helper.pid == 0
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)  # killed and reaped
    assert helper.call(100, 10, stop=lambda: True) == isolated.Stopped("stop")
    assert helper.call(0.0, 10) == 0.0  # a new helper
    assert isolated.Isolated(_nan_forever).call(None, 30) == isolated.Stopped("nan")
    assert isolated.Isolated(_die).call(None, 30).reason == "died"
    with pytest.raises(RuntimeError, match="ValueError: no"):
        isolated.Isolated(_fail).call(None, 30)


def test_the_helper_is_stopped_at_its_deadline_not_a_poll_later(monkeypatch) -> None:
    """The caller is woken at the deadline itself: with a poll interval longer than the work,
    a deadline before the answer still stops it (waiting a poll, the caller would have taken
    the late answer), and an answer in time is taken."""
    monkeypatch.setattr(isolated, "POLL", 60.0)
    helper = isolated.Isolated(_sleep)
    assert helper.call(0.0, 10) == 0.0  # the helper forked
    assert helper.call(0.5, 0.01) == isolated.Stopped("time")
    assert helper.call(0.001, 10) == 0.001


# -- the time a solve takes, up front (item 8) -------------------------------------------------

def test_a_long_solve_is_announced_with_its_estimate(monkeypatch) -> None:
    from ocgroupoid.cli import solve

    monkeypatch.setattr(solve, "LONG_SOLVE", 0.0)  # every solve is long now
    r = runner.invoke(app, ["solve", str(PROBLEMS / "so3_rest_to_rest.yaml"), "--set",
                            "horizon.N=16", "--set", "solver.multistart=false"])
    assert r.exit_code == 0, r.output
    text = " ".join(r.output.split())
    assert "N=16: this solve takes about" in text and "then 1 start of" in text
    assert "solver.max_seconds = 600" in text


def test_N_beyond_the_time_limit_is_refused_with_the_estimate() -> None:
    t0 = time.perf_counter()
    r = runner.invoke(app, ["check", str(PROBLEMS / "plate_ball.yaml"), "--set",
                            "horizon.N=20000"])
    text = " ".join(r.output.split())
    assert r.exit_code == 2 and time.perf_counter() - t0 < 5, text
    assert "horizon.N = 20000: a solve takes about" in text and "more than " \
        "solver.max_seconds = 600" in text and "fatrop's build grows like N^2" in text
