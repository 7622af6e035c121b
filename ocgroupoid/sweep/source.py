"""The base problem of a sweep: a problem file's data, its name and the ``--set`` overrides.

A Source is plain data (a dict from ``yaml.safe_load``), so it travels to Dask workers by
pickle; every worker loads and builds its points itself (CasADi objects never travel).
"""

from __future__ import annotations

import copy
import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping, Sequence

from ..errors import ConfigError

if TYPE_CHECKING:  # the files layer is imported when a sweep runs, not with ocgroupoid
    from ..files import Config


@dataclass(frozen=True)
class Source:
    """Problem-file data, the file's path (for messages and the problem's default name, its
    stem) and the overrides every point shares."""

    path: str | None
    data: dict[str, Any]
    overrides: tuple[str, ...] = ()

    @staticmethod
    def of(problem: str | Path | Mapping[str, Any], overrides: Sequence[str] = ()) -> Source:
        """A Source from a problem file path or from its data (a dict, as YAML reads it)."""
        if isinstance(problem, Mapping):
            return Source(None, copy.deepcopy(dict(problem)), tuple(overrides))
        if isinstance(problem, (str, Path)):
            from ..files.source import read_yaml

            data, _ = read_yaml(problem)
            return Source(str(problem), data, tuple(overrides))
        raise ConfigError(f"sweep takes a problem file (path) or its data (a dict), got a "
                          f"{type(problem).__name__}; write the problem as YAML (see problems/)")

    @property
    def digest(self) -> str:
        """A digest of the name, data and overrides: point ids depend on it, so a sweep of a
        changed file never reuses the points of the old one."""
        name = Path(self.path).name if self.path else None
        text = json.dumps([name, self.data, list(self.overrides)], sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()

    def load(self, point_overrides: Sequence[str] = ()) -> Config:
        """The validated Config of one point (a fresh copy of the data: overrides mutate)."""
        from ..files import load

        return load(self.path, [*self.overrides, *point_overrides],
                    data=copy.deepcopy(self.data))
