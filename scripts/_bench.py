"""Shared helpers of the benchmark scripts: timing, progress, JSON and PNG output."""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from pathlib import Path
from typing import Any, Callable

import casadi
import numpy as np
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from ocgroupoid.solve.solution import _jsonable, write_atomic

RESULTS = Path(__file__).resolve().parent.parent / "results"


def arguments(description: str) -> argparse.Namespace:
    """--out (results folder) and --quick (small sizes, for CI)."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--out", type=Path, default=RESULTS, help="folder for JSON and PNG")
    ap.add_argument("--quick", action="store_true", help="small sizes and few repeats (CI)")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)  # results/ is not tracked: made on first use
    return args


def progress() -> Progress:
    return Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                    TimeElapsedColumn(), transient=False)


def median_time(fn: Callable[[], Any], repeats: int) -> tuple[float, Any]:
    """Median wall time of ``fn()`` over ``repeats`` calls, and the last result."""
    times, result = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def machine() -> dict[str, str]:
    return {"python": platform.python_version(), "casadi": casadi.__version__,
            "machine": platform.machine(), "processor": platform.processor() or "unknown"}


def save(out: Path, stem: str, data: dict[str, Any]) -> Path:
    """Write ``stem.json`` atomically; return its path."""
    path = out / f"{stem}.json"
    write_atomic(path, json.dumps(_jsonable({**data, "machine": machine()}), indent=1) + "\n")
    return path


def order(values: list[float]) -> list[float]:
    """Observed orders log2(e_N / e_2N) of a sequence on grids that double."""
    v = np.asarray(values, dtype=float)
    return np.log2(v[:-1] / v[1:]).tolist()
