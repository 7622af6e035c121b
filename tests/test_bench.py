"""``ocgroupoid bench`` (issue 16): work-precision rows, charts and stability maps, written as
they go; bad input named; the gimbal lock of the Euler-angle baseline measured."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.bench import workprecision
from ocgroupoid.bench.chart import work_precision_grid
from ocgroupoid.bench.equal_accuracy import compare, headline, report, time_at
from ocgroupoid.bench.record import read_rows
from ocgroupoid.bench.stability import manoeuvre
from ocgroupoid.bench.timing import interleaved, median_seconds
from ocgroupoid.cli import app
from ocgroupoid.verify.richardson import observed_orders

ROOT = Path(__file__).resolve().parent.parent
SO3 = ROOT / "problems" / "so3_rest_to_rest.yaml"
PNG = b"\x89PNG\r\n\x1a\n"
runner = CliRunner()
TINY = ["--schemes", "order4,rk4_quat", "--N", "8,16", "--repeats", "1", "--reference-N", "32"]


def work_precision(out: Path, *extra: str) -> object:
    return runner.invoke(app, ["bench", "work-precision", str(SO3), "--out", str(out), "-q",
                               *TINY, *extra])


def test_work_precision_writes_rows_summary_and_chart(tmp_path: Path) -> None:
    r = work_precision(tmp_path)
    assert r.exit_code == 0, r.output
    rows = read_rows(tmp_path / "work_precision" / "so3_rest_to_rest.jsonl")
    assert [x["kind"] for x in rows] == ["reference"] + ["row"] * 4
    summary = json.loads((tmp_path / "work_precision" / "so3_rest_to_rest.json").read_text())
    ref = summary["reference"]
    assert ref["N"] == [16, 32] and ref["check"]["cost"] is not None
    assert ref["relative_uncertainty"] < 1e-4, ref
    assert {(x["method"], x["N"]) for x in summary["rows"]} == {
        (m, N) for m in ("order4", "rk4_quat") for N in (8, 16)}
    for x in summary["rows"]:
        assert x["status"] == "Solve_Succeeded" and x["minimum"] == "same", x
        assert 0 < x["cost_error"] < 1e-1 and x["replay_error"] > 0 and x["seconds"] > 0
        assert x["backend"] == "ipopt" and x["iterations_all"] == x["iterations"] > 0
    assert (tmp_path / "figures" / "work_precision_so3_rest_to_rest.png").read_bytes()[:8] \
        == PNG
    text = report(summary)  # what the command and scripts/bench_schemes.py print
    assert "so3_rest_to_rest: reference J = " in text and "at equal cost error" in text
    grid = work_precision_grid([summary, summary], tmp_path / "grid.png")
    assert grid.read_bytes()[:8] == PNG


def test_an_interrupted_run_keeps_its_finished_rows(tmp_path: Path, monkeypatch) -> None:
    """Ctrl-C while the third row is read out: exit 130, the reference and two rows kept."""
    real = workprecision.row
    calls = []

    def interrupted(*args, **kwargs):
        calls.append(args)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(workprecision, "row", interrupted)
    r = work_precision(tmp_path)
    assert r.exit_code == 130
    jsonl = tmp_path / "work_precision" / "so3_rest_to_rest.jsonl"
    assert "interrupted; the finished rows are kept in" in r.output and jsonl.name in r.output
    rows = read_rows(jsonl)
    assert [x["kind"] for x in rows] == ["reference", "row", "row"]
    assert [(x["method"], x["N"]) for x in rows[1:]] == [("order4", 8), ("order4", 16)]
    assert not (tmp_path / "work_precision" / "so3_rest_to_rest.json").exists()


@pytest.mark.parametrize("args, message", [
    (["--schemes", "order3"], "unknown scheme 'order3'"),
    (["--schemes", "order2:cubic"], "unknown retraction 'cubic'"),
    (["--schemes", "order2@snopt"], "unknown backend 'snopt'"),
    (["--schemes", "order4+coarse+jit"], "in this order"),
    (["--schemes", "order4+fast"], "may end with +jit, +coarse"),
    (["--schemes", "order4+coarse", "--N", "8,16"], "no --N of at least 32"),
    (["--N", "1,8"], "N must be at least 2"),
    (["--N", "8,x"], "is not a comma-separated list of integers"),
    (["--reference-N", "100"], "power of two"),
    (["--repeats", "0"], "--repeats must be at least 1"),
], ids=["scheme", "retraction", "backend", "flag-order", "flag", "coarse-N", "N", "N-text",
        "reference-N", "repeats"])
def test_bad_input_exits_2_with_the_option_named(tmp_path: Path, args: list[str],
                                                 message: str) -> None:
    r = runner.invoke(app, ["bench", "work-precision", str(SO3), "--out", str(tmp_path), *args])
    assert r.exit_code == 2, r.output
    assert message in r.output and "Traceback" not in r.output


def test_methods_name_their_backend_and_compiled_evaluation() -> None:
    """``SCHEME[:RETRACTION][@BACKEND][+jit]``: parsed, labelled back the same way, and a
    method that repeats another's computation (exp on R^n) is named against the same
    backend, and one without a rule for the problem's order is left out."""
    from ocgroupoid.bench.methods import Method, left_out, parse_methods
    methods = parse_methods("order4@fatrop+jit,order2:exp@fatrop,rk4_quat+jit,order2@fatrop",
                            ())
    assert methods == [Method("order4", "cayley", "fatrop", True),
                       Method("order2", "exp", "fatrop", False),
                       Method("rk4_quat", "cayley", "ipopt", True),
                       Method("order2", "cayley", "fatrop", False)]
    assert [m.label for m in methods] == ["order4@fatrop+jit", "order2:exp@fatrop",
                                          "rk4_quat+jit", "order2@fatrop"]
    plane = files.build(files.load(ROOT / "problems" / "cart_pole.yaml"))
    assert left_out(methods, plane) == {
        "order2:exp@fatrop": "identical to order2@fatrop here: every retraction is the "
                             "translation on R^n"}


