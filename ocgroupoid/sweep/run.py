"""``sweep``: solve every point of a grid (or random samples) of one problem file on Dask.

The driver claims the sweep's folder (:mod:`~ocgroupoid.sweep.claim`), validates every
point, groups them by NLP structure, sends chunks to the workers
(:mod:`~ocgroupoid.sweep.dispatch`, :mod:`~ocgroupoid.sweep.task`) and writes each point as
it comes back (:mod:`~ocgroupoid.sweep.store`), so an interrupted sweep resumes without
redoing finished points. A failing point is recorded with its status and message; the sweep
goes on. A write that fails (a full disk) stops it: the table of the finished points is
written if the disk takes it, and StorageError says what to do.
"""

from __future__ import annotations

import json
import tempfile
import time
from contextlib import ExitStack, closing, contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterator, Mapping, Protocol, Sequence

from ..errors import ConfigError, StorageError
from . import estimate, extras, record
from .claim import claim
from .cluster import connect
from .dispatch import outcomes
from .source import Source
from .spec import axes, draws, points
from .store import SweepDir
from .structure import chunk_size as default_chunk_size, chunks, classify
from .table import frame, write_table
from .task import WARM_MODES, Task, Warm

if TYPE_CHECKING:
    import pandas as pd
    from distributed import Client


class Progress(Protocol):
    """Told the number of finished points and the total: once before the first point is
    sent (``rec`` None; resumed points count as finished), then after every point."""

    def __call__(self, finished: int, total: int, rec: dict[str, Any] | None) -> None: ...


def _quiet(finished: int, total: int, rec: dict[str, Any] | None) -> None:
    return None


def _silent(line: str) -> None:
    return None


#: the statuses ``resume`` solves again: the point never got a result
RETRY = (record.WORKER_LOST, record.ERROR)


@contextmanager
def _folder(out: str | Path | None) -> Iterator[Path]:
    """``out``, or a temporary folder removed afterwards (no resume without ``out``)."""
    if out is not None:
        yield Path(out)
        return
    with tempfile.TemporaryDirectory(prefix="ocgroupoid-sweep-") as tmp:
        yield Path(tmp)


