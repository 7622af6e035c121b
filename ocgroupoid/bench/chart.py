"""The work-precision chart: error against solver time, log-log, one line per method.

Two panels: the relative cost error against the reference, and the replay terminal error
(the plan's miss when its controls drive the continuous dynamics). Lower left is better.
Filled markers are verified successes, hollow ones solutions IPOPT converged to that the
verdict rejects (e.g. a quaternion off the unit sphere, a plan that does not land); rows in
another minimum and failed solves are counted in the subtitle, not drawn. The band at the
bottom of the cost panel is below the reference's own uncertainty.
"""

from __future__ import annotations

import io
import textwrap
from pathlib import Path
from typing import Any

from ..solve.solution import write_atomic
from .equal_accuracy import lines
from .methods import Method

#: method label -> (colour, line style, marker); ours solid, the baselines dashed
STYLES = {"order2": ("tab:blue", "-", "o"), "order4": ("tab:green", "-", "s"),
          "order6": ("magenta", "-", "h"),
          "order2:exp": ("tab:cyan", "-.", "D"), "order4:exp": ("olive", "-.", "P"),
          "order2:first_order": ("tab:gray", ":", "h"),
          "rk4_quat": ("tab:red", "--", "^"), "rk4_matrix": ("tab:orange", "--", "v"),
          "rk4_euler": ("tab:purple", "--", "X")}
NAMES = {"order2": "ours: order2 (cayley)", "order4": "ours: order4 (cayley)",
         "order6": "ours: order6 (cayley)",
         "order2:exp": "ours: order2 (exp)", "order4:exp": "ours: order4 (exp)",
         "order2:first_order": "ours: order2 (first_order)",
         "rk4_quat": "RK4 shooting, quaternions", "rk4_matrix": "RK4 shooting, matrices",
         "rk4_euler": "RK4 shooting, ZYX Euler angles"}
#: a method run with another backend or compiled (``order4@fatrop+jit``): a shade of its
#: scheme's colour and a marker of its own
SHADES = {"order2": {"+jit": "navy", "@fatrop": "deepskyblue", "@fatrop+jit": "darkviolet",
                     "@fatrop+jit+coarse": "slateblue"},
          "order4": {"+jit": "darkgreen", "@fatrop": "yellowgreen",
                     "@fatrop+jit": "saddlebrown", "+jit+coarse": "teal",
                     "@fatrop+jit+coarse": "darkorange"},
          "order6": {"+jit": "mediumvioletred", "@fatrop": "orchid", "@fatrop+jit": "black",
                     "+jit+coarse": "indigo", "@fatrop+jit+coarse": "dimgray"},
          "rk4_quat": {"+jit": "darkred", "@fatrop": "salmon", "@fatrop+jit": "maroon",
                       "+jit+coarse": "deeppink"}}
VARIANT_MARKERS = {"+jit": "D", "@fatrop": "v", "@fatrop+jit": "*", "+jit+coarse": "p",
                   "@fatrop+jit+coarse": "P"}


