"""Multi-start on worker processes (:mod:`ocgroupoid.solve.parallel`): the same result as the
starts in turn, the workers option checked, a start that fails in its worker reported."""

from __future__ import annotations

import os
import time
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import ocgroupoid as og
from ocgroupoid.errors import ConfigError
from ocgroupoid.nlp.transcription import RawResult, Transcription
from ocgroupoid.solve import parallel
from ocgroupoid.solve.compiled import START_BUDGET
from ocgroupoid.systems.heavy_top import heavy_top
from ocgroupoid.systems.rigid_body import rigid_body

from .interrupts import sigint_after

pytestmark = pytest.mark.skipif("fork" not in __import__("multiprocessing")
                                .get_all_start_methods(), reason="workers are forked")


@pytest.mark.parametrize("factory, N, starts", [(rigid_body, 16, 3), (heavy_top, 32, 2)])
def test_parallel_gives_the_sequential_result(factory, N: int, starts: int) -> None:
    """Same best start and cost, same distinct minima, same verdict, starts in order."""
    problem = factory()
    one = og.compile_problem(problem, N=N, workers=1).solve(multistart=starts)
    two = og.compile_problem(problem, N=N, workers=2).solve(multistart=starts)
    assert one.diagnostics["multistart"]["workers"] == 1
    assert two.diagnostics["multistart"]["workers"] == 2
    assert two.success == one.success and two.status == one.status
    assert two.discretization["start"] == one.discretization["start"]
    assert two.cost == pytest.approx(one.cost, rel=1e-9)
    assert [m["label"] for m in two.minima] == [m["label"] for m in one.minima]
    assert [m["cost"] for m in two.minima] == pytest.approx([m["cost"] for m in one.minima],
                                                            rel=1e-9)
    assert two.iterations == one.iterations and two.starts == one.starts
    report = two.diagnostics["multistart"]
    assert report["starts"] == report["finished"] == two.starts
    assert report["sequential_seconds"] == pytest.approx(two.ipopt_seconds_total)
    assert 0 < report["best_start_seconds"] <= report["sequential_seconds"]
    parallel.close()
    assert not __import__("multiprocessing").active_children()  # the workers ended


def _pids() -> list[int]:
    assert parallel._kept is not None
    return [proc.pid for proc in parallel._kept.procs]


def _alive_soon() -> set[int]:
    """The child processes alive once those told to end have ended (10 s at most)."""
    import multiprocessing

    end = time.monotonic() + 10
    while time.monotonic() < end and len(multiprocessing.active_children()) > len(_pids()):
        time.sleep(0.01)
    return {p.pid for p in multiprocessing.active_children()}


def test_the_workers_are_kept_for_the_next_multistart_of_the_same_grid() -> None:
    """A second multi-start of the same transcription runs on the same workers with the same
    result; a worker that died is replaced; another grid ends them (without waiting) and forks
    its own; ``close`` ends them and waits for every worker told to end."""
    import multiprocessing

    solver = og.compile_problem(rigid_body(), N=16, workers=2)
    first = solver.solve(multistart=2)
    kept = _pids()
    again = solver.solve(multistart=2)
    assert _pids() == kept and again.cost == pytest.approx(first.cost, rel=1e-12)
    assert again.discretization["start"] == first.discretization["start"]
    os.kill(kept[0], 9)
    while parallel._kept.procs[0].is_alive():
        time.sleep(0.01)
    third = solver.solve(multistart=2)  # not a failed start: new workers
    assert "failed" not in third.diagnostics["multistart"]
    assert third.cost == pytest.approx(first.cost, rel=1e-12)
    replaced = _pids()
    assert not set(replaced) & set(kept)
    og.compile_problem(rigid_body(), N=8, workers=2).solve(multistart=2)
    assert not set(_pids()) & set(replaced)
    assert _alive_soon() == set(_pids())  # the other grid's workers end
    og.compile_problem(rigid_body(), N=12, workers=2).solve(multistart=2)
    parallel.close()  # waits for these and for the last grid's, told to end
    assert parallel._kept is None and not parallel._ending
    assert not multiprocessing.active_children()


