"""The sweep's table: one row per point, a column per swept key, written as Parquet.

A swept key whose values are all numbers is a numeric column; any other (vectors,
rotations such as ``{rotvec: [0, 0, 1]}``) is its one-line YAML text. pandas and pyarrow
are imported here, when a table is made, not when ``ocgroupoid`` is.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

from ..solve import write_atomic
from .spec import yaml_text

if TYPE_CHECKING:
    import pandas as pd

#: the columns after the swept keys, in order
COLUMNS = ["status", "success", "cost", "iterations", "solve_seconds", "build_seconds",
           "nlp_built", "start", "warm", "minima", "replay_error", "message", "seconds",
           "worker", "solution"]


def _numeric(values: Sequence[Any]) -> bool:
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)


def frame(records: Sequence[dict[str, Any]], keys: Sequence[str]) -> pd.DataFrame:
    """A DataFrame of the records: ``id``, the swept keys, then :data:`COLUMNS`."""
    import pandas as pd

    data: dict[str, Any] = {"id": [r["id"] for r in records]}
    for k in keys:
        values = [r["values"][k] for r in records]
        data[k] = values if _numeric(values) else [yaml_text(v) for v in values]
    for c in COLUMNS:
        data[c] = [r.get(c) for r in records]
    df = pd.DataFrame(data)
    for c in ("cost", "replay_error"):
        df[c] = pd.to_numeric(df[c], errors="coerce").astype(float)
    df["solution"] = df["solution"].fillna("")
    return df


def write_table(path: str | Path, df: pd.DataFrame) -> Path:
    """Write ``df`` as Parquet, atomically."""
    buffer = io.BytesIO()
    df.to_parquet(buffer, index=False)
    write_atomic(path, buffer.getvalue())
    return Path(path)
