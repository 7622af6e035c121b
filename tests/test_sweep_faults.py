"""Sweeps under faults (issue 30): one sweep per folder, a resume only of the same grid, lost
and errored points retried, a full disk stops cleanly, finished chunks released, an estimate
before the work, bad bounds recorded invalid, a missing extra named in one line."""

from __future__ import annotations

import errno
import json
import multiprocessing
import sys
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid.cli import app
from ocgroupoid.errors import ConfigError, DependencyError, StorageError
from ocgroupoid.sweep import dispatch, store, table

ROOT = Path(__file__).resolve().parent.parent
SO3 = ROOT / "problems" / "so3_rest_to_rest.yaml"
SETS = ["horizon.N=16"]
ANGLES = "final.R.axis_angle.angle"
runner = CliRunner()


def one_line(text: str) -> str:
    return " ".join(text.split())


# -- one sweep per folder (items 1 and 2) ------------------------------------------------------

RACE_TRIALS = 10


def race(barrier: Any, folders: list[str], results: Any) -> None:
    """One of two processes that start a sweep into the same folder at the same moment, once
    per trial (a spawned process: it has its own in-process Dask cluster)."""
    from distributed import Client

    with Client(processes=False, n_workers=1, threads_per_worker=1,
                dashboard_address=None) as c:
        for folder in folders:
            barrier.wait(timeout=120)
            try:
                df = og.sweep(SO3, {ANGLES: "[0.5, 1.0]"}, overrides=SETS, out=folder, client=c)
                results.put((folder, "ran", len(df)))
            except ConfigError as err:
                results.put((folder, "refused", str(err)))


def test_two_sweeps_started_at_once_into_one_folder_one_proceeds(tmp_path: Path) -> None:
    ctx = multiprocessing.get_context("spawn")
    barrier, results = ctx.Barrier(2), ctx.Queue()
    folders = [str(tmp_path / f"trial{i}") for i in range(RACE_TRIALS)]
    procs = [ctx.Process(target=race, args=(barrier, folders, results)) for _ in range(2)]
    for p in procs:
        p.start()
    outcomes: dict[str, list[tuple[str, Any]]] = {f: [] for f in folders}
    for _ in range(2 * RACE_TRIALS):
        folder, kind, detail = results.get(timeout=300)
        outcomes[folder].append((kind, detail))
    for p in procs:
        p.join(timeout=60)
    for folder, got in outcomes.items():
        kinds = sorted(k for k, _ in got)
        assert kinds == ["ran", "refused"], (folder, got)
        refusal = next(d for k, d in got if k == "refused")
        assert "another sweep is running" in refusal or "holds a sweep already" in refusal
        manifest = json.loads((Path(folder) / "sweep.json").read_text())
        assert len(manifest["ids"]) == 2 and len(pd.read_parquet(Path(folder) /
                                                                  "table.parquet")) == 2


def test_resume_of_another_grid_is_refused_naming_the_difference(client: Any,
                                                                   tmp_path: Path) -> None:
    out = tmp_path / "s"
    first = og.sweep(SO3, {ANGLES: "0.5:2:4"}, overrides=SETS, out=out, client=client)
    manifest = (out / "sweep.json").read_text()
    with pytest.raises(ConfigError) as err:
        og.sweep(SO3, {ANGLES: "0.5:2:2"}, overrides=SETS, out=out, client=client, resume=True)
    assert "has 2 values (0.5, 2.0) here, 4 values (0.5, 1.0, 1.5, ...) there" in str(err.value)
    with pytest.raises(ConfigError, match="--set is horizon.N=12 here, horizon.N=16 there"):
        og.sweep(SO3, {ANGLES: "0.5:2:4"}, overrides=["horizon.N=12"], out=out, resume=True)
    r = runner.invoke(app, ["sweep", str(SO3), "--grid", "horizon.T=4:6:2", "--set", SETS[0],
                            "--out", str(out), "--resume"])
    assert r.exit_code == 2 and "Traceback" not in r.output
    assert f"--grid {ANGLES} is swept there, not here" in one_line(r.output)
    assert (out / "sweep.json").read_text() == manifest
    assert len(pd.read_parquet(out / "table.parquet")) == len(first) == 4