@pytest.mark.parametrize("command", ["work-precision", "stability"])
def test_a_missing_file_exits_2(tmp_path: Path, command: str) -> None:
    r = runner.invoke(app, ["bench", command, str(tmp_path / "nope.yaml"), "--out",
                            str(tmp_path)])
    assert r.exit_code == 2 and "nope.yaml" in r.output and "check the path" in r.output


def test_stability_needs_an_attitude(tmp_path: Path) -> None:
    r = runner.invoke(app, ["bench", "stability", str(SO3), "--out", str(tmp_path),
                            "--state", "Omega"])
    assert r.exit_code == 2 and "no SO(3) state" in r.output, r.output


def test_stability_map_writes_cells_with_messages(tmp_path: Path) -> None:
    r = runner.invoke(app, ["bench", "stability", str(SO3), "--out", str(tmp_path), "-q",
                            "--name", "so3", "--schemes", "order2,rk4_euler", "--N", "32",
                            "--angles", "2.0"])
    assert r.exit_code == 0, r.output
    summary = json.loads((tmp_path / "stability" / "so3.json").read_text())
    cells = {c["method"]: c for c in summary["cells"]}
    assert cells["order2"]["outcome"] == "converged"
    euler = cells["rk4_euler"]
    assert euler["outcome"] in ("failed", "off target", "unverified") and euler["message"]
    assert "gimbal lock" in euler["message"]
    assert len(read_rows(tmp_path / "stability" / "so3.jsonl")) == 3  # reference, 2 cells
    assert (tmp_path / "figures" / "stability_so3.png").read_bytes()[:8] == PNG


def test_euler_angles_fail_through_pitch_90_where_ours_succeed() -> None:
    """A 2 rad slew about the body y axis passes pitch 90 degrees (gimbal lock)."""
    cfg = files.load(SO3, [manoeuvre("R", [0, 1, 0], 2.0)])
    pb = files.build(cfg)
    sols = {s: og.solve(pb, 32, scheme=s, ipopt=cfg.file.solver.ipopt, multistart=False)
            for s in ("order2", "order4", "rk4_euler")}
    assert sols["order2"].success and sols["order4"].success
    euler = sols["rk4_euler"]
    assert not euler.success
    if euler.status == "Solve_Succeeded":
        miss = euler.diagnostics["replay"]["max_terminal_error"]
        assert miss >= 100 * sols["order2"].diagnostics["replay"]["max_terminal_error"]