def sweep(problem: str | Path | Mapping[str, Any],
          grid: Mapping[str, Any] | Sequence[str] | None = None, *,
          random: Mapping[str, str] | Sequence[str] | None = None,
          samples: int | None = None, seed: int = 0, overrides: Sequence[str] = (),
          out: str | Path | None = None, client: Client | None = None,
          scheduler: str | None = None, workers: int | None = None, resume: bool = False,
          retry_failed: bool = False, warm: Warm = "fallback", chunk_size: int | None = None,
          timeout: float = 10.0, progress: Progress = _quiet,
          report: Callable[[str], None] = _silent) -> pd.DataFrame:
    """Solve one problem file at every point of a grid and/or random samples.

    >>> og.sweep("problems/so3_rest_to_rest.yaml",                     # doctest: +SKIP
    ...          grid={"final.R.axis_angle.angle": "0.5:3:6",
    ...                "parameters.inertia": [[1, 2, 3], [2, 2, 3]]})

    ``grid``: ``{key: "START:STOP:COUNT" | "[v1, v2]" | [v1, v2]}`` or the CLI's
    ``["KEY=SPEC", ...]``; ``random``: ``{key: "normal(mu, sigma)" | "uniform(a, b)"}``
    with ``samples`` draws from ``seed``; ``overrides``: ``--set`` assignments shared by
    every point. Runs on ``client``, on the scheduler at ``scheduler`` (answering within
    ``timeout`` s), or on a LocalCluster of ``workers`` processes (default: one per core).
    ``out`` keeps the sweep's folder (see :mod:`~ocgroupoid.sweep.store`), claimed for this
    sweep alone (:mod:`~ocgroupoid.sweep.claim`); ``resume`` continues the sweep in it, of
    the same grid, solving again the points whose worker was lost or that raised an error
    (with ``retry_failed``, every point that did not succeed). ``warm``: see
    :mod:`~ocgroupoid.sweep.task`. ``report`` hears the estimate of points, disk and time
    (:mod:`~ocgroupoid.sweep.estimate`).

    Returns one row per point (:func:`~ocgroupoid.sweep.table.frame`); ``df.attrs`` holds
    the run's counts: points, attempted (solved or tried in this run), invalid, resumed
    (finished in earlier runs), nlps_built (over the table), workers, seconds. A write that
    fails raises StorageError after the table of the finished points is written.
    """
    t0 = time.perf_counter()
    extras.require()
    if warm not in WARM_MODES:
        raise ConfigError(f"warm={warm!r}: choose one of {', '.join(WARM_MODES)}")
    if chunk_size is not None and chunk_size < 1:
        raise ConfigError(f"chunk_size must be >= 1, got {chunk_size}")
    if retry_failed and not resume:
        raise ConfigError("--retry-failed (retry_failed=True) solves the failed points of an "
                          "earlier run again: add --resume (resume=True)")
    source = Source.of(problem, overrides)
    grid_axes, random_draws = axes(grid), draws(random)
    pts = points(grid_axes, random_draws, samples, seed, source.digest)
    keys = [a.key for a in grid_axes] + [d.key for d in random_draws]
    manifest = {"problem": source.path, "overrides": list(source.overrides),
                "source": source.digest, "keys": keys,
                "grid": {a.key: list(a.values) for a in grid_axes},
                "random": {d.key: f"{d.law}({d.a:g}, {d.b:g})" for d in random_draws},
                "samples": samples, "seed": seed, "warm": warm, "ids": [p.id for p in pts]}
    with _folder(out) as root, claim(root, SweepDir(root).manifest, manifest, resume), \
            ExitStack() as stack:
        store = SweepDir(root)
        retry = (*RETRY, "failed") if retry_failed else RETRY
        resumed = store.finished(retry) & {p.id for p in pts} if resume else set()
        todo = [p for p in pts if p.id not in resumed]
        report(f"validating {len(todo)} points")
        valid, invalid = classify(source, todo)
        if len(invalid) == len(pts):
            raise ConfigError(invalid[0][1])
        report(estimate.before(len(pts), len(valid), len(resumed), len(invalid), store.root))
        c = stack.enter_context(connect(client, scheduler, workers, timeout)) if valid else None
        finished = len(resumed)
        progress(finished, len(pts), None)
        run = _Run(store, len(pts), finished, progress, report)
        try:
            for p, message in invalid:
                run.save(record.failed(p, record.INVALID, message), None)
            workers_used = 0
            if c is not None:
                slots = c.nthreads()  # worker -> threads: the tasks that run at once
                workers_used = len(slots)
                size = chunk_size or default_chunk_size(len(valid), sum(slots.values()))
                tasks = [Task(source, key, tuple(group), len(grid_axes), warm)
                         for key, group in chunks(valid, size)]
                run.start(len(valid), len(tasks), sum(slots.values()))
                with closing(outcomes(c, tasks, sum(slots.values()))) as results:
                    for chunk in results:
                        for outcome in chunk:
                            run.save(outcome.record, outcome.solution)
                        run.chunk_done()
        except StorageError as err:
            raise StorageError(_stopped(store, [p.id for p in pts], keys, err)) from None
        df = frame(store.records([p.id for p in pts]), keys)
        df.attrs.update({"points": len(pts), "attempted": len(valid), "invalid": len(invalid),
                         "resumed": len(resumed), "nlps_built": int(df["nlp_built"].sum()),
                         "workers": workers_used, "seconds": time.perf_counter() - t0})
        try:
            write_table(store.table, df)
        except OSError as err:
            raise StorageError(f"writing {store.table}: {err.strerror or err}; every point is "
                               f"done and recorded in {store.points}: free space, then run "
                               "the sweep again with --resume to write the table") from None
    return df


class _Run:
    """The points stored so far: progress after each, the time estimate once the first chunk
    is stored (:mod:`~ocgroupoid.sweep.estimate`)."""

    def __init__(self, store: SweepDir, total: int, finished: int, progress: Progress,
                 report: Callable[[str], None]) -> None:
        self.sweep_dir, self.total, self.finished = store, total, finished
        self.progress, self.report = progress, report
        self.to_solve = self.chunks = self.slots = self.done = self.written = 0
        self.t0: float | None = None  # when the work started
        self.reported = False

    def start(self, points: int, chunks: int, slots: int) -> None:
        """The work starts: ``points`` to solve in ``chunks`` on ``slots`` task slots."""
        self.to_solve, self.chunks, self.slots = points, chunks, slots
        self.t0 = time.perf_counter()

    def save(self, rec: dict[str, Any], solution: str | None) -> None:
        """Write a point (StorageError if the disk refuses), then tell progress."""
        self.sweep_dir.save(rec, solution)
        self.finished += 1
        self.progress(self.finished, self.total, rec)
        if self.t0 is not None:
            self.done += 1
            self.written += len(solution or "") + len(json.dumps(rec))

    def chunk_done(self) -> None:
        """After the first chunk, if more follow: the estimate of the time left."""
        self.chunks -= 1
        if self.t0 is not None and not self.reported and self.chunks > 0:
            self.reported = True
            self.report(estimate.after_first(self.done, time.perf_counter() - self.t0,
                                             self.to_solve - self.done, self.written,
                                             self.slots))


def _stopped(store: SweepDir, ids: list[str], keys: list[str], err: StorageError) -> str:
    """The message of a sweep stopped by a write error, after writing the table of what is
    done (if the disk takes it)."""
    done = store.records(ids)
    try:
        write_table(store.table, frame(done, keys))
        table = f"they are in {store.table}"
    except OSError as again:
        table = f"the table could not be written either ({again.strerror or again})"
    return (f"{err}; the sweep stopped: {len(done)} of {len(ids)} points are done and kept "
            f"({table}); free space (or fix the folder), then finish with --resume")