def test_one_set_of_workers_is_kept_when_two_threads_multistart_at_once() -> None:
    """A multi-start in a thread holds its workers while another one, in the main thread,
    forks and keeps its own: whichever ends last keeps its set and ends the other's."""
    import multiprocessing
    import threading

    parallel.close()  # workers an earlier test kept would count as the thread's
    before = len(multiprocessing.active_children())  # other children (none, or a fixture's)
    go = threading.Event()

    def held(line: str) -> None:  # the thread's multi-start waits at its first start
        go.wait(60)

    thread = threading.Thread(target=og.compile_problem(rigid_body(), N=8, workers=2).solve,
                              kwargs={"multistart": 2, "progress": held})
    thread.start()
    try:
        while len(multiprocessing.active_children()) < before + 1:  # the thread's forked
            time.sleep(0.01)
        og.compile_problem(rigid_body(), N=16, workers=2).solve(multistart=2)
        assert len(multiprocessing.active_children()) == before + 2  # both sets alive
    finally:
        go.set()
        thread.join(60)
    assert _alive_soon() == set(_pids())  # the set told to end is not waited for: it ends
    parallel.close()


def test_the_solving_process_solves_the_first_start_and_takes_its_share(monkeypatch,
                                                                       tmp_path) -> None:
    """With two workers the solving process is one of them: it solves the first start (and
    its rescue), and the worker forked beside it and it take the further starts in turn,
    each start once; progress names every start once as it is handed out."""
    import multiprocessing

    solve = Transcription.solve
    record = tmp_path / "solved"

    def spy(self, guess, *args, **kwargs):
        with open(record, "a") as out:
            out.write(f"{guess.label}\t{os.getpid()}\n")
        return solve(self, guess, *args, **kwargs)

    monkeypatch.setattr(Transcription, "solve", spy)
    progress: list[str] = []
    sol = og.compile_problem(rigid_body(), N=16, workers=2).solve(multistart=3,
                                                         progress=progress.append)
    solved = [line.split("\t") for line in record.read_text().splitlines()]
    labels = ["geodesic", "long way round", "perturbed 1", "perturbed 2", "perturbed 3"]
    assert sorted(label for label, _ in solved) == sorted(labels)
    assert dict(solved)["geodesic"] == str(os.getpid())
    workers = {int(pid) for _, pid in solved} - {os.getpid()}
    assert workers <= set(_pids()) and len(_pids()) == 1
    assert len(multiprocessing.active_children()) == 1
    handed = [line for line in progress if line.startswith("N=16: start ") and
              line.endswith(")")]
    assert sorted(handed) == sorted(f"N=16: start {i + 1}/5 ({label})"
                                    for i, label in enumerate(labels))
    assert sol.diagnostics["multistart"]["workers"] == 2
    parallel.close()


def test_an_error_in_the_solving_processs_start_is_raised_and_ends_the_workers(
        monkeypatch) -> None:
    """A start that raises in the solving process raises, as in turn; its worker, busy with
    the other starts, is ended, not kept."""
    import multiprocessing

    solve = Transcription.solve
    here = os.getpid()

    def faulty(self, guess, *args, **kwargs):
        if os.getpid() == here and guess.label == "geodesic":
            time.sleep(0.2)  # the worker is on its starts meanwhile
            raise RuntimeError("broken first start")
        return solve(self, guess, *args, **kwargs)

    monkeypatch.setattr(Transcription, "solve", faulty)
    with pytest.raises(RuntimeError, match="broken first start"):
        og.compile_problem(rigid_body(), N=16, workers=2).solve(multistart=3)
    assert parallel._kept is None and not multiprocessing.active_children()