def test_time_at_equal_accuracy_is_read_on_the_log_log_line() -> None:
    rows = [{"N": 8, "e": 1e-2, "seconds": 1.0}, {"N": 16, "e": 1e-4, "seconds": 4.0}]
    t, bound = time_at(rows, "e", 1e-3)
    assert math.isclose(t, 2.0) and not bound
    assert time_at(rows, "e", 1e-1) == (1.0, True)  # the coarsest grid is more accurate
    assert time_at(rows, "e", 1e-5) is None
    base = [{"N": 8, "e": 1e-1, "seconds": 1.0}, {"N": 16, "e": 1e-3, "seconds": 4.0}]
    ours = [{"N": 8, "e": 5e-3, "seconds": 0.1}, {"N": 16, "e": 5e-5, "seconds": 0.4}]
    found = {c["level"]: c for c in compare({"rk4_quat": base, "order4": ours}, "e")}
    assert set(found) == {1e-2, 1e-3, 1e-4}  # at 1e-1 the baseline's own time is only a bound
    assert found[1e-2]["lower_bound"] and math.isclose(found[1e-2]["ratio"], 2.0 / 0.1)
    t_ours = 0.1 * 4 ** (math.log(5) / math.log(100))
    assert math.isclose(found[1e-3]["ratio"], 4.0 / t_ours) and not found[1e-3]["lower_bound"]
    # 1e-4: the baseline's finest grid (1e-3, 4 s) falls short; a finer one takes longer
    t_ours = 0.1 * 4 ** (math.log(50) / math.log(100))
    assert found[1e-4]["lower_bound"] and math.isclose(found[1e-4]["ratio"], 4.0 / t_ours)
    assert found[1e-4]["baseline_seconds"] == 4.0
    assert headline(list(found.values()), 1e-2)["level"] == 1e-3  # interpolated first


def test_observed_orders_of_every_halving_and_none_without_a_rate() -> None:
    orders = observed_orders([1.0, 0.25, 1 / 64, 0.0])
    assert orders[:2] == [pytest.approx(2.0), pytest.approx(4.0)] and orders[2] is None


def test_interleaved_solves_one_of_each_trial_per_round() -> None:
    """Rounds, not rows: every trial that wants another solve gets one per round, in turn,
    until none wants more; a trial done early drops out."""
    order: list[str] = []

    class Counted:
        def __init__(self, name: str, solves: int) -> None:
            self.name, self.left = name, solves

        def wants(self, repeats: int) -> bool:
            return self.left > 0

        def run(self) -> None:
            order.append(self.name)
            self.left -= 1

    rounds: list[tuple[int, int]] = []
    interleaved([Counted("a", 3), Counted("b", 1), Counted("c", 2)], 3,  # type: ignore[list-item]
                lambda k, n: rounds.append((k, n)))
    assert order == ["a", "b", "c", "a", "c", "a"]
    assert rounds == [(0, 3), (1, 2), (2, 1)]


def test_median_seconds_times_every_call_and_keeps_the_last_result() -> None:
    calls = []
    seconds, last = median_seconds(lambda: calls.append(1) or len(calls), 3)
    assert last == 3 and seconds >= 0.0
    assert median_seconds(lambda: "once", 0)[1] == "once"  # at least one call


