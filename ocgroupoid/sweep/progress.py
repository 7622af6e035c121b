"""What the command line shows of a sweep: a rich progress bar over points, then a summary."""

from __future__ import annotations

from contextlib import contextmanager
from typing import TYPE_CHECKING, Any, Iterator

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from .run import Progress as Callback

if TYPE_CHECKING:
    import pandas as pd


@contextmanager
def progress_bar(console: Console, quiet: bool = False) -> Iterator[Callback]:
    """A :class:`~ocgroupoid.sweep.run.Progress` callback drawing a bar on ``console``
    (failed points counted in the description) from its first call, so that bad input
    shows only its message; silent when ``quiet``."""
    if quiet:
        yield lambda finished, total, rec: None
        return
    bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                   TimeElapsedColumn(), TimeRemainingColumn(), console=console)
    task: TaskID | None = None
    failed = 0

    def update(finished: int, total: int, rec: dict[str, Any] | None) -> None:
        nonlocal task, failed
        if task is None:
            bar.start()
            task = bar.add_task("points", total=total)
        failed += rec is not None and not rec["success"]
        bar.update(task, completed=finished, total=total,
                   description=f"points ({failed} failed)" if failed else "points")

    try:
        yield update
    finally:
        bar.stop()


def summary(df: pd.DataFrame) -> str:
    """Two lines: points and failures by status; this run's workers, time, rate and builds."""
    a = df.attrs
    failed = df.loc[~df["success"].astype(bool), "status"].value_counts()
    failures = ", ".join(f"{n} {status}" for status, n in failed.items()) or "none failed"
    rate = a["attempted"] / a["seconds"] if a["seconds"] > 0 else float("nan")
    return (f"{len(df)} points: {len(df) - int(failed.sum())} solved, {failures}\n"
            f"{a['attempted']} run now ({a['resumed']} finished before) on {a['workers']} "
            f"worker(s) in {a['seconds']:.1f} s ({rate:.2f} points/s); "
            f"{a['nlps_built']} NLP(s) built for {len(df)} points")