def test_starts_are_handed_out_once_and_in_order() -> None:
    """Two processes taking starts at once get each start once, in increasing order each;
    none after the stop or the deadline; reset hands out from the second start again."""
    import multiprocessing

    ctx = multiprocessing.get_context("fork")
    shared = parallel._Shared.make(ctx, 2)
    total, far = 3001, time.monotonic() + 600
    together = ctx.Barrier(2)
    readers = []
    for w in range(2):
        mine, theirs = ctx.Pipe(duplex=False)

        def taker(w=w, theirs=theirs) -> None:
            got = []
            together.wait(60)
            while (i := shared.take(total, far, w)) is not None:
                got.append(i)
            theirs.send(got)

        proc = ctx.Process(target=taker)
        proc.start()
        readers.append((mine, proc))
    got = [mine.recv() for mine, _ in readers]
    for _, proc in readers:
        proc.join()
    assert all(g == sorted(g) for g in got)
    assert sorted(got[0] + got[1]) == list(range(1, total))
    assert [shared.taken[w] for w in range(2)] == [g[-1] if g else parallel._NONE for g in got]
    shared.reset()
    assert list(shared.taken) == [parallel._NONE] * 2
    assert shared.take(total, far, 0) == 1 and shared.taken[0] == 1
    assert shared.take(total, far, None) == 2 and shared.taken[1] == parallel._NONE
    assert shared.take(total, time.monotonic() - 1, 0) is None  # past the deadline
    shared.stop.set()
    assert shared.take(total, far, 0) is None
    shared.reset()
    assert shared.take(2, far, 0) == 1 and shared.take(2, far, 0) is None


@pytest.mark.parametrize("workers", [0, -1, 1.5, True, "2"])
def test_workers_are_checked(workers) -> None:
    with pytest.raises(ConfigError, match="workers is the number of processes"):
        og.SolverOptions(workers=workers)
    with pytest.raises(ConfigError, match="an integer >= 1"):
        og.compile_problem(rigid_body(), N=8, workers=workers)


def test_plan() -> None:
    """Never more workers than starts; one start, or workers=1, runs in turn."""
    assert parallel.plan(4, 1) == (1, "")
    assert parallel.plan(1, 9) == (1, "")
    assert parallel.plan(8, 3)[0] == 3
    assert parallel.plan(None, 9)[0] == min(parallel.cores(), 9)


def test_a_start_that_fails_in_its_worker_is_reported(monkeypatch, tmp_path) -> None:
    """One start raises in the worker, which then dies on the next: both are reported as
    failed starts, the solving process solves the start left and the best is returned."""
    solve = Transcription.solve
    here, died = os.getpid(), tmp_path / "died"

    def faulty(self, guess, *args, **kwargs):
        if os.getpid() == here and guess.label == "geodesic":  # the first start, this
            end = time.monotonic() + 60  # process's: until the worker took both faulty ones
            while not died.exists() and time.monotonic() < end:
                time.sleep(0.01)
        if os.getpid() != here and guess.label == "perturbed 1":
            raise RuntimeError("broken start")
        if os.getpid() != here and guess.label == "perturbed 2":
            died.touch()
            os._exit(3)
        return solve(self, guess, *args, **kwargs)

    monkeypatch.setattr(Transcription, "solve", faulty)  # the forked worker inherits it
    progress: list[str] = []
    sol = og.compile_problem(rigid_body(), N=16, workers=2).solve(multistart=3,
                                                         progress=progress.append)
    failed = {f["label"]: f["error"] for f in sol.diagnostics["multistart"]["failed"]}
    assert failed["perturbed 1"] == "RuntimeError: broken start"
    assert "died (exit code 3)" in failed["perturbed 2"]
    assert len(failed) == 2
    assert sol.success and sol.starts == 5 and sol.diagnostics["multistart"]["finished"] == 5
    assert any("starts done" in line for line in progress)
    assert any("failed in its worker" in line for line in progress)
    assert parallel._kept is None  # a failed start: the workers are not kept


def test_a_further_start_waits_for_the_first_starts_budget() -> None:
    """At the smallest budget a further start in a worker waits until the starts ahead of it
    (here the solving process's first) have decided it, then stops where it would have in
    turn; after a first start that failed it has no limit."""
    import threading

    shared = _as_a_worker_sees_it()
    shared.seconds.value = 1e9
    sent: list = []
    conn = type("Conn", (), {"send": lambda self, m: sent.append(m)})()
    waited = [0.0]
    further = parallel._listener(conn, 1, _batch(), shared, waited)
    assert not further(29, 1.0, 0.0)
    timer = threading.Timer(0.2, lambda: setattr(shared.budget, "value", 45))
    timer.start()
    t0 = time.perf_counter()
    assert not further(30, 1.0, 0.0)  # waited for the first start
    assert time.perf_counter() - t0 >= waited[0] >= 0.15  # not counted as solver time
    assert not further(44, 1.0, 0.0) and further(45, 1.0, 0.0)
    shared.budget.value, shared.lead.value = parallel._UNKNOWN, 1  # the first start failed
    assert not further(1000, 1.0, 0.0)
    shared.stop.set()
    assert further(1, 1.0, 0.0)