def save_png(fig: Any, path: Path, dpi: int) -> Path:
    """Write a matplotlib figure as PNG atomically (a run cut short leaves no half file)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    write_atomic(path, buf.getvalue())
    return path


def style(method: str, i: int) -> tuple[str, str, str, str]:
    """Colour, line style, marker and legend name of a method's line (``i``: its place,
    for a method without a style of its own)."""
    base, variant = Method.split(method)
    color, ls, marker = STYLES.get(base, (f"C{i}", "-", "o"))
    name = NAMES.get(base, base)
    if variant:
        scheme = base.split(":")[0]
        color = SHADES.get(scheme, {}).get(variant, f"C{i}")
        marker = VARIANT_MARKERS.get(variant, marker)
        name += ", " + variant.lstrip("@+").replace("+", ", ")
    return color, ls, marker, name


def _panel(ax: Any, by_method: dict[str, list[dict[str, Any]]], key: str) -> list[float]:
    """One line per method on ``ax``; returns the errors drawn."""
    drawn: list[float] = []
    for i, (method, rows) in enumerate(by_method.items()):
        pts = sorted((r["N"], r["seconds"], r[key], r["success"]) for r in rows if r.get(key))
        if not pts:
            continue
        color, ls, marker, name = style(method, i)
        N, t, e, ok = zip(*pts)
        ax.loglog(t, e, linestyle=ls, color=color, marker=marker, ms=6, lw=1.6, label=name)
        for tt, ee, good in zip(t, e, ok):
            if not good:
                ax.plot(tt, ee, marker=marker, ms=6, color=color, mfc="white",
                        linestyle="none")
        for j in {0, len(pts) - 1}:
            ax.annotate(f"N={N[j]}", (t[j], e[j]), xytext=(4, 3), textcoords="offset points",
                        fontsize=7, color=color)
        drawn += e
    return drawn


def subtitle(summary: dict[str, Any]) -> str:
    """What the chart leaves out, in words."""
    rows = summary["rows"]
    other = [f"{r['method']} N={r['N']}" for r in rows if r.get("minimum") == "other"]
    failed = [f"{r['method']} N={r['N']} ({r['status']})" for r in rows
              if r["status"] != "Solve_Succeeded"]
    parts = []
    if summary["skipped"]:
        parts.append("not run (same computation as another): " + ", ".join(summary["skipped"]))
    if other:
        parts.append("in another local minimum than the reference's, not drawn: "
                     + ", ".join(other))
    if failed:
        parts.append("the solver failed, not drawn: " + ", ".join(failed))
    return "\n".join(_wrap(p, 150) for p in parts)


def _wrap(text: str, width: int) -> str:
    return "\n".join(textwrap.wrap(text, width))


def work_precision_chart(summary: dict[str, Any], path: Path, dpi: int = 110) -> Path:
    """Draw the chart of a work-precision summary (module docstring) and write it as PNG."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    fig = Figure(figsize=(13.5, 6.6), layout="constrained")
    axes = fig.subplots(1, 2)
    by_method = lines(summary["rows"])
    s, ref = summary["settings"], summary["reference"]
    units = summary.get("replay_units") or "the units of each final value"
    panels = (("cost_error", "relative cost error  |J - J_ref| / |J_ref|",
               "cost accuracy"),
              ("replay_error", f"replay terminal error, worst final value\n[{units}]",
               "landing accuracy: the controls replayed through the continuous dynamics"))
    for ax, (key, ylabel, title) in zip(axes, panels):
        drawn = _panel(ax, by_method, key)
        if key == "cost_error" and drawn:
            low = min(min(drawn), ref["relative_uncertainty"]) / 5
            ax.axhspan(low, ref["relative_uncertainty"], color="0.88", zorder=0,
                       label="below the reference's uncertainty")
            ax.set_ylim(bottom=low)
        ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel(f"wall time per solve [s]  (median of at least {s['repeats']} "
                      "runs from one cold start)")
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3, which="both")
    handles, labels = axes[0].get_legend_handles_labels()
    more = axes[1].get_legend_handles_labels()
    for h, lab in zip(*more):
        if lab not in labels:
            handles.append(h)
            labels.append(lab)
    if handles:
        fig.legend(handles, labels, loc="outside lower center", ncol=4, fontsize=8,
                   title="filled: verified success; hollow: converged, not verified (see the "
                         "rows' hints)", title_fontsize=8, frameon=False)
    head = (f"{summary['problem']}: work-precision, N = {', '.join(map(str, s['N']))}; "
            f"reference J = {ref['cost']:.10g} ({ref['method']}; uncertainty "
            f"{ref['relative_uncertainty']:.1e}). Lower left is better.")
    fig.suptitle(_wrap(head, 150) + ("\n" + subtitle(summary) if subtitle(summary) else ""),
                 fontsize=9)
    return save_png(fig, path, dpi)


def work_precision_grid(summaries: list[dict[str, Any]], path: Path, dpi: int = 100
                        ) -> Path:
    """Several work-precision summaries on one PNG: a row of the two panels (cost and
    landing accuracy) per problem, without the reference band and subtitles of
    :func:`work_precision_chart`."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 3.4 * len(summaries)), layout="constrained")
    axes = fig.subplots(len(summaries), 2, squeeze=False)
    for row, summary in zip(axes, summaries):
        by_method = lines(summary["rows"])
        for ax, key, what in zip(row, ("cost_error", "replay_error"),
                                 ("relative cost error", "replay terminal error")):
            _panel(ax, by_method, key)
            ax.set_xlabel("wall time per solve [s] (median)")
            ax.set_ylabel(what)
            ax.set_title(f"{summary['problem']}: {what} against time", fontsize=9)
            ax.grid(alpha=0.3, which="both")
            ax.legend(fontsize=7)
    fig.suptitle("Work-precision: lower left is better")
    return save_png(fig, path, dpi)


def ratio_bars(rows: list[dict[str, Any]], path: Path, ylabel: str, title: str,
               label: str = "N = {N}") -> Path:
    """A ratio per file (``rows``: ``file``, ``N``, ``ratio``, None where there is none), one
    bar per N (``label`` formatted with N and its half), on a log scale around 1."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(r["file"] for r in rows))
    Ns = sorted({r["N"] for r in rows})
    fig, ax = plt.subplots(figsize=(10, 4.5), layout="constrained")
    width = 0.8 / len(Ns)
    for j, N in enumerate(Ns):
        xs, ys = [], []
        for i, name in enumerate(names):
            r = next((r for r in rows if r["file"] == name and r["N"] == N), None)
            if r and r.get("ratio"):
                xs.append(i + (j - (len(Ns) - 1) / 2) * width)
                ys.append(r["ratio"])
        ax.bar(xs, ys, width, label=label.format(N=N, half=N // 2), color=f"C{j}")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_yscale("log")
    ax.set_xticks(range(len(names)), names, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return save_png(fig, path, 110)
