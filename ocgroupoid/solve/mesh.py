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


def active_sides(tr: Transcription, r: RawResult) -> tuple[np.ndarray, np.ndarray]:
    """Times of the bounds' points (sorted) and, per bound row and time, +1 (at the upper
    bound), -1 (at the lower) or 0 (free)."""
    rows = tr.rows(Kind.INEQUALITY)
    if not rows.size:
        return np.zeros(0), np.zeros((0, 0))
    frac = np.concatenate([b.times for b in tr.blocks if b.kind is Kind.INEQUALITY])
    order = np.argsort(frac, kind="stable")
    g = np.array(tr.g_fun(r.x, r.p)).ravel()[rows][:, order]
    lbg, ubg, _, _ = (np.array(v).ravel() for v in tr.bounds_function(r.p))
    lo, hi = lbg[rows][:, order], ubg[rows][:, order]
    tol = ACTIVE * np.maximum(1.0, np.abs(np.where(np.isfinite(hi), hi, lo)))
    side = np.where(g >= hi - tol, 1, np.where(g <= lo + tol, -1, 0))
    return frac[order] * tr.horizon(r.x, r.p), side


def switch_times(tr: Transcription, r: RawResult) -> list[float]:
    """Where the active set of some bound changes: the entry and exit of every active arc;
    a direct jump from one bound to the other (through free points) counts once, midway."""
    t, side = active_sides(tr, r)
    found: list[float] = []
    for row in side:
        runs, start = [], 0  # maximal runs of one side: (side, first time, last time)
        for j in range(1, len(row) + 1):
            if j == len(row) or row[j] != row[start]:
                runs.append((row[start], t[start], t[j - 1]))
                start = j
        active = [run for run in runs if run[0] != 0]
        for a, b in zip(active, active[1:]):
            if a[0] == -b[0]:  # bang-bang: one switch between the arcs
                found.append((a[2] + b[1]) / 2)
            else:
                found += [a[2], b[1]]
        if active and active[0][1] > t[0]:
            found.append(active[0][1])  # the first arc starts inside the horizon
        if active and active[-1][2] < t[-1]:
            found.append(active[-1][2])
    return sorted(found)


def phases(tr: Transcription, r: RawResult) -> tuple[int, ...]:
    """Interval counts of the phases between the switches of a uniform solve (N in all):
    each phase gets intervals in proportion to its duration, at least one."""
    N, T = tr.N, tr.horizon(r.x, r.p)
    cuts: list[float] = []
    for s in switch_times(tr, r):
        if T / N < s < T - T / N and all(abs(s - c) > T / N for c in cuts):
            cuts.append(s)
    bounds = np.array([0.0, *sorted(cuts), T])
    counts = np.maximum(1, np.round(np.diff(bounds) / T * N)).astype(int)
    while counts.sum() != N:  # round to N, changing the longest phase
        counts[np.argmax(counts)] += 1 if counts.sum() < N else -1
    return tuple(int(c) for c in counts)