def test_the_first_start_that_succeeds_sets_the_budget() -> None:
    """Start k's budget is that of the first start before it that succeeded, none when all
    before it failed, unknown while one ahead of that first success has not ended."""
    rule = parallel.Rule(least=30, times=3, pace=3.0, least_seconds=1.0)
    failed, solved = _first(500, 9.0, success=False), _first(22, 0.55)
    assert parallel.budget_of({}, 0, rule) == (True, None)  # the first start: no limit
    assert parallel.budget_of({}, 1, rule) == (False, None)
    assert parallel.budget_of({0: failed}, 1, rule) == (True, None)
    assert parallel.budget_of({0: failed}, 2, rule) == (False, None)
    assert parallel.budget_of({0: failed, 2: solved}, 3, rule) == (False, None)
    assert parallel.budget_of({0: failed, 1: solved}, 3, rule) == \
        (True, parallel.budget_after(solved, rule))
    assert parallel.budget_of({0: solved, 1: failed}, 2, rule) == \
        (True, parallel.budget_after(solved, rule))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.booleans(), min_size=1, max_size=7), st.randoms(use_true_random=False))
def test_what_the_workers_read_is_the_budget_in_turn(outcomes: list[bool], rng) -> None:
    """Whatever order the starts end in, what a worker reads of start k's budget from the
    shared numbers (:meth:`_Shared.budget_of`) is, at every moment, what the starts ended so
    far give in turn (:func:`budget_of`)."""
    import multiprocessing

    rule = parallel.Rule(least=30, times=3, pace=3.0, least_seconds=1.0)
    shared = parallel._Shared.make(multiprocessing.get_context("fork"), 1)
    order = list(range(len(outcomes)))
    rng.shuffle(order)
    ended: dict[int, RawResult] = {}
    for i in [None, *order]:
        if i is not None:
            ended[i] = _first(10 + i, 0.1 * (i + 1), success=outcomes[i])
            shared.publish(ended, rule)
        for k in range(len(outcomes) + 1):
            known, budget = parallel.budget_of(ended, k, rule)
            seen = shared.budget_of(k)
            assert seen[0] == known
            if known:
                assert (seen[1] is None) == (budget is None)
                if budget is not None:
                    assert seen[1].iterations == budget.iterations
                    assert seen[1].seconds == pytest.approx(budget.seconds)


@pytest.mark.parametrize("workers", [1, 2])
def test_after_a_first_start_that_failed_the_next_success_sets_the_budget(
        monkeypatch, workers: int) -> None:
    """The first start fails (made to); the next one runs without a limit and succeeds, and
    its budget (here none at all: 0 iterations) stops the starts after it, in turn and in
    parallel. Before, no start after a failed first had a budget."""
    from ocgroupoid.solve import compiled

    monkeypatch.setattr(compiled, "START_BUDGET", parallel.Rule(least=0, times=0, pace=1e9,
                                                                least_seconds=1e9))
    solve = Transcription.solve

    def first_fails(self, guess, *args, **kwargs):
        r = solve(self, guess, *args, **kwargs)
        return replace(r, success=False, status="Restoration_Failed") \
            if guess.label == "geodesic" else r

    parallel.close()  # the workers to fork inherit the patch
    monkeypatch.setattr(Transcription, "solve", first_fails)
    sol = og.compile_problem(rigid_body(), N=16, workers=workers).solve(multistart=2)
    parallel.close()
    ms = sol.diagnostics["multistart"]
    assert ms["workers"] == workers and ms["finished"] == ms["starts"] == 4
    labels = [m["label"] for m in sol.minima]
    assert sol.success and sol.discretization["start"] not in ("geodesic", *ms["budget_spent"])
    assert len(ms["budget_spent"]) == 2 and "geodesic" not in ms["budget_spent"]
    assert set(ms["budget_spent"]).isdisjoint(labels)


def _as_a_worker_sees_it():
    """What a worker shares with its solving process (this test's parent, as it sees it)."""
    import multiprocessing

    shared = parallel._Shared.make(multiprocessing.get_context("fork"), 1)
    return replace(shared, parent=os.getppid())


