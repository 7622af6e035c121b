"""Initial guesses: geodesics of every factor, the model's own, perturbations, and
interpolation of a coarser solution (continuation).

Every guess is a set of interval velocities (N x dim y); the scheme turns it into an NLP
point (:attr:`~ocgroupoid.nlp.transcription.Transcription.point_function`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import ConfigError
from ..model.problem import GuessContext
from ..nlp.transcription import Guess, Transcription
from .solution import Solution


def geodesic_guesses(tr: Transcription, p: np.ndarray) -> list[Guess]:
    """The all-preferred geodesic guess, then one per alternative of each factor."""
    return tr.guesses(p)


def context(tr: Transcription, p: np.ndarray, base: np.ndarray) -> GuessContext:
    """What a model's guess hook sees of the instance p (NaN marks a free component)."""
    pb, G, m = tr.problem, tr.problem.groupoid, tr.masks
    P = tr.part(p, "P")
    params = {name: P[sl].copy() for name, sl in pb.parameter_slices.items()}
    ends: dict[str, dict[str, np.ndarray]] = {"initial": {}, "final": {}}
    for end, key, states, vkey, vmask in (("initial", "start", m.start_state, "V0",
                                           m.start_velocity),
                                          ("final", "end", m.end_state, "VN", m.end_velocity)):
        packed = tr.part(p, key)
        for f, ts, mask in zip(G.factors, G.target_layout.slices, states):
            if mask.any():
                s = np.asarray(f.state_of_target(packed[ts]), dtype=float).copy()
                if f.componentwise:
                    s[~mask] = np.nan
                ends[end][f.state] = s
        if pb.end_velocities:
            V = np.where(vmask, tr.part(p, vkey), np.nan)
            for f, vs in zip(G.factors, G.velocity_layout.slices):
                ends[end][f.velocity] = V[vs]
    return GuessContext(tr.N, tr.horizon_of(p), params, ends["initial"], ends["final"],
                        base.copy())


def model_guesses(tr: Transcription, p: np.ndarray, base: Guess) -> list[Guess]:
    """The problem's own multi-start guesses (:meth:`Problem.guesses`), if any."""
    hook = tr.problem.guess_hook
    if hook is None:
        return []
    return [Guess(label, xi) for label, xi in hook(tr.problem, context(tr, p, base.xi))]


def perturbed_guesses(base: Guess, T: float, count: int, seed: int = 0) -> list[Guess]:
    """Deterministic perturbations ``xi + A sin(pi t/T) d`` of a guess (fixed seed)."""
    rng = np.random.default_rng(seed)
    N, n = base.xi.shape
    t = (np.arange(N) + 0.5) / N
    scale = max(float(np.sqrt(np.mean(base.xi**2))), 1.0 / T)
    out = []
    for i in range(count):
        d = rng.normal(size=n)
        d /= np.linalg.norm(d)
        out.append(Guess(f"perturbed {i + 1}",
                         base.xi + 2.0 * scale * np.sin(np.pi * t)[:, None] * d[None, :]))
    return out


def interpolate(coarse: Transcription, x: np.ndarray, p: np.ndarray, N: int) -> Guess:
    """A guess on N intervals from a solution on a coarser grid: the mean velocity of each
    coarse interval (its algebra increment over h), linear in time."""
    steps = coarse.readout(x, p)["steps"]
    T = coarse.horizon(x, p)
    xi = steps / (T / coarse.N)
    t_c = (np.arange(coarse.N) + 0.5) * T / coarse.N
    t_f = (np.arange(N) + 0.5) * T / N
    return Guess(f"interpolated from N={coarse.N}",
                 np.column_stack([np.interp(t_f, t_c, xi[:, j]) for j in range(xi.shape[1])]),
                 T=T)


def resampled(xi: Any, N: int, dg: int) -> np.ndarray | None:
    """Interval velocities of a grid of M intervals (M x dg, finite) on N intervals: linear in
    the fraction of the horizon between the interval midpoints (constant beyond the first and
    the last); None if ``xi`` is not such an array."""
    xi = np.asarray(xi, dtype=float)
    if xi.ndim != 2 or xi.shape[1] != dg or xi.shape[0] < 1 or not np.all(np.isfinite(xi)):
        return None
    given, wanted = (np.arange(xi.shape[0]) + 0.5) / xi.shape[0], (np.arange(N) + 0.5) / N
    return np.column_stack([np.interp(wanted, given, xi[:, j]) for j in range(dg)])


