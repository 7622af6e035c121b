"""Panels drawn on one matplotlib Figure (no pyplot: no global state, no backend switch)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .names import Names
from .panels import Panel

WIDTH, HEIGHT = 6.2, 3.3  # inches per panel
LEGEND_ROWS = 12  # entries of a legend column (8 pt type: fits a panel's height)


def arrange(panels: list[Panel]) -> list[Panel]:
    """Reading order, except that with an odd count the last panel, which spans the figure's
    width, is one against time (a path keeps equal axes, so it would waste the width)."""
    if len(panels) % 2 and len(panels) > 1 and panels[-1].kind != "time":
        k = max((i for i, p in enumerate(panels) if p.kind == "time"), default=None)
        if k is not None:
            panels = panels[:k] + panels[k + 1:] + [panels[k]]
    return panels


def fitted(ys: list[Any], margin: float = 0.05) -> tuple[float, float]:
    """y limits that hold the finite values of ``ys`` with matplotlib's default margin."""
    v = np.concatenate([np.ravel(np.asarray(y, dtype=float)) for y in ys] or [np.zeros(0)])
    v = v[np.isfinite(v)]
    lo, hi = (float(v.min()), float(v.max())) if v.size else (-1.0, 1.0)
    pad = margin * (hi - lo) if hi > lo else max(abs(lo), 1.0) * margin
    return lo - pad, hi + pad


def draw(ax: Any, p: Panel) -> None:
    """One panel on its axes: its curves (the y axis fitted to those that set the scale),
    the free final time, title, axis labels, a grid, equal scales for a path, and the
    legend beside the axes (never over a curve)."""
    for c in p.curves:
        ax.plot(c.x, c.y, label=c.label if c.label is not None else "_nolegend_", gid=c.gid,
                **c.style)
    if not all(c.scale for c in p.curves):
        ax.set_ylim(*fitted([c.y for c in p.curves if c.scale]))
    if p.final_time is not None:
        ax.axvline(p.final_time, color="0.3", linestyle=":", linewidth=1.2, gid="final-time",
                   label=p.final_time_label or "_nolegend_")
    ax.set_title(p.title, fontsize=10)
    ax.set_xlabel(p.xlabel)
    ax.set_ylabel(p.ylabel)
    ax.set_gid(p.gid)
    ax.grid(alpha=0.3)
    if p.kind == "plane":
        ax.set_aspect("equal", adjustable="datalim")
    entries = len(ax.get_legend_handles_labels()[1])
    if entries:  # in columns of at most LEGEND_ROWS entries, so that it fits the panel
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False,
                  ncols=-(-entries // LEGEND_ROWS))


def figure(sol: Any, panels: list[Panel]) -> Any:
    """A Figure with the panels in two columns (the last one spanning both when their count
    is odd), titled with the problem, status, cost, N and T."""
    from matplotlib.figure import Figure

    panels = arrange(panels)
    n = len(panels)
    cols = 1 if n <= 1 else 2
    rows = max(1, -(-n // cols))
    fig = Figure(figsize=(WIDTH * cols, HEIGHT * rows + 0.5), layout="constrained")
    grid = fig.add_gridspec(rows, cols)
    first = None  # every panel against time shares the first one's time axis
    for k, p in enumerate(panels):
        r, c = divmod(k, cols)
        spec = grid[r, :] if (n % cols and k == n - 1) else grid[r, c]
        ax = fig.add_subplot(spec, sharex=first if p.kind == "time" else None)
        if p.kind == "time" and first is None:
            first = ax
        draw(ax, p)
    names = Names(sol)
    free = " (free)" if names.free_horizon() else ""
    fig.suptitle(f"{sol.problem}: {sol.status}, cost {sol.cost:.6g}, N = {sol.N}, "
                 f"T = {sol.T:.4g} {names.time_unit}{free}", fontsize=11)
    return fig
