"""Time at equal accuracy: where two work-precision lines cross a common error level.

A method's line is its rows ordered by N, (time, error) on log-log axes. The time it needs
for an error e is read where the line first falls to e, linearly in (log e, log t) between
the two grids around it; when even its coarsest grid is more accurate than e, that grid's
time is an upper bound; when no grid reaches e, it is undefined. The ratio of the baseline's
time to our fastest scheme's is read at the decades 10^-k that one of ours reaches and the
baseline's line crosses or never reaches. It is a lower bound where ours is bounded, and
where the baseline never reaches the level: it would need a grid finer than its finest,
which takes at least that grid's time (the time of a solve grows with N).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..nlp.schemes import BASELINES, SCHEME_NAMES
from .methods import Method

#: schemes (any retraction) counted as ours: every scheme but the baselines
OURS = tuple(n for n in SCHEME_NAMES if n not in BASELINES)


def lines(rows: list[dict[str, Any]]) -> dict[str, list[dict[str, Any]]]:
    """The rows of every method that make its line: IPOPT solved, in the reference's
    minimum."""
    out: dict[str, list[dict[str, Any]]] = {}
    for r in rows:
        if r["status"] == "Solve_Succeeded" and r["minimum"] == "same":
            out.setdefault(r["method"], []).append(r)
    return out


def time_at(rows: list[dict[str, Any]], key: str, level: float
            ) -> tuple[float, bool] | None:
    """Seconds the rows' method needs for ``rows[key] == level`` and whether that is only an
    upper bound (its coarsest grid is already more accurate: its time there); None when no
    grid reaches the level (module docstring)."""
    pts = sorted((r["N"], r[key], r["seconds"]) for r in rows if r.get(key))
    if not pts:
        return None
    if pts[0][1] <= level:
        return pts[0][2], True
    for (_, e0, t0), (_, e1, t1) in zip(pts, pts[1:]):
        if e0 >= level >= e1 and e0 > e1:
            w = (math.log(e0) - math.log(level)) / (math.log(e0) - math.log(e1))
            return float(np.exp((1 - w) * math.log(t0) + w * math.log(t1))), False
    return None


def finest_time(rows: list[dict[str, Any]], key: str) -> float | None:
    """Seconds of the finest grid among the rows with an error ``key`` (None without any):
    a lower bound on the time of any finer grid."""
    pts = [(r["N"], r["seconds"]) for r in rows if r.get(key)]
    return max(pts)[1] if pts else None


def error_range(rows: list[dict[str, Any]], key: str) -> tuple[float, float] | None:
    """The smallest and largest error of the rows (None without any)."""
    errors = [r[key] for r in rows if r.get(key)]
    return (min(errors), max(errors)) if errors else None


def decades(low: float, high: float) -> list[float]:
    """The powers of ten in [low, high], largest first."""
    return [10.0 ** k for k in range(math.floor(math.log10(high)),
                                     math.ceil(math.log10(low)) - 1, -1)
            if low <= 10.0 ** k <= high]


def compare(lines: dict[str, list[dict[str, Any]]], key: str, baseline: str = "rk4_quat"
            ) -> list[dict[str, Any]]:
    """At every decade of error that one of ours reaches and ``baseline``'s line crosses or
    never reaches: the baseline's time over our fastest (> 1: ours is faster), and which of
    ours that was. ``lower_bound`` when the true ratio is larger: ours is already more
    accurate on its coarsest grid, or the baseline is not accurate enough on its finest
    (its time there stands for that of the finer grid it would need; module docstring)."""
    if baseline not in lines:
        return []
    out = []
    base = lines[baseline]
    ours = {m: rows for m, rows in lines.items()
            if Method.split(m)[0].split(":")[0] in OURS}
    ranges = [r for r in (error_range(rows, key) for rows in [base, *ours.values()]) if r]
    if len(ranges) < 2:
        return []
    low, high = min(r[0] for r in ranges), max(r[1] for r in ranges)
    for level in decades(low, high):
        times = {m: t for m, rows in ours.items() if (t := time_at(rows, key, level))}
        at_base = time_at(base, key, level)
        if at_base is None:  # the baseline's finest grid is less accurate than level
            base_seconds, short = finest_time(base, key), True
        elif at_base[1]:  # the baseline's own time is only an upper bound
            continue
        else:
            base_seconds, short = at_base[0], False
        if not times or base_seconds is None:
            continue
        best = min(times, key=lambda m: times[m][0])
        out.append({"level": level, "ours": best, "ours_seconds": times[best][0],
                    "baseline_seconds": base_seconds, "ratio": base_seconds / times[best][0],
                    "lower_bound": times[best][1] or short,
                    "all_ours_seconds": {m: t for m, (t, _) in times.items()}})
    return out


def headline(comparisons: list[dict[str, Any]], preferred: float) -> dict[str, Any] | None:
    """The comparison quoted: at ``preferred`` if there, else at the level nearest to it
    (log scale), an interpolated ratio before a bound."""
    if not comparisons:
        return None
    return min(comparisons, key=lambda c: (c["lower_bound"],
                                           abs(math.log10(c["level"] / preferred))))


def report(summary: dict[str, Any]) -> str:
    """The reference of a work-precision summary, then one line per error kind: rk4_quat's
    time over our fastest at each common level (as ``ocgroupoid bench`` prints it)."""
    ref = summary["reference"]
    text = [f"{summary['problem']}: reference J = {ref['cost']:.12g} (relative uncertainty "
            f"{ref['relative_uncertainty']:.1e})"]
    for key, rows in summary["equal_accuracy"].items():
        text.append(f"  time of rk4_quat / ours at equal {key.replace('_', ' ')}: " + (
            ", ".join(f"{r['level']:.0e}: {'>=' if r['lower_bound'] else ''}{r['ratio']:.2g}x "
                      f"({r['ours']})" for r in rows) or "no common error level"))
    return "\n".join(text)
