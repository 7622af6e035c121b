"""A rich progress bar that appears on its first update, for the commands that run many
solves (``sweep``, ``bench``): bad input before the first solve shows only its message."""

from __future__ import annotations

from contextlib import contextmanager
from typing import Callable, Iterator

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

#: ``update(description, finished, total)``
Update = Callable[[str, int, int], None]


@contextmanager
def progress_bar(console: Console, quiet: bool = False) -> Iterator[Update]:
    """An :data:`Update` callback drawing a bar on ``console`` from its first call; silent
    when ``quiet``."""
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