def test_a_sweep_running_in_a_folder_keeps_others_out(client: Any, tmp_path: Path) -> None:
    """The lock holds while the sweep runs: even a resume of the same grid waits its turn."""
    out = tmp_path / "s"
    refused: list[str] = []

    def progress(finished: int, total: int, rec: Any) -> None:
        if rec is None:  # the first sweep holds the folder now: start a second one
            with pytest.raises(ConfigError) as err:
                og.sweep(SO3, {ANGLES: "[0.5, 1.0]"}, overrides=SETS, out=out, resume=True)
            refused.append(str(err.value))

    df = og.sweep(SO3, {ANGLES: "[0.5, 1.0]"}, overrides=SETS, out=out, client=client,
                  progress=progress)
    assert df["success"].all() and len(refused) == 1
    assert "another sweep is running in this folder (pid" in refused[0]
    again = og.sweep(SO3, {ANGLES: "[0.5, 1.0]"}, overrides=SETS, out=out, resume=True)
    assert again.attrs["resumed"] == 2  # the lock went with the first sweep


# -- lost and errored points (item 3) ----------------------------------------------------------

def rewrite(out: Path, point: str, **changes: Any) -> None:
    path = out / "points" / f"{point}.json"
    path.write_text(json.dumps({**json.loads(path.read_text()), **changes}) + "\n")


def test_resume_solves_lost_and_errored_points_again(client: Any, tmp_path: Path) -> None:
    out = tmp_path / "s"
    df = og.sweep(SO3, {ANGLES: "0.5:2:4"}, overrides=SETS, out=out, client=client)
    ids = list(df["id"])
    # what a run whose worker died, or whose point raised, leaves behind
    rewrite(out, ids[0], status="worker_lost", success=False, cost=None,
            message="KilledWorker: the worker died")
    rewrite(out, ids[1], status="error", success=False, cost=None, message="RuntimeError: x")
    rewrite(out, ids[2], status="Maximum_Iterations_Exceeded", success=False)
    again = og.sweep(SO3, {ANGLES: "0.5:2:4"}, overrides=SETS, out=out, client=client,
                     resume=True)
    assert again.attrs["attempted"] == 2 and again.attrs["resumed"] == 2
    assert list(again["status"]) == ["Solve_Succeeded", "Solve_Succeeded",
                                     "Maximum_Iterations_Exceeded", "Solve_Succeeded"]
    failed = og.sweep(SO3, {ANGLES: "0.5:2:4"}, overrides=SETS, out=out, client=client,
                      resume=True, retry_failed=True)
    assert failed.attrs["attempted"] == 1 and failed["success"].all()
    assert list(failed["cost"]) == list(df["cost"])
    r = runner.invoke(app, ["sweep", str(SO3), "--grid", f"{ANGLES}=0.5:2:4", "--set", SETS[0],
                            "--out", str(out), "--retry-failed"])
    assert r.exit_code == 2 and "add --resume" in one_line(r.output)


# -- a full disk (item 4) ----------------------------------------------------------------------

def full_disk(monkeypatch: pytest.MonkeyPatch, after: int, table_too: bool) -> list[str]:
    """Writes of point files fail with ENOSPC after ``after`` of them (and the table's,
    with ``table_too``); the names written."""
    written: list[str] = []
    real = store.write_atomic

    def writer(path: Any, data: Any) -> None:
        if len(written) >= after:
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        real(path, data)
        written.append(Path(path).name)

    def table_writer(path: Any, data: Any) -> None:
        if table_too:
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        real(path, data)

    monkeypatch.setattr(store, "write_atomic", writer)
    monkeypatch.setattr(table, "write_atomic", table_writer)
    return written


@pytest.mark.parametrize("table_too", [False, True])
def test_a_full_disk_stops_the_sweep_cleanly(client: Any, tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch,
                                             table_too: bool) -> None:
    out = tmp_path / "s"
    full_disk(monkeypatch, after=6, table_too=table_too)  # 3 points: solution and record
    with pytest.raises(StorageError) as err:
        og.sweep(SO3, {ANGLES: "0.5:2:8"}, overrides=SETS, out=out, client=client,
                 chunk_size=2)
    message = str(err.value)
    assert "No space left on device" in message and "3 of 8 points are done" in message
    assert "--resume" in message
    if table_too:
        assert "the table could not be written either" in message
        assert not (out / "table.parquet").exists()
    else:
        assert len(pd.read_parquet(out / "table.parquet")) == 3
    files = [p for p in out.rglob("*") if p.is_file()]
    assert not [p for p in files if p.name.startswith(".") and p.name != ".sweep.lock"]
    records = [json.loads(p.read_text()) for p in (out / "points").glob("*.json")]
    assert len(records) == 3 and all((out / r["solution"]).is_file() for r in records)
    monkeypatch.undo()
    done = og.sweep(SO3, {ANGLES: "0.5:2:8"}, overrides=SETS, out=out, client=client,
                    resume=True)
    assert done["success"].all() and done.attrs["resumed"] == 3


