"""A sweep's folder, written as the points finish so that an interrupted sweep resumes.

::

    DIR/sweep.json             what was swept (problem, overrides, axes, draws, point ids,
                               the grid's digest): written once, when the sweep claims DIR
    DIR/.sweep.lock            locked while a sweep runs (:mod:`~ocgroupoid.sweep.claim`)
    DIR/points/<id>.json       one record per finished point: the resume marker
    DIR/solutions/<id>.json    its Solution (``ocgroupoid plot`` reads it), if IPOPT ran
    DIR/table.parquet          one row per point, rebuilt from points/ at the end

Every file is written atomically (:func:`~ocgroupoid.solve.write_atomic`), the solution
before its record: a record on disk always means a finished point. A write that fails (a
full disk, a read-only folder) raises :class:`~ocgroupoid.errors.StorageError`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Collection, Sequence

from ..errors import ConfigError, StorageError
from ..solve import write_atomic

MANIFEST = "sweep.json"
TABLE = "table.parquet"


class SweepDir:
    """The files of one sweep under ``root``."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)
        self.manifest = self.root / MANIFEST
        self.points = self.root / "points"
        self.solutions = self.root / "solutions"
        self.table = self.root / TABLE

    def read_manifest(self) -> dict[str, Any]:
        """The manifest, or ConfigError naming the folder."""
        try:
            return json.loads(self.manifest.read_text())
        except FileNotFoundError:
            raise ConfigError(f"{self.root}: no {MANIFEST}; give a folder written by "
                              "`ocgroupoid sweep --out DIR`") from None
        except (json.JSONDecodeError, UnicodeDecodeError) as err:
            raise ConfigError(f"{self.manifest}: not a sweep manifest ({err}); run the "
                              "sweep again with --resume") from None

    def finished(self, retry: Collection[str] = ()) -> set[str]:
        """Ids of the points with a record, except those whose status is in ``retry`` (a
        resumed sweep solves them again); ``"failed"`` in ``retry`` stands for every point
        that did not succeed."""
        done = set()
        for path in self.points.glob("*.json"):
            if retry:
                try:
                    rec = json.loads(path.read_text())
                except (OSError, ValueError):
                    continue  # not a whole record: solve the point again
                if rec.get("status") in retry or ("failed" in retry and not rec.get("success")):
                    continue
            done.add(path.stem)
        return done

    def save(self, rec: dict[str, Any], solution: str | None) -> None:
        """Write a point's solution (if any; else an earlier attempt's is removed), then its
        record; StorageError when the disk refuses (the point then has no record)."""
        target = self.solutions / f"{rec['id']}.json"
        try:
            if solution is not None:
                write_atomic(target, solution + "\n")
                rec = {**rec, "solution": f"solutions/{rec['id']}.json"}
            else:
                target.unlink(missing_ok=True)
            write_atomic(self.points / f"{rec['id']}.json", json.dumps(rec) + "\n")
        except OSError as err:
            raise StorageError(f"writing {err.filename or self.root}: {err.strerror or err}"
                               ) from None

    def records(self, ids: Sequence[str]) -> list[dict[str, Any]]:
        """The records of ``ids`` that exist, in the order of ``ids``."""
        out = []
        for i in ids:
            path = self.points / f"{i}.json"
            if path.exists():
                out.append(json.loads(path.read_text()))
        return out
