"""``sweep``: solve every point of a grid (or random samples) of one problem file on Dask.

The driver validates every point, groups them by NLP structure, sends chunks to the
workers (:mod:`~ocgroupoid.sweep.task`) and writes each point as it comes back
(:mod:`~ocgroupoid.sweep.store`), so an interrupted sweep resumes without redoing finished
points. A failing point is recorded with its status and message; the sweep goes on.
"""

from __future__ import annotations

import tempfile
import time
from contextlib import ExitStack, closing, contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterator, Mapping, Protocol, Sequence

from ..errors import ConfigError
from . import record
from .cluster import connect
from .source import Source
from .spec import axes, draws, points
from .store import SweepDir
from .structure import chunk_size as default_chunk_size
from .structure import chunks, classify
from .table import frame, write_table
from .task import WARM_MODES, Outcome, Task, Warm, solve_chunk

if TYPE_CHECKING:
    import pandas as pd
    from distributed import Client


class Progress(Protocol):
    """Told the number of finished points and the total: once before the first point is
    sent (``rec`` None; resumed points count as finished), then after every point."""

    def __call__(self, finished: int, total: int, rec: dict[str, Any] | None) -> None: ...


def _quiet(finished: int, total: int, rec: dict[str, Any] | None) -> None:
    return None


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
          warm: Warm = "fallback", chunk_size: int | None = None, timeout: float = 10.0,
          progress: Progress = _quiet) -> pd.DataFrame:
    """Solve one problem file at every point of a grid and/or random samples.

    >>> og.sweep("problems/so3_rest_to_rest.yaml",                     # doctest: +SKIP
    ...          grid={"final.R.axis_angle.angle": "0.5:3:6",
    ...                "parameters.inertia": [[1, 2, 3], [2, 2, 3]]})

    ``grid``: ``{key: "START:STOP:COUNT" | "[v1, v2]" | [v1, v2]}`` or the CLI's
    ``["KEY=SPEC", ...]``; ``random``: ``{key: "normal(mu, sigma)" | "uniform(a, b)"}``
    with ``samples`` draws from ``seed``; ``overrides``: ``--set`` assignments shared by
    every point. Runs on ``client``, on the scheduler at ``scheduler`` (answering within
    ``timeout`` s), or on a LocalCluster of ``workers`` processes (default: one per core).
    ``out`` keeps the sweep's folder (see :mod:`~ocgroupoid.sweep.store`); ``resume``
    continues the sweep in it. ``warm``: see :mod:`~ocgroupoid.sweep.task`.

    Returns one row per point (:func:`~ocgroupoid.sweep.table.frame`); ``df.attrs`` holds
    the run's counts: points, attempted (solved or tried in this run), invalid, resumed
    (finished in earlier runs), nlps_built (over the table), workers, seconds.
    """
    t0 = time.perf_counter()
    if warm not in WARM_MODES:
        raise ConfigError(f"warm={warm!r}: choose one of {', '.join(WARM_MODES)}")
    if chunk_size is not None and chunk_size < 1:
        raise ConfigError(f"chunk_size must be >= 1, got {chunk_size}")
    source = Source.of(problem, overrides)
    grid_axes, random_draws = axes(grid), draws(random)
    pts = points(grid_axes, random_draws, samples, seed, source.digest)
    keys = [a.key for a in grid_axes] + [d.key for d in random_draws]
    with _folder(out) as root, ExitStack() as stack:
        store = SweepDir(root)
        store.claim(resume)
        resumed = store.finished() & {p.id for p in pts} if resume else set()
        todo = [p for p in pts if p.id not in resumed]
        valid, invalid = classify(source, todo)
        if len(invalid) == len(pts):
            raise ConfigError(invalid[0][1])
        c = stack.enter_context(connect(client, scheduler, workers, timeout)) if valid else None
        store.start({"problem": source.path, "overrides": list(source.overrides),
                     "keys": keys, "grid": {a.key: list(a.values) for a in grid_axes},
                     "random": {d.key: f"{d.law}({d.a:g}, {d.b:g})" for d in random_draws},
                     "samples": samples, "seed": seed, "warm": warm,
                     "ids": [p.id for p in pts]})
        finished = len(resumed)
        progress(finished, len(pts), None)
        for p, message in invalid:
            rec = record.failed(p, record.INVALID, message)
            store.save(rec, None)
            finished += 1
            progress(finished, len(pts), rec)
        workers_used = 0
        if c is not None:
            slots = c.nthreads()  # worker -> threads: the tasks that run at once
            workers_used = len(slots)
            size = chunk_size or default_chunk_size(len(valid), sum(slots.values()))
            tasks = [Task(source, key, tuple(group), len(grid_axes), warm)
                     for key, group in chunks(valid, size)]
            with closing(_run(c, tasks)) as outcomes:
                for outcome in outcomes:
                    store.save(outcome.record, outcome.solution)
                    finished += 1
                    progress(finished, len(pts), outcome.record)
        df = frame(store.records([p.id for p in pts]), keys)
        df.attrs.update({"points": len(pts), "attempted": len(valid), "invalid": len(invalid),
                         "resumed": len(resumed), "nlps_built": int(df["nlp_built"].sum()),
                         "workers": workers_used, "seconds": time.perf_counter() - t0})
        write_table(store.table, df)
    return df


def _run(client: Client, tasks: Sequence[Task]) -> Iterator[Outcome]:
    """Submit the chunks and yield their outcomes as they finish; a chunk whose task died
    yields WORKER_LOST records. Unfinished chunks are cancelled when the caller stops
    (an interrupt), so the cluster is free for the resumed run."""
    from distributed import as_completed

    futures = {client.submit(solve_chunk, t, pure=False): t for t in tasks}
    try:
        for future in as_completed(futures):
            try:
                outcomes = future.result()
            except Exception as err:  # noqa: BLE001  (the task's error, recorded per point)
                outcomes = [Outcome(record.failed(p, record.WORKER_LOST, record.describe(err)),
                                    None) for p in futures[future].points]
            yield from outcomes
    finally:
        client.cancel(list(futures))

