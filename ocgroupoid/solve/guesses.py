"""Initial guesses: geodesics of every factor, the model's own, perturbations, and
interpolation of a coarser solution (continuation).

Every guess is a set of interval velocities (N x dim y); the scheme turns it into an NLP
point (:attr:`~ocgroupoid.nlp.transcription.Transcription.point_function`).
"""

from __future__ import annotations

import numpy as np

from ..model.problem import GuessContext
from ..nlp.transcription import Guess, Transcription


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
                 np.column_stack([np.interp(t_f, t_c, xi[:, j]) for j in range(xi.shape[1])]))