def _batch() -> parallel._Batch:
    """A multi-start as a worker gets it: a deadline a minute away, progress never."""
    return parallel._Batch((), np.zeros(0), time.monotonic() + 60, START_BUDGET, 1e9)


def _first(iterations: int, seconds: float, success: bool = True,
           earlier: tuple = ()) -> RawResult:
    return RawResult("first", np.zeros(1), np.zeros(0), np.zeros(0), 1.0,
                     "Solve_Succeeded" if success else "Infeasible_Problem_Detected", success,
                     iterations, seconds, np.zeros(1), earlier=earlier)


def test_the_budget_follows_the_first_start() -> None:
    """max(least, times x its iterations), pace x its seconds per iteration over them but at
    least least_seconds; no budget after a first start that failed; either limit spends it."""
    rule = parallel.Rule(least=30, times=3, pace=3.0, least_seconds=1.0)
    budget = parallel.budget_after(_first(22, 0.55), rule)
    assert budget is not None and budget.iterations == 66
    assert budget.seconds == pytest.approx(3.0 * 66 * 0.55 / 22)
    assert parallel.budget_after(_first(4, 0.1), rule).iterations == 30
    assert parallel.budget_after(_first(0, 0.1), rule).seconds == pytest.approx(9.0)
    assert parallel.budget_after(_first(34, 0.01), rule).seconds == 1.0  # the floor
    assert parallel.budget_after(_first(22, 0.55, success=False), rule) is None
    assert not budget.spent(65, 4.9) and budget.spent(66, 0.0) and budget.spent(1, 5.0)


def test_the_budget_counts_every_run_of_the_first_start() -> None:
    """A first start that fatrop brought near the minimum in 51 iterations and IPOPT polished
    in 7 gives 3 x 58 iterations, at its seconds per iteration over the 58 (not 3 x 7 = 21,
    raised to 30, which stopped every further start of ``quadrotor_min_time`` at N = 256)."""
    rule = parallel.Rule(least=30, times=3, pace=3.0, least_seconds=1.0)
    polished = _first(7, 2.58, earlier=(("fatrop", "Solved_To_Acceptable_Level", 51),))
    budget = parallel.budget_after(polished, rule)
    assert budget is not None and budget.iterations == 174
    assert budget.seconds == pytest.approx(3.0 * 174 * 2.58 / 58)


def test_a_further_start_in_a_worker_is_stopped_by_its_seconds() -> None:
    """Past the seconds of its budget a further start stops at its next iteration, the
    seconds it waited for the first start not counted."""
    shared = _as_a_worker_sees_it()
    shared.budget.value, shared.seconds.value = 1000, 0.3
    conn = type("Conn", (), {"send": lambda self, m: None})()
    waited = [0.0]
    further = parallel._listener(conn, 1, _batch(), shared, waited)
    assert not further(1, 1.0, 0.0)
    time.sleep(0.2)
    waited[0] = 0.15  # as if it had waited that long at the smallest budget
    assert not further(2, 1.0, 0.0)
    time.sleep(0.3)
    assert further(3, 1.0, 0.0)


@pytest.mark.parametrize("workers", [1, 2])
def test_a_crawling_further_start_is_stopped_by_its_seconds(monkeypatch, tmp_path,
                                                              workers: int) -> None:
    """A further start whose iterations take far longer than the first start's (as the
    heavy top's from the long way round, where MUMPS reallocates) is stopped by the seconds
    of its budget long before its iterations, in turn and in parallel; the others solve."""
    solve = Transcription.solve
    record = tmp_path / "crawled"

    def slow(self, guess, p=None, listener=None, *args, **kwargs):
        if guess.label != "perturbed 1" or listener is None:
            return solve(self, guess, p, listener, *args, **kwargs)

        def crawl(iteration: int, objective: float, infeasibility: float) -> bool:
            time.sleep(0.25)
            return listener(iteration, objective, infeasibility)

        r = solve(self, guess, p, crawl, *args, **kwargs)
        record.write_text(f"{r.status} {r.iterations}")  # from a worker too
        return r

    monkeypatch.setattr(Transcription, "solve", slow)  # the forked workers inherit it
    sol = og.compile_problem(rigid_body(), N=16, workers=workers).solve(multistart=2)
    ms = sol.diagnostics["multistart"]
    assert ms["workers"] == workers and ms["finished"] == ms["starts"] == 4
    status, iterations = record.read_text().split()
    assert status == "User_Requested_Stop" and int(iterations) < START_BUDGET.least
    assert ms["budget_spent"] == ["perturbed 1"]  # reported as such, not as Ctrl-C
    assert sol.success and sol.discretization["start"] != "perturbed 1"


