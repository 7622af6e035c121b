"""The plant a closed loop runs against: the continuous dynamics, mismatched and disturbed.

The continuous controlled Euler-Lagrange(-Poincaré) equations of the problem
(:class:`~ocgroupoid.nlp.dynamics.Dynamics`, the right-hand side the replay of every solution
integrates, :mod:`~ocgroupoid.verify.replay`) are integrated by classical RK4
(:func:`~ocgroupoid.nlp.loop.plant_piece`: the exported C's too) with
:data:`~ocgroupoid.nlp.loop.SUBSTEPS` substeps per piece of the applied
control polynomial, with the plant's own parameters (the model's, some scaled: a mismatch such
as inertia x 1.05). After each sample the velocities receive process noise: independent
normal kicks of standard deviation ``noise`` (in the velocities' units), from a seeded
generator, so that a run is reproducible.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..nlp.loop import plant_dynamics, plant_piece
from ..nlp.transcription import Transcription


def mismatched(tr: Transcription, p: np.ndarray, mismatch: dict[str, float]) -> np.ndarray:
    """The physical parameters P of p with the named ones scaled: ``{"inertia": 1.05}``."""
    pb = tr.problem
    P = np.array(tr.part(p, "P"), dtype=float)
    for key, factor in mismatch.items():
        if key not in pb.parameter_slices:
            known = ", ".join(pb.parameter_slices) or "none"
            raise ConfigError(f"mismatch {key}={factor}: {pb.name!r} has no parameter {key!r}; "
                              f"its parameters: {known}")
        if not np.isfinite(factor) or factor <= 0:
            raise ConfigError(f"mismatch {key}={factor}: the factor must be a finite number "
                              "> 0 (e.g. 1.05 for 5 % more)")
        P[pb.parameter_slices[key]] *= factor
    return P


class Plant:
    """The simulated system (module docstring); its state is ``z = (s, y)``."""

    def __init__(self, tr: Transcription, P: np.ndarray, noise: float = 0.0, seed: int = 0
                 ) -> None:
        pb = tr.problem
        if not np.isfinite(noise) or noise < 0:
            raise ConfigError(f"noise must be a finite standard deviation >= 0, got {noise}")
        rhs = plant_dynamics(tr)
        self.P, self.noise = np.asarray(P, dtype=float), float(noise)
        self.rng = np.random.default_rng(seed)
        self.ns, self.ny = pb.groupoid.state_size, pb.groupoid.algebra_dim
        self._rhs = rhs
        self._pieces: dict[int, ca.Function] = {}

    def _piece(self, k: int, m: int) -> ca.Function:
        """:func:`~ocgroupoid.nlp.loop.plant_piece` for polynomials of k coefficients."""
        if k not in self._pieces:
            self._pieces[k] = plant_piece(self._rhs, self.ns + self.ny, k, m, self.P.size)
        return self._pieces[k]

    def advance(self, z: np.ndarray, ppoly: dict[str, np.ndarray], t0: float, t1: float
                ) -> np.ndarray:
        """The state after the control polynomial's span ``[t0, t1]`` (its own times), then
        the process noise on the velocities."""
        breaks, C = np.asarray(ppoly["x"], dtype=float), np.asarray(ppoly["c"], dtype=float)
        k, n, m = C.shape
        piece = self._piece(k, m)
        z = np.asarray(z, dtype=float)
        for j in range(n):
            a, b = max(t0, breaks[j]), min(t1, breaks[j + 1])
            if j == n - 1:
                b = t1  # past the plan's end: its last piece, extended
            if b <= a:
                continue
            c = C[:, j, :].T.ravel(order="F")  # (m, k) column-major: component fastest
            z = np.array(piece(z, c, a - breaks[j], b - a, self.P)).ravel()
        if self.noise > 0:
            z = z.copy()
            z[self.ns:] += self.rng.normal(0.0, self.noise, self.ny)
        return z
