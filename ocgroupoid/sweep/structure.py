"""Which points share one NLP, and the chunks of points that a worker solves in a row.

Parameter values, boundary values and a fixed T go through the NLP's parameter vector p;
anything else (model, definition, N, scheme, retraction, rule, IPOPT options, multi-start,
continuation, whatever else the file holds) and the set of prescribed boundary components
count as the NLP's structure. The
structure key is that part of a validated problem file, so points with equal keys are
solved by one compiled NLP.
"""

from __future__ import annotations

import json
import math
from typing import TYPE_CHECKING, Any, Sequence

from ..errors import OcgError
from .source import Source
from .spec import Point

if TYPE_CHECKING:
    from ..files import Config

VALUE_SECTIONS = {"parameters", "initial", "final", "output"}


def prescribed(value: Any) -> Any:
    """Which parts of a boundary value are given (True) or free (False), component by
    component for lists; validated rotations (arrays) are one given value."""
    if value is None:
        return False
    if isinstance(value, (list, tuple)):
        return [prescribed(v) for v in value]
    if isinstance(value, dict):
        return {k: prescribed(v) for k, v in value.items()}
    return True


def structure_key(cfg: Config) -> str:
    """Everything of a validated problem file that changes the NLP, as canonical JSON."""
    top = cfg.file.model_dump(mode="json", exclude=VALUE_SECTIONS)
    if isinstance(top["horizon"].get("T"), (int, float)):  # a fixed T is a value; others
        top["horizon"].pop("T")                              # (a free T) are structure
    ends = {"initial": prescribed(cfg.initial.model_dump()),
            "final": prescribed(cfg.final.model_dump())}
    return json.dumps([cfg.name, top, ends], sort_keys=True)


def classify(source: Source, pts: Sequence[Point]
             ) -> tuple[list[tuple[str, Point]], list[tuple[Point, str]]]:
    """Validate every point: (structure key, point) of the valid ones, (point, message) of
    the others (a value the problem file rejects, e.g. a negative T)."""
    from ..files import fixed_grid

    valid, invalid = [], []
    for p in pts:
        try:
            cfg = source.load(p.overrides)
            fixed_grid(cfg, "a sweep")  # one compiled NLP per structure
            valid.append((structure_key(cfg), p))
        except OcgError as err:
            invalid.append((p, str(err)))
    return valid, invalid


def chunk_size(points: int, slots: int, largest: int = 8) -> int:
    """About two chunks per task slot (a worker thread; balance), at most ``largest``
    points (progress, and what an interrupt loses)."""
    return max(1, min(largest, math.ceil(points / (2 * max(slots, 1)))))


def chunks(keyed: Sequence[tuple[str, Point]], size: int) -> list[tuple[str, list[Point]]]:
    """Points grouped by structure (in sweep order, so grid neighbours stay together), each
    group cut into runs of ``size``."""
    groups: dict[str, list[Point]] = {}
    for key, p in keyed:
        groups.setdefault(key, []).append(p)
    return [(key, group[i:i + size]) for key, group in groups.items()
            for i in range(0, len(group), size)]