def as_guess(guess: Any, tr: Transcription, p: np.ndarray) -> Guess:
    """What ``solve(guess=...)`` accepts, as a Guess of this grid:

    * a :class:`Guess` (interval velocities N x dim y, or a whole NLP point ``x``); velocities
      of another grid (M x dim y: the final grid's, given with continuation) are resampled
      linearly in the fraction of the horizon onto this grid's interval midpoints;
    * a :class:`Solution` of the same problem on any N or scheme: its velocities interpolated
      linearly in time onto this grid's interval midpoints (its own point as is when the
      NLP is the same; :meth:`CompiledProblem.solve` adds its multipliers where they carry
      over, :func:`~ocgroupoid.solve.multipliers.with_multipliers`);
    * an array of interval velocities, N x dim y (or M x dim y, resampled as a Guess's).
    """
    dg = tr.problem.groupoid.algebra_dim
    if isinstance(guess, Solution):
        if guess.x.size == tr.nx and guess.N == tr.N and \
                guess.discretization.get("scheme") == tr.disc.scheme:
            return Guess(f"solution ({guess.discretization.get('scheme')}, N={guess.N})",
                         np.zeros((0, 0)), guess.x)
        names = [f.velocity for f in tr.problem.groupoid.factors]
        missing = [n for n in names if n not in guess.velocities]
        if guess.velocities and missing:
            raise ConfigError(f"guess: the solution of {guess.problem!r} has no velocities "
                              f"{missing} (it has {list(guess.velocities)}): pass a solution "
                              "of the same problem")
        V = np.hstack([guess.velocities[n] for n in names]) if guess.velocities \
            else np.zeros((0, dg))
        t = np.asarray(guess.velocity_t, dtype=float)
        if V.shape[1] != dg or t.size != V.shape[0] or t.size < 1:
            raise ConfigError(f"guess: the solution of {guess.problem!r} has velocities of "
                              f"{V.shape[1]} components, this problem {dg}: pass a solution "
                              "of the same problem")
        T = guess.T if tr.problem.T_free else tr.horizon_of(p)  # a free T starts at its
        mid = (np.arange(tr.N) + 0.5) / tr.N * T
        scaled = t * (T / guess.T) if guess.T > 0 else t  # onto this horizon
        onto = np.column_stack([np.interp(mid, scaled, V[:, j]) for j in range(dg)])
        return Guess(f"interpolated from a solution ({guess.discretization.get('scheme')}, "
                     f"N={guess.N})", onto, T=guess.T)
    if isinstance(guess, Guess):
        if guess.x is None and np.shape(guess.xi) != (tr.N, dg):
            xi = resampled(guess.xi, tr.N, dg)
            if xi is None:
                raise ConfigError(f"guess {guess.label!r}: its velocities are shaped "
                                  f"{np.shape(guess.xi)}, this grid needs finite ones shaped "
                                  f"(N, dim y) = ({tr.N}, {dg}) (or (M, {dg}) on another grid "
                                  "of M intervals, resampled)")
            return replace(guess, label=f"{guess.label} (from N={len(guess.xi)})", xi=xi)
        if guess.x is not None and np.size(guess.x) != tr.nx:
            raise ConfigError(f"guess {guess.label!r}: its point has {np.size(guess.x)} "
                              f"variables, this NLP {tr.nx}: pass interval velocities, or a "
                              "Solution (interpolated onto this grid)")
        return guess
    xi = np.asarray(guess, dtype=float) if isinstance(guess, (list, tuple, np.ndarray)) \
        else None
    other = resampled(xi, tr.N, dg) if xi is not None and xi.shape != (tr.N, dg) else None
    if xi is not None and other is not None:
        return Guess(f"given velocities (from N={len(xi)})", other)
    if xi is None or xi.shape != (tr.N, dg) or not np.all(np.isfinite(xi)):
        raise ConfigError(f"guess: give an og.Guess, a Solution or finite interval velocities "
                          f"shaped (N, dim y) = ({tr.N}, {dg}), got {type(guess).__name__}"
                          f"{' of shape ' + str(np.shape(xi)) if xi is not None else ''}")
    return Guess("given velocities", xi)
