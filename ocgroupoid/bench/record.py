"""Where a benchmark writes: one JSON line per finished solve as it goes, then a summary.

``<name>.jsonl`` is opened fresh by a run and gets a line (flushed) after every solve, so an
interrupted run keeps what it finished; ``<name>.json`` (the summary, written atomically) and
the chart come at the end.
"""

from __future__ import annotations

import json
import os
import platform
import time
from pathlib import Path
from types import TracebackType
from typing import Any

import casadi

from .._version import __version__
from ..solve.solution import _jsonable, write_atomic


def machine() -> dict[str, str]:
    """What the timings were measured on (and how busy it was when the run ended)."""
    return {"python": platform.python_version(), "casadi": casadi.__version__,  # type: ignore[attr-defined]  # not in its stubs
            "ocgroupoid": __version__, "machine": platform.machine(),
            "processor": platform.processor() or "unknown", "cpus": str(os.cpu_count()),
            "load_average_1min": f"{os.getloadavg()[0]:.2f}"}


class Rows:
    """A JSONL file a run appends one record to per finished solve (module docstring)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.count = 0
        path.parent.mkdir(parents=True, exist_ok=True)
        self._file = path.open("w", encoding="utf-8")

    def append(self, record: dict[str, Any]) -> None:
        """Write ``record`` as one line and flush it to the disk."""
        self._file.write(json.dumps(_jsonable(record)) + "\n")
        self._file.flush()
        os.fsync(self._file.fileno())
        self.count += 1

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> "Rows":
        return self

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()


def read_rows(path: Path) -> list[dict[str, Any]]:
    """The records of a JSONL file (a last line cut short by an interruption is skipped)."""
    out = []
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return out


def write_summary(path: Path, data: dict[str, Any]) -> Path:
    """``data`` with the machine and the date, written atomically as indented JSON."""
    full = {**data, "created": time.strftime("%Y-%m-%d %H:%M:%S"), "machine": machine()}
    write_atomic(path, json.dumps(_jsonable(full), indent=1) + "\n")
    return path
