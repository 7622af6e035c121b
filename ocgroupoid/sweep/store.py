"""A sweep's folder, written as the points finish so that an interrupted sweep resumes.

::

    DIR/sweep.json             what was swept (problem, overrides, axes, draws, point ids)
    DIR/points/<id>.json       one record per finished point: the resume marker
    DIR/solutions/<id>.json    its Solution (``ocgroupoid plot`` reads it), if IPOPT ran
    DIR/table.parquet          one row per point, rebuilt from points/ at the end

Every file is written atomically (:func:`~ocgroupoid.solve.write_atomic`), the solution
before its record: a record on disk always means a finished point.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Sequence

from ..errors import ConfigError
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

    def claim(self, resume: bool) -> None:
        """Check that a new sweep may start here: a folder holding one needs ``resume``."""
        if self.manifest.exists() and not resume:
            raise ConfigError(f"{self.root} holds a sweep already: add --resume (resume=True)"
                              " to finish it without redoing finished points, or give "
                              "another --out folder")

    def start(self, manifest: dict[str, Any]) -> None:
        """Write the manifest (what is swept)."""
        write_atomic(self.manifest, json.dumps(manifest, indent=1) + "\n")

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

    def finished(self) -> set[str]:
        """Ids of the points with a record."""
        return {p.stem for p in self.points.glob("*.json")}

    def save(self, rec: dict[str, Any], solution: str | None) -> None:
        """Write a point's solution (if any), then its record."""
        if solution is not None:
            write_atomic(self.solutions / f"{rec['id']}.json", solution + "\n")
            rec = {**rec, "solution": f"solutions/{rec['id']}.json"}
        write_atomic(self.points / f"{rec['id']}.json", json.dumps(rec) + "\n")

    def records(self, ids: Sequence[str]) -> list[dict[str, Any]]:
        """The records of ``ids`` that exist, in the order of ``ids``."""
        out = []
        for i in ids:
            path = self.points / f"{i}.json"
            if path.exists():
                out.append(json.loads(path.read_text()))
        return out
