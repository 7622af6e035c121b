"""What the command line shows while a benchmark runs: a rich progress bar over its solves."""

from __future__ import annotations

from contextlib import contextmanager
from typing import Iterator

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

from .workprecision import Progress as Callback


@contextmanager
def progress_bar(console: Console, quiet: bool = False) -> Iterator[Callback]:
    """A ``(description, finished, total)`` callback drawing a bar on ``console`` from its
    first call (bad input shows only its message); silent when ``quiet``."""
    if quiet:
        yield lambda *_: None
        return
    bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                   TimeElapsedColumn(), TimeRemainingColumn(), console=console)
    task: TaskID | None = None

    def update(description: str, finished: int, total: int) -> None:
        nonlocal task
        if task is None:
            bar.start()
            task = bar.add_task(description, total=total)
        bar.update(task, completed=finished, total=total, description=description)

    try:
        yield update
    finally:
        bar.stop()
