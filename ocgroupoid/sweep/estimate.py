"""What a sweep will cost, said before the work starts: points, disk, then time.

Before the first point is sent: the number of points (how many run now, how many are
finished or invalid) and the disk they take, at :data:`DISK_PER_POINT` a point, against the
free space of the folder. Once the first chunk is back: the time the rest will take at the
rate measured so far (the cluster's start-up and the first NLP builds are in it, so it errs
long), and the disk per point measured on that chunk.
"""

from __future__ import annotations

import shutil
from pathlib import Path

#: bytes on disk a point takes before one is measured: its record (~1 kB) and its solution
#: JSON (~30 kB for so3 at N = 32; proportional to N and the state's size)
DISK_PER_POINT = 35_000


def _bytes(n: float) -> str:
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n:.0f} B"


def _seconds(s: float) -> str:
    if s >= 5400:
        return f"{s / 3600:.1f} h"
    if s >= 90:
        return f"{s / 60:.0f} min"
    return f"{s:.0f} s"


def free_bytes(folder: Path) -> int | None:
    """Free space where ``folder`` is (or would be), None if the system does not say."""
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    try:
        return shutil.disk_usage(folder).free
    except OSError:
        return None


def before(points: int, run: int, resumed: int, invalid: int, folder: Path,
           per_point: float = DISK_PER_POINT) -> str:
    """The line shown before the work starts."""
    need = run * per_point
    free = free_bytes(folder)
    room = "" if free is None else f", {_bytes(free)} free" + (
        " (too little: the sweep stops when the disk is full; free space or choose another "
        "--out)" if need > free else "")
    return (f"{points} points: {run} to solve" + (f", {resumed} finished before" if resumed
                                                  else "")
            + (f", {invalid} invalid" if invalid else "")
            + f"; about {_bytes(need)} on disk (~{_bytes(per_point)} a point){room}; the time "
            "follows the first chunk")


def after_first(done: int, seconds: float, left: int, written: int, slots: int) -> str:
    """The line shown once the first chunk is back: ``done`` points in ``seconds`` since the
    work started, ``left`` to go, ``written`` bytes written for the ``done`` points; the
    ``slots`` task slots each solve a chunk at that pace."""
    rate = done * max(slots, 1) / seconds if seconds > 0 else float("inf")
    per_point = written / done if done else DISK_PER_POINT
    return (f"first chunk back: {done} points in {seconds:.1f} s; the {left} left take about "
            f"{_seconds(left / rate)} at that pace on {slots} worker thread"
            f"{'s' if slots != 1 else ''} and {_bytes(left * per_point)} on disk "
            f"({_bytes(per_point)} a point)")
