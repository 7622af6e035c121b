"""A coarse grid's multipliers carried onto a finer grid: with the interpolated point, IPOPT's
primal-dual warm start of the finer grid (continuation, accuracy on demand, and a Solution
given as the guess of another grid, which keeps its NLP's rows: :mod:`~ocgroupoid.solve.rows`).

The coarse solution's velocities interpolated onto the finer grid (:func:`interpolate`) start
the finer grid near its solution, but IPOPT started there from its own initial barrier
parameter and multipliers moves away before it comes back: ``quadrotor_min_time`` (order4)
from its N = 256 solution took 330 iterations (51.6 s) at N = 512, its barrier parameter down
to 1e-8.6 while the cost was still far off. With the coarse grid's multipliers carried over,
IPOPT's warm start (the barrier parameter at 1e-6, the bound pushes at 1e-9) took 25
iterations (2.75 s) to the same minimum. The carried start has IPOPT options of its own
(:data:`~ocgroupoid.nlp.backends.ipopt.CARRIED_IPOPT`, the bound pushes at 1e-5, 20
iterations there): the interpolated controls cross their bounds where the coarse ones
switched, and slacks pushed only 1e-9 inside them cut IPOPT's first steps short
(``quadrotor_min_time`` from N = 16 to 32: 37 iterations, against 24 with 1e-5 and 27
without the multipliers).

Every constraint block keeps its meaning from grid to grid, so each of its rows is a function
of time sampled at the block's columns (measured between the converged solutions on N and 2N,
2026-12-04, ``quadrotor_min_time`` and the cart-pole, median ratios): the multipliers of the
discrete Euler-Lagrange equations (:attr:`Kind.PATH <ocgroupoid.nlp.assembly.Kind>`, the
seeds' lambda^k), of the reconstruction and of the final conditions keep their size (ratio
0.99-1.01); those of the bounds, imposed at points of the intervals, are weights of a sum over
the points and halve with h (ratio 0.49 and 0.46, the cart-pole's from N = 128 to 256). A
block with several points per interval is interpolated point by point, each over its own
times: an interval's end and the next one's start share a time but not their multipliers
across a switch of the control (the cart-pole from N = 64 to 128: 19 IPOPT iterations, 36
with all its points interpolated at once, 18 without multipliers). The variables' own bounds
(the free horizon's limits, free boundary values) are the same variables on every grid,
their multipliers copied.
"""

from __future__ import annotations

from typing import Callable, Protocol, TypeVar

import numpy as np

from ..nlp.assembly import Kind
from ..nlp.transcription import Guess, Transcription
from .guesses import interpolate
from .rows import Rows, times

#: what a solve returns (a :class:`~ocgroupoid.nlp.transcription.RawResult`)
R = TypeVar("R")

#: the kinds of constraint blocks whose multipliers are carried; a block of another kind (the
#: mesh of adaptive steps) leaves the finer grid without multipliers
CARRIED = (Kind.RECONSTRUCTION, Kind.PATH, Kind.FINAL, Kind.FINAL_CONDITION, Kind.INEQUALITY,
           Kind.COST)


class Solved(Protocol):
    """A solution on a grid: its point, parameters and multipliers."""

    x: np.ndarray
    p: np.ndarray
    lam_g: np.ndarray
    lam_x: np.ndarray


def carried(a: Rows, lam_g: np.ndarray, lam_x: np.ndarray,
            b: Rows) -> tuple[np.ndarray, np.ndarray] | None:
    """The coarse grid ``a``'s multipliers ``lam_g``, ``lam_x`` on the fine grid ``b`` (module
    docstring): each row of a block interpolated linearly in time, point by point (a block
    of one column copied), a bound's scaled by the ratio of the steps, coarse N / fine N;
    the variables' own bounds copied (the stage variables have none). None where the grids'
    blocks do not correspond (another scheme, retraction or rule, adaptive steps, other
    sizes): the fine grid then starts without them."""
    if a.method != b.method or a.phased or b.phased or len(a.blocks) != len(b.blocks) \
            or a.nx - a.stage != b.nx - b.stage or lam_g.size != a.ng or lam_x.size != a.nx:
        return None
    out = np.zeros(b.ng)
    for bc, bf in zip(a.blocks, b.blocks):
        rc, rf = bc.g_rows, bf.g_rows
        if bc.name != bf.name or bc.kind is not bf.kind or bc.kind not in CARRIED \
                or rc.shape[0] != rf.shape[0]:
            return None
        if rc.size == 0:
            continue
        scale = a.N / b.N if bc.kind is Kind.INEQUALITY else 1.0
        values = lam_g[rc]
        if rc.shape[1] == 1 and rf.shape[1] == 1:
            out[rf] = scale * values
            continue
        tc, tf = times(bc, a.N), times(bf, b.N)
        if tc is None or tf is None or bc.points != bf.points:
            return None
        k = bc.points  # the points of a column apart: an interval's end and the next's
        for j in range(k):  # start share a time, on either side of a switch
            out[rf[:, j::k]] = scale * np.array([np.interp(tf[j::k], tc[j::k], row)
                                                 for row in values[:, j::k]])
    x_lam = np.zeros(b.nx)
    x_lam[b.stage:] = lam_x[a.stage:]
    return out, x_lam


def with_multipliers(coarse: Rows, solved: Solved, fine: Transcription, p: np.ndarray,
                     primal: Guess) -> Guess:
    """``primal`` (the coarse solution's velocities on the fine grid) and, where the fine
    grid is solved by IPOPT and the multipliers carry over (:func:`carried`), the whole
    point with them: IPOPT's primal-dual warm start, which falls back to ``primal`` (its
    ``Guess.primal``) if it fails."""
    duals = carried(coarse, solved.lam_g, solved.lam_x, Rows.of(fine)) \
        if fine.fatrop is None else None
    if duals is None:
        return primal
    x0, _ = fine.start_point(primal, p)
    return Guess(f"{primal.label}, with its multipliers", primal.xi, np.asarray(x0, dtype=float),
                 duals[0], duals[1], T=primal.T, primal=primal)


def onto(coarse: Transcription, solved: Solved, fine: Transcription, p: np.ndarray) -> Guess:
    """The start of a finer grid from a coarse grid's solution: its velocities interpolated
    (:func:`interpolate`) and, where the fine grid is solved by IPOPT and the multipliers
    carry over (:func:`carried`), the whole point with them: IPOPT's primal-dual warm start,
    which falls back to the interpolated velocities alone (``Guess.primal``) if it fails."""
    return with_multipliers(Rows.of(coarse), solved, fine, p,
                            interpolate(coarse, solved.x, solved.p, fine.N))


def from_carried(start: Guess, solve: Callable[[Guess], R], succeeded: Callable[[R], bool],
                 again: Callable[[], bool] = lambda: True) -> list[R]:
    """The runs of ``solve`` from ``start`` (:func:`onto`'s): from the carried warm start,
    and, if that did not succeed, ``again()`` allows it and the start has one, from its
    velocities alone (``start.primal``); in order."""
    runs = [solve(start)]
    if not succeeded(runs[0]) and start.primal is not None and again():
        runs.append(solve(start.primal))
    return runs
