"""The stability map: one panel per method, slew angle across, N up, a coloured cell per
solve (:mod:`~ocgroupoid.bench.outcome`) with a short note: the replay's miss of an off-target
plan, the distance off the group, the net turn of another minimum, IPOPT's status of a
failure. Dotted lines mark pi/2 (where the Euler pitch passes 90 degrees) and pi (beyond it
the slew turns the other way round)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from .chart import NAMES, save_png
from .outcome import OUTCOMES

COLOURS = {"converged": "#4daf4a", "unverified": "#d9ef8b", "off group": "#b07cc6",
           "off target": "#ff9f40", "other minimum": "#6baed6", "failed": "#e41a1c"}
MEANING = {"converged": "converged (verified)",
           "unverified": "converged, lands, rejected by the verdict (its hint)",
           "off group": "off the group by > 1e-6 (note: the distance)",
           "off target": "replay misses the target by > 5% (note: the miss)",
           "other minimum": "turns another way (note: its net turn, rad)",
           "failed": "IPOPT failed (note: its status)"}
STATUS = {"Maximum_Iterations_Exceeded": "max iter", "Restoration_Failed": "restor.",
          "Invalid_Number_Detected": "NaN", "Infeasible_Problem_Detected": "infeas.",
          "Search_Direction_Becomes_Too_Small": "small step", "Diverging_Iterates": "diverge",
          "Error_In_Step_Computation": "KKT sing.", "Solved_To_Acceptable_Level": "accept."}


def note(cell: dict[str, Any]) -> str:
    """The short text written in a cell."""
    o = cell["outcome"]
    if o == "off target":
        miss = cell["replay_miss"]
        return "diverged" if math.isinf(miss) else f"{miss:.0%}"
    if o == "off group":
        return f"{cell['off_group']:.0e}"
    if o == "other minimum":
        return f"{cell['net_turn']:+.2f}"
    if o == "failed":
        return STATUS.get(cell["status"], cell["status"][:8])
    return "ok" if o == "converged" else "flag"


def _panel(ax: Any, cells: list[dict[str, Any]], angles: list[float], Ns: list[int]) -> None:
    codes = np.full((len(Ns), len(angles)), np.nan)
    for c in cells:
        i, j = Ns.index(c["N"]), angles.index(c["angle"])
        codes[i, j] = OUTCOMES.index(c["outcome"])
        ax.text(j, i, note(c), ha="center", va="center", fontsize=6.5,
                color="white" if c["outcome"] == "failed" else "black")
    from matplotlib.colors import ListedColormap

    ax.imshow(codes, cmap=ListedColormap([COLOURS[o] for o in OUTCOMES]), vmin=-0.5,
              vmax=len(OUTCOMES) - 0.5, origin="lower", aspect="auto")
    for mark in (math.pi / 2, math.pi):
        x = float(np.interp(mark, angles, range(len(angles)), left=np.nan, right=np.nan))
        if not math.isnan(x) and angles[0] < mark < angles[-1]:
            ax.axvline(x, color="0.2", linestyle=":", linewidth=1)
    ax.set_xticks(range(len(angles)), [f"{a:g}" for a in angles], fontsize=8)
    ax.set_yticks(range(len(Ns)), [str(N) for N in Ns], fontsize=8)
    ax.set_xlabel("slew angle [rad]", fontsize=8)
    ax.set_ylabel("N (intervals)", fontsize=8)


def stability_chart(summary: dict[str, Any], path: Path, dpi: int = 110) -> Path:
    """Draw the map of a stability summary (module docstring) and write it as PNG."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    s = summary["settings"]
    angles, Ns, methods = list(s["angles"]), list(s["N"]), list(s["methods"])
    cols = min(4, len(methods) + 1)
    rows = math.ceil((len(methods) + 1) / cols)
    fig = Figure(figsize=(3.6 * cols, 3.0 * rows + 0.8), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
    for ax, m in zip(axes, methods):
        _panel(ax, [c for c in summary["cells"] if c["method"] == m], angles, Ns)
        ax.set_title(NAMES.get(m, m), fontsize=9)
    for ax in axes[len(methods):]:
        ax.axis("off")
    axes[-1].legend(handles=[Patch(color=COLOURS[o], label=MEANING[o]) for o in OUTCOMES],
                    loc="center", fontsize=7.5, frameon=False, title="outcome",
                    title_fontsize=8)
    axis = ", ".join(f"{a:g}" for a in s["axis"])
    fig.suptitle(f"{summary['problem']}: rest-to-rest slews of {s['state']} about ({axis}), "
                 f"from {s['start']}. Dotted: pi/2 (Euler pitch 90 deg), pi (beyond it the "
                 "slew turns the other way round)", fontsize=9)
    return save_png(fig, path, dpi)
