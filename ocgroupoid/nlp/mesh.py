"""Adaptive steps: a mesh rule that moves nodes onto the switches of the controls.

A solve with uniform steps shows where the bounds are active. The times at which the active
set changes — the entry and exit of a constrained arc, or the jump of a bang-bang control
from one bound to the other — split the horizon into phases. A second solve keeps the steps
uniform within each phase but makes every phase's duration a variable (sum = T, seed 001,
§6.3: time as a variable of the discrete problem), so that the phase boundaries, which are
nodes, settle exactly on the switches: a control that is smooth within each phase is then
resolved at the scheme's order, where a switch inside an interval costs O(h).
"""

from __future__ import annotations

import numpy as np

from ..nlp.assembly import Kind
from ..nlp.transcription import RawResult, Transcription

ACTIVE = 1e-6  # a bound within ACTIVE * max(1, |bound|) counts as active


def active_sides(tr: Transcription, r: RawResult,
                 rows_at: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Times of the bounds' points (sorted) and, per bound row and time, +1 (at the upper
    bound), -1 (at the lower) or 0 (free). ``rows_at``: the rows ``(g, lbg, ubg)`` at r where
    the caller has them already (else evaluated here)."""
    rows = tr.rows(Kind.INEQUALITY)
    if not rows.size:
        return np.zeros(0), np.zeros((0, 0))
    frac = np.concatenate([b.times for b in tr.blocks if b.kind is Kind.INEQUALITY])
    order = np.argsort(frac, kind="stable")
    times = clock(tr, r, frac[order])
    g_all, lbg, ubg = rows_at if rows_at is not None else rows_of(tr, r.x, r.p)
    g = g_all[rows][:, order]
    lo, hi = lbg[rows][:, order], ubg[rows][:, order]
    tol = ACTIVE * np.maximum(1.0, np.abs(np.where(np.isfinite(hi), hi, lo)))
    side = np.where(g >= hi - tol, 1, np.where(g <= lo + tol, -1, 0))
    return times, side


def rows_of(tr: Transcription, x: np.ndarray, p: np.ndarray, g: np.ndarray | None = None
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The NLP's rows ``g`` at (x, p) (evaluated unless given) and their bounds ``lbg``,
    ``ubg``, flat."""
    lbg, ubg, _, _ = (np.array(v).ravel() for v in tr.bounds_function(p))
    return np.array(tr.g_fun(x, p)).ravel() if g is None else g, lbg, ubg


def clock(tr: Transcription, r: RawResult, frac: np.ndarray) -> np.ndarray:
    """Times of fractions of the grid (interval k = floor(frac N) at its own fraction): T frac
    for uniform steps, through each interval's own step for phased ones."""
    w = np.concatenate([np.asarray(r.x, dtype=float).ravel(), r.p])
    steps = w[tr.layout.steps] / tr.N
    nodes = np.concatenate([[0.0], np.cumsum(steps)])
    u = np.asarray(frac, dtype=float) * tr.N
    k = np.minimum(np.floor(u), tr.N - 1).astype(int)
    return nodes[k] + (u - k) * steps[k]


def switch_times(tr: Transcription, r: RawResult) -> list[float]:
    """Where the active set of some bound changes: the entry and exit of every active arc;
    a direct jump from one bound to the other (through the free points of the interval that
    holds it) counts once, midway; a free arc between them (longer than two steps: the
    straight segment between a left and a right turn) twice, at its ends."""
    t, side = active_sides(tr, r)
    step = tr.horizon(r.x, r.p) / tr.N
    found: list[float] = []
    for row in side:
        runs, start = [], 0  # maximal runs of one side: (side, first time, last time)
        for j in range(1, len(row) + 1):
            if j == len(row) or row[j] != row[start]:
                runs.append((row[start], t[start], t[j - 1]))
                start = j
        active = [run for run in runs if run[0] != 0]
        for a, b in zip(active, active[1:]):
            if a[0] == -b[0] and b[1] - a[2] <= 2 * step:  # bang-bang: one switch
                found.append((a[2] + b[1]) / 2)
            else:
                found += [a[2], b[1]]
        if active and active[0][1] > t[0]:
            found.append(active[0][1])  # the first arc starts inside the horizon
        if active and active[-1][2] < t[-1]:
            found.append(active[-1][2])
    return sorted(found)


def cut_times(tr: Transcription, r: RawResult) -> list[float]:
    """The switches of r where phases begin: at least a twentieth of a step from the ends
    and a step apart."""
    N, T = tr.N, tr.horizon(r.x, r.p)  # uniform or phased: switch_times are times
    cuts: list[float] = []
    for s in switch_times(tr, r):
        if 0.05 * T / N < s < T - 0.05 * T / N and all(abs(s - c) > T / N for c in cuts):
            cuts.append(s)
    return sorted(cuts)


def phases(tr: Transcription, r: RawResult) -> tuple[int, ...]:
    """Interval counts of the phases between the switches of a solve (N in all): each phase
    gets intervals in proportion to its duration, at least one."""
    N, T = tr.N, tr.horizon(r.x, r.p)
    bounds = np.array([0.0, *cut_times(tr, r), T])
    counts = np.maximum(1, np.round(np.diff(bounds) / T * N)).astype(int)
    while counts.sum() != N:  # round to N, changing the longest phase
        counts[np.argmax(counts)] += 1 if counts.sum() < N else -1
    return tuple(int(c) for c in counts)


#: a bound held at one side at this share of a phase's points is held there throughout it
HELD = 0.8


def held_sides(tr: Transcription, r: RawResult, phases: tuple[int, ...]
               ) -> tuple[tuple[int, ...], ...]:
    """Per phase of ``phases`` (placed on the switches of r), per bound row: the side r holds
    at :data:`HELD` of the points inside the phase (+1 upper, -1 lower), else 0. The phased
    solve keeps those rows at their side (a bang-bang arc as an equality): the phases'
    durations become the switching times, and a node lands on every switch."""
    t, side = active_sides(tr, r)
    cuts = np.array([0.0, *cut_times(tr, r)])
    out = []
    for a, b in zip(cuts, [*cuts[1:], np.inf]):
        inside = (t > a + 1e-12) & (t < b - 1e-12)
        row = []
        for s in side:
            v = s[inside]
            share = {k: float(np.mean(v == k)) if v.size else 0.0 for k in (1, -1)}
            row.append(1 if share[1] >= HELD else -1 if share[-1] >= HELD else 0)
        out.append(tuple(row))
    return tuple(out)