@pytest.mark.parametrize("backend", ["ipopt", "fatrop"])
def test_a_timed_solve_counts_what_its_caller_waits_for(backend: str,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """A work-precision row's time is the wall time of the whole solve of the built NLP: the
    guess's start point and, for fatrop, the way into its guarded solve (or to its helper
    process) and back, with the solve (the solver's own time alone left out 0.9-2.4 ms of
    fatrop's 3-13 ms on so3); and a fatrop run reports the caller's wait as its seconds.
    Each step is slowed by 50 ms here: the times must contain the delays."""
    import time

    from ocgroupoid.bench.methods import Method
    from ocgroupoid.bench.timing import Setting, timed_solve
    from ocgroupoid.nlp.backends.fatrop import FatropBackend
    from ocgroupoid.nlp.transcription import Transcription
    delay = 0.05
    start_point, solve_here = Transcription.start_point, FatropBackend._solve_here

    def slow_start(self: Transcription, *args: object) -> object:
        time.sleep(delay)
        return start_point(self, *args)  # type: ignore[arg-type]

    def slow_solve(self: FatropBackend, *args: object, **kwargs: object) -> object:
        time.sleep(delay)
        return solve_here(self, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(Transcription, "start_point", slow_start)
    monkeypatch.setattr(FatropBackend, "_solve_here", slow_solve)
    cfg = files.load(SO3)
    timed = timed_solve(files.build(cfg), Method("order4", backend=backend), 8,
                        Setting.of(cfg.file), repeats=2)
    assert timed.solution.status == "Solve_Succeeded" and timed.solution.backend == backend
    both = 2 * delay if backend == "fatrop" else delay
    assert len(timed.seconds) >= 2 and min(timed.seconds) >= both
    if backend == "fatrop":
        assert timed.solution.solve_seconds >= delay


@pytest.mark.parametrize("backend", ["ipopt", "fatrop"])
def test_a_timed_solve_is_held_to_max_seconds_and_a_failed_one_is_not_repeated(
        backend: str) -> None:
    """The file's ``solver.max_seconds`` bounds every run of a work-precision row (it was
    ignored: starts that diverge slowly kept the heavy top's run going for 18 minutes, their
    repeats included); a run that fails is run once, while a successful one is repeated."""
    import dataclasses

    from ocgroupoid.bench.methods import Method
    from ocgroupoid.bench.timing import Setting, timed_solve
    assert Setting.of(files.load(SO3, ["solver.max_seconds=42"]).file).max_seconds == 42.0
    cfg = files.load(SO3)
    problem, setting = files.build(cfg), Setting.of(cfg.file)
    method = Method("order4", backend=backend)
    stopped = timed_solve(problem, method, 256, dataclasses.replace(setting, max_seconds=1e-3),
                          repeats=3)
    assert stopped.solution.status == "Maximum_WallTime_Exceeded" and len(stopped.seconds) == 1
    solved = timed_solve(problem, method, 256, setting, repeats=3)
    assert solved.solution.status == "Solve_Succeeded" and len(solved.seconds) >= 3


def test_every_method_label_parses_back_to_its_method() -> None:
    """``parse_methods(m.label) == [m]`` for every scheme, retraction, backend and flag."""
    import itertools

    from ocgroupoid.bench.methods import Method, parse_methods
    from ocgroupoid.nlp.options import BACKENDS
    for scheme, retraction, backend, jit, coarse in itertools.product(
            ("order2", "order4", "rk4_quat"), ("cayley", "exp"), BACKENDS, (False, True),
            (False, True)):
        if scheme == "rk4_quat" and retraction != "cayley":
            continue  # the baselines ignore the retraction: their label has none
        m = Method(scheme, retraction, backend, jit, coarse)
        assert parse_methods(m.label, ()) == [m], m.label


def test_a_coarse_method_has_rows_where_it_has_a_coarse_grid(tmp_path: Path) -> None:
    """A ``+coarse`` row below N = 32 would time the plain method's cold solve a second time
    (and the fastest of two timings of one solve would be taken as ours): it has none."""
    r = runner.invoke(app, ["bench", "work-precision", str(SO3), "--out", str(tmp_path), "-q",
                            "--schemes", "order4,order4+coarse", "--N", "16,32",
                            "--repeats", "1", "--reference-N", "64"])
    assert r.exit_code == 0, r.output
    rows = read_rows(tmp_path / "work_precision" / "so3_rest_to_rest.jsonl")[1:]
    assert [(x["method"], x["N"]) for x in rows] == [("order4", 16), ("order4", 32),
                                                     ("order4+coarse", 32)]
    assert rows[2]["iterations_all"] > rows[2]["iterations"]  # N = 8 first


def test_a_coarse_method_solves_a_quarter_of_the_grid_first() -> None:
    """``+coarse``: the solve of a row on N is a solve on N/4 from the row's start and one on
    N from that solution, interpolated, with IPOPT's multipliers carried over
    (``solver.continuation: [N/4]`` of the compiled problem); the coarse run is listed
    first, the time counts both, and it lands where the cold solve lands. Below a coarse
    grid of 8 the method solves cold."""
    from ocgroupoid.bench.methods import Method, parse_methods
    from ocgroupoid.bench.timing import Setting, timed_solve
    (method,) = parse_methods("order4@fatrop+jit+coarse", ())
    assert method == Method("order4", "cayley", "fatrop", True, True)
    assert method.label == "order4@fatrop+jit+coarse"
    assert [method.coarse_N(N) for N in (16, 31, 32, 128)] == [None, None, 8, 32]
    assert method.options({}, N=64).continuation == (16,)
    assert method.options({}, N=16).continuation == ()
    assert Method("order4").coarse_N(128) is None
    cfg = files.load(ROOT / "problems" / "plate_ball_rotating.yaml")
    problem, setting = files.build(cfg), Setting.of(cfg.file)
    coarse = timed_solve(problem, Method("order4", coarse=True), 32, setting, repeats=1)
    cold = timed_solve(problem, Method("order4"), 32, setting, repeats=1)
    runs = coarse.solution.diagnostics["runs"]
    assert [r["backend"] for r in runs] == ["ipopt on N=8", "ipopt"]
    assert all(r["status"] == "Solve_Succeeded" for r in runs)
    assert coarse.solution.discretization["start"] == \
        "interpolated from N=8, with its multipliers"  # as continuation carries them
    assert runs[1]["iterations"] < cold.solution.iterations  # it starts near the solution
    assert coarse.solution.cost == pytest.approx(cold.solution.cost, rel=1e-8)
    assert coarse.solution.success and coarse.solution.solve_seconds > 0
    alone = timed_solve(problem, Method("order4", coarse=True), 16, setting, repeats=1)
    assert [r["backend"] for r in alone.solution.diagnostics["runs"]] == ["ipopt"]
