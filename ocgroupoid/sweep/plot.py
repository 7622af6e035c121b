"""The figure of a sweep's folder: cost against each swept key, failed points marked.

One panel per swept key. Successful points are dots; along a grid key they are joined by a
line where the other keys are equal (a grid's rows). Failed points are red crosses on the
panel's floor, counted by status in the legend. Keys with non-numeric values (vectors,
rotations) are categories.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigError
from ..solve import write_atomic
from . import extras
from .store import SweepDir
from .table import frame


def _positions(values: Any) -> tuple[np.ndarray, list[str] | None]:
    """x positions of a column, and tick labels when it is categorical."""
    if values.dtype.kind in "if":
        return values.to_numpy(dtype=float), None
    labels = list(dict.fromkeys(values.tolist()))
    return np.array([labels.index(v) for v in values], dtype=float), labels


def _lines(df: Any, key: str, keys: list[str]) -> list[np.ndarray]:
    """Rows of the points that differ only in ``key`` (one line each)."""
    others = [k for k in keys if k != key]
    if not others:
        return [np.arange(len(df))]
    return [np.asarray(r) for r in df.groupby([df[k].astype(str) for k in others]).indices
            .values()]


def plot_sweep(folder: str | Path, path: str | Path, dpi: int = 110) -> Path:
    """Write a PNG of the sweep in ``folder`` (written by ``ocgroupoid sweep --out``)."""
    extras.require("the figure of a sweep")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    store = SweepDir(folder)
    manifest = store.read_manifest()
    keys = manifest["keys"]
    df = frame(store.records(manifest["ids"]), keys)
    if df.empty:
        raise ConfigError(f"{folder}: no finished point yet; run the sweep (--resume) first")
    ok = df["success"].to_numpy(dtype=bool)
    floor = float(df.loc[ok, "cost"].min()) if ok.any() else 0.0
    fig, axes = plt.subplots(1, len(keys), figsize=(5 * len(keys), 4), squeeze=False)
    for key, ax in zip(keys, axes[0]):
        x, labels = _positions(df[key])
        for rows in _lines(df, key, keys) if key in manifest["grid"] else []:
            rows = rows[ok[rows]]
            if rows.size > 1:
                order = rows[np.argsort(x[rows])]
                ax.plot(x[order], df["cost"].to_numpy()[order], "-", color="C0", alpha=0.4)
        ax.plot(x[ok], df.loc[ok, "cost"], "o", color="C0", ms=4, label=f"solved ({ok.sum()})")
        for status, rows in df[~ok].groupby("status").indices.items():
            failed = np.flatnonzero(~ok)[rows]
            ax.plot(x[failed], np.full(failed.size, floor), "x", ms=7,
                    label=f"{status} ({failed.size})", color="C3")
        if labels is not None:
            ax.set_xticks(range(len(labels)), [t if len(t) < 24 else t[:21] + "..."
                                               for t in labels], rotation=30, ha="right",
                          fontsize=7)
        ax.set_xlabel(key)
        ax.set_ylabel("cost")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"{Path(manifest['problem'] or 'problem').stem}: {len(df)} of "
                 f"{len(manifest['ids'])} points")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    plt.close(fig)
    write_atomic(path, buf.getvalue())
    return Path(path)
