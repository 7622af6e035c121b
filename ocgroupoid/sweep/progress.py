"""What the command line shows of a sweep: a rich progress bar over points, then a summary."""

from __future__ import annotations

from contextlib import contextmanager
from typing import TYPE_CHECKING, Any, Iterator

from rich.console import Console

from .. import progress
from .run import Progress as Callback

if TYPE_CHECKING:
    import pandas as pd


@contextmanager
def progress_bar(console: Console, quiet: bool = False) -> Iterator[Callback]:
    """A :class:`~ocgroupoid.sweep.run.Progress` callback drawing a bar on ``console``
    (failed points counted in the description) from its first call, so that bad input
    shows only its message; silent when ``quiet``."""
    failed = 0
    with progress.progress_bar(console, quiet) as bar:
        def update(finished: int, total: int, rec: dict[str, Any] | None) -> None:
            nonlocal failed
            failed += rec is not None and not rec["success"]
            bar(f"points ({failed} failed)" if failed else "points", finished, total)

        yield update


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
