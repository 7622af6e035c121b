"""What the benchmark scripts (``scripts/``) share: their command line, a progress bar, the
rounding of the orders they print, and what they keep of a timed trial and print of it.

Every script takes ``--out`` (where its JSON and PNG go) and ``--quick`` (small sizes and
few repeats, for the tests); it writes its JSON with
:func:`~ocgroupoid.bench.record.write_summary` (the machine and the date added) and reports
each step as it starts on the bar of :mod:`ocgroupoid.progress` (on stderr).
"""

from __future__ import annotations

import argparse
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Callable, Iterator

from rich.console import Console

from ..errors import OcgError
from ..progress import progress_bar
from .timing import Trial

#: hears the description of every step as it starts
Step = Callable[[str], None]


def arguments(description: str, out: Path | None,
              out_help: str = "folder for JSON and PNG",
              quick_help: str = "small sizes and few repeats (CI)",
              more: Callable[[argparse.ArgumentParser], None] | None = None
              ) -> argparse.Namespace:
    """``--out`` (default ``out``) and ``--quick``, and the script's own arguments (``more``
    adds them to the parser), parsed from the command line."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--out", type=Path, default=out, help=out_help)
    ap.add_argument("--quick", action="store_true", help=quick_help)
    if more is not None:
        more(ap)
    return ap.parse_args()


@contextmanager
def steps(total: int) -> Iterator[Step]:
    """A bar over ``total`` steps on stderr: call the step with its description as each one
    starts; the bar is full when the block ends."""
    with progress_bar(Console(stderr=True)) as update:
        done = 0

        def step(description: str) -> None:
            nonlocal done
            update(description, done, total)
            done += 1

        yield step
        update("done", total, total)


def rounded(values: list[float | None], digits: int = 2) -> list[float | None]:
    """``values`` rounded for printing (None, e.g. an order with no rate to observe, kept)."""
    return [None if v is None else round(v, digits) for v in values]


def record(trial: Trial | OcgError) -> dict[str, Any]:
    """What a benchmark script keeps of a trial (or of the error that stopped its build):
    its median time, the iterations of every run (a coarse grid's first), cost and status,
    or the status ``error`` and the message."""
    if isinstance(trial, OcgError):
        return {"status": "error", "message": str(trial)}
    try:
        timed = trial.timed()
    except OcgError as e:
        return {"status": "error", "message": str(e)}
    sol = timed.solution
    return {"status": sol.status, "seconds": timed.median, "cost": sol.cost,
            "iterations": [r["iterations"] for r in sol.diagnostics["runs"]]}


def cell(d: dict[str, Any]) -> str:
    """A record as the table prints it: the iterations of every run and the median ms, with
    the status when it did not solve."""
    if "seconds" not in d:
        return str(d["status"])
    return f"{' + '.join(map(str, d['iterations']))}, {1e3 * d['seconds']:.1f}" + \
        ("" if d["status"] == "Solve_Succeeded" else f" ({d['status']})")