def test_a_full_disk_is_exit_code_3_with_one_line(monkeypatch: pytest.MonkeyPatch,
                                                  tmp_path: Path) -> None:
    def stopped(*args: Any, **kwargs: Any) -> None:
        raise StorageError("writing s/points/x.json: No space left on device; the sweep "
                           "stopped: 3 of 8 points are done and kept")

    monkeypatch.setattr(sys.modules["ocgroupoid.sweep"], "sweep", stopped)
    r = runner.invoke(app, ["sweep", str(SO3), "--grid", f"{ANGLES}=0.5:2:8", "--out",
                            str(tmp_path / "s")])
    assert r.exit_code == 3 and "No space left on device" in r.output
    assert "Traceback" not in r.output


# -- memory and the estimate (item 5) ----------------------------------------------------------

def test_finished_chunks_are_released(client: Any, tmp_path: Path) -> None:
    held: list[int] = []

    def progress(finished: int, total: int, rec: Any) -> None:
        if rec is not None:
            held.append(len(client.futures))

    df = og.sweep(SO3, {ANGLES: "0.5:2:24"}, overrides=SETS, out=tmp_path / "s",
                  client=client, chunk_size=2, progress=progress)
    assert df["success"].all() and len(held) == 24
    slots = sum(client.nthreads().values())
    # bounded by what is in flight, not by the points done (a future released a moment ago
    # may still be registered with the client: one more)
    assert max(held) <= dispatch.IN_FLIGHT * slots + 1 < 12  # 12 chunks
    assert min(held[-4:]) <= 1  # the last chunks: nothing else queued


def test_local_workers_run_without_the_profiler() -> None:
    """Dask's statistical profiler kept an hour of stack samples per worker: 40 kB a point
    (55 kB with the futures held; 2 kB now, over 1600 so3 points)."""
    from ocgroupoid.sweep.cluster import connect

    with connect(workers=1) as c:
        enabled = c.run(lambda: __import__("dask").config.get(
            "distributed.worker.profile.enabled"))
    assert list(enabled.values()) == [False]


def test_the_estimate_comes_before_the_work(client: Any, tmp_path: Path) -> None:
    events: list[str] = []
    df = og.sweep(SO3, {ANGLES: "0.5:2:12"}, overrides=SETS, out=tmp_path / "s",
                  client=client, chunk_size=2,
                  progress=lambda f, t, rec: events.append("point" if rec else "start"),
                  report=lambda line: events.append(line))
    assert len(df) == 12
    first_point = events.index("point")
    before = [e for e in events[:first_point] if e not in ("start", "point")]
    assert before[0] == "validating 12 points"
    assert before[1].startswith("12 points: 12 to solve; about 420 kB on disk (~35 kB a point)")
    after = [e for e in events[first_point:] if e.startswith("first chunk back: 2 points in ")]
    assert len(after) == 1 and "the 10 left take about" in after[0]
    r = runner.invoke(app, ["sweep", "--help"])
    assert "about 35 kB a point" in one_line(r.output)
    assert "once the first chunk is back the time the rest will take" in one_line(r.output)


# -- smaller (items 9 and 11) ------------------------------------------------------------------

def test_bounds_with_lower_above_upper_are_invalid(client: Any, tmp_path: Path) -> None:
    df = og.sweep(ROOT / "problems" / "so3_minimum_time.yaml",
                  {"bounds.u": "[[-0.5, 0.5], [0.5, -0.5]]"}, overrides=SETS, client=client)
    assert list(df["status"]) == ["Solve_Succeeded", "invalid"]
    assert "lower 0.5 > upper -0.5" in df.loc[1, "message"]


def test_a_sweep_without_the_extra_names_it(monkeypatch: pytest.MonkeyPatch,
                                            tmp_path: Path) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)  # as after `pip install -e .`
    r = runner.invoke(app, ["sweep", str(SO3), "--grid", f"{ANGLES}=0.5:2:2", "--out",
                            str(tmp_path / "s")])
    assert r.exit_code == 2, r.output
    assert 'pip install -e ".[sweep]"' in one_line(r.output) and "dask[distributed]" in r.output
    assert "Traceback" not in r.output and len(r.output.strip().splitlines()) <= 2
    with pytest.raises(DependencyError, match="sweep extra"):
        og.sweep(SO3, {ANGLES: "0.5:2:2"})
    assert not (tmp_path / "s").exists()
