"""Figures of a Solution for engineers: every quantity against a shared time axis, one panel
per quantity group and unit, with its meaning, unit and one legend entry per component;
attitude errors to the target, x-y paths with start and target; bounds, targets and a free
final time marked (see :mod:`ocgroupoid.plotting.panels`).

``plot(solution, path=None)`` returns the matplotlib Figure (and writes a PNG at ``path``);
``Solution.plot`` calls it (registered here, as this layer sits above the Solution's).
``view(solution, path)`` writes the 3-D view of the body moving along the solution: a
self-contained HTML page, a GIF or an MP4 (:mod:`ocgroupoid.plotting.view`).
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

from ..solve import solution as _solution
from ..solve.outputs import check_file
from ..solve.solution import Solution, write_atomic
from .figure import figure
from .panels import Panel, panels
from .view import view

DPI = 110


def plot(solution: Solution, path: str | Path | None = None, dpi: int = DPI) -> Any:
    """The figure of a Solution (a ``matplotlib.figure.Figure``, no pyplot state): the
    panels of :func:`~ocgroupoid.plotting.panels.panels` in two columns; with ``path``, also
    written there as a PNG (atomically; a folder, or a path under a file, is a ConfigError
    raised before drawing)."""
    if path is not None:
        path = check_file(path, "plot path", "figure.png")
    fig = figure(solution, panels(solution))
    if path is not None:
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=dpi)
        write_atomic(path, buf.getvalue())
    return fig


_solution.PLOTTER = plot

__all__ = ["plot", "panels", "figure", "Panel", "view"]