@pytest.mark.parametrize("workers", [1, 2])
def test_fatrops_stop_reads_the_seconds_of_a_further_start(monkeypatch, tmp_path,
                                                           workers: int) -> None:
    """fatrop's helper has no iteration callback; the ``stop()`` it polls is true once a
    further start has spent its seconds (here a budget of microseconds), never for the
    first start, in turn and in parallel."""
    from ocgroupoid.solve import compiled

    monkeypatch.setattr(compiled, "START_BUDGET", parallel.Rule(least=1000, times=1000,
                                                                pace=1e-6, least_seconds=0.0))
    solve = Transcription.solve

    def spy(self, guess, p=None, listener=None, deadline=None, stop=None, *args, **kwargs):
        # the first start ("geodesic") waits a little; the others until their stop() is true
        # (the budget is known once the first start has ended), or 10 s
        end = time.monotonic() + (0.3 if guess.label == "geodesic" else 10.0)
        while not stop() and time.monotonic() < end:
            time.sleep(0.01)
        with open(tmp_path / "stops", "a") as out:
            out.write(f"{guess.label}\t{stop()}\n")
        return solve(self, guess, p, listener, deadline, stop, *args, **kwargs)

    monkeypatch.setattr(Transcription, "solve", spy)
    sol = og.compile_problem(rigid_body(), N=16, workers=workers).solve(multistart=2)
    stops = dict(line.split("\t") for line in (tmp_path / "stops").read_text().splitlines())
    assert len(stops) == 4 and stops.pop("geodesic") == "False"
    assert sol.discretization["start"] == "geodesic"  # the others stopped by their budget
    assert set(stops.values()) == {"True"}
    assert sorted(sol.diagnostics["multistart"]["budget_spent"]) == sorted(stops)


def test_ctrl_c_stops_the_workers_with_the_best_point_so_far() -> None:
    """SIGINT to the solving process: the workers stop at their next iteration and end,
    the starts not handed out are skipped, status interrupted."""
    import multiprocessing
    import signal

    solver = og.compile_problem(heavy_top(), N=128, workers=2)
    before = signal.getsignal(signal.SIGINT)
    with sigint_after(0.5):
        sol = solver.solve(multistart=12)
    assert sol.status == "interrupted" and not sol.success
    assert sol.starts < sol.diagnostics["multistart"]["starts"]
    assert "budget_spent" not in sol.diagnostics["multistart"]  # Ctrl-C stopped them
    assert not multiprocessing.active_children()  # the workers are gone
    assert signal.getsignal(signal.SIGINT) is before


def test_problem_files_and_the_cli_set_the_workers(tmp_path) -> None:
    """``solver.workers`` of a problem file reaches the options (checked as they are); the
    summary of ``ocgroupoid solve`` shows the multi-start's workers and times."""
    from pathlib import Path

    from typer.testing import CliRunner

    from ocgroupoid.cli import app
    from ocgroupoid.files.load import load
    from ocgroupoid.files.solving import options

    so3 = Path(__file__).resolve().parent.parent / "problems" / "so3_rest_to_rest.yaml"
    assert options(load(so3, ["solver.workers=1"])).workers == 1
    assert options(load(so3)).workers is None
    with pytest.raises(ConfigError, match="workers"):
        load(so3, ["solver.workers=0"])
    out = tmp_path / "sol.json"
    r = CliRunner().invoke(app, ["solve", str(so3), "--set", "horizon.N=16",
                                 "--set", "solver.workers=2", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert "multi-start" in r.output  # the summary's row (its text wraps with the terminal)
    report = og.Solution.from_json(out).diagnostics["multistart"]
    assert report["workers"] == 2 and report["finished"] == report["starts"] > 1
