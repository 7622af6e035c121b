"""The warm start of the next sample: the last primal-dual point moved along its own time.

The NLP in stage form (:mod:`~ocgroupoid.nlp.stageform`) is a chain of K + 1 stages, stage k
at time ``k T / K`` of its horizon; each stage holds four parts — states ``x_k``, controls
``u_k``, the gap rows into ``x_{k+1}`` and its own rows — of the same sizes at every interior
stage. The next sample's problem starts h later; its stage k sits at time ``h + k T' / K`` of
the last one, i.e. at the fractional stage

    sigma_k = K h / T + k T' / T        (T' = T: receding; T' = T - h: shrinking),

and takes there each part of the last point, linearly interpolated between the two stages
around sigma_k (for the receding horizon with h = T/N this is the classic shift by one stage;
a part whose size differs there, the ends of the chain, keeps its own value — the last stage
is repeated). Multipliers move with their rows. Group states are interpolated in their stored
coordinates: a warm start need not lie on the group, the reconstruction rows pull the next
iterate back onto it. The bound multipliers of a shrinking horizon are interpolated without
rescaling by the ratio of the steps: a first-order warm start, which IPOPT and the RTI's QP
correct.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..nlp.stageform import StageForm, stage_form
from ..nlp.transcription import Transcription
from .rti import Iterate


@dataclass(frozen=True)
class _Part:
    """One part of every stage: its offset and size per stage in a stage-ordered vector."""

    start: np.ndarray
    size: np.ndarray


def _parts(sf: StageForm) -> tuple[list[_Part], list[_Part]]:
    """The (x, u) parts of z and the (gap, stage rows) parts of the rows, per stage."""
    nx, nu, ng = (np.asarray(v) for v in (sf.nx, sf.nu, sf.ng))
    z_start = np.concatenate([[0], np.cumsum(nx + nu)[:-1]])
    gaps = np.concatenate([nx[1:], [0]])  # stage k's gap rows define x_{k+1}
    r_start = np.concatenate([[0], np.cumsum(gaps + ng)[:-1]])
    return ([_Part(z_start, nx), _Part(z_start + nx, nu)],
            [_Part(r_start, gaps), _Part(r_start + gaps, ng)])


class Shift:
    """Moves points of one transcription along time (module docstring)."""

    def __init__(self, tr: Transcription) -> None:
        self.tr = tr
        self.form = stage_form(tr.blocks, tr.nx)
        self.z_parts, self.row_parts = _parts(self.form)

    def sigma(self, h: float, T: float, T_next: float) -> np.ndarray:
        """The fractional stage of the last point where each new stage sits."""
        K = self.form.K
        return K * h / T + np.arange(K + 1) * T_next / T

    def __call__(self, it: Iterate, sigma: np.ndarray) -> Iterate:
        """The point ``it`` moved to the stages ``sigma`` (:meth:`sigma`)."""
        sf = self.form
        z = _move(sf.z_of(it.x), self.z_parts, sigma)
        lam_z = _move(sf.z_of(it.lam_x), self.z_parts, sigma)
        rows = _move(sf.rows_z(it.lam_g), self.row_parts, sigma)
        return Iterate(sf.x_of(z), sf.rows_x(rows), sf.x_of(lam_z))


def _move(v: np.ndarray, parts: list[_Part], sigma: np.ndarray) -> np.ndarray:
    """Every stage's parts of the stage-ordered vector v taken at the fractional stages."""
    out = v.copy()
    K = sigma.size - 1
    for part in parts:
        for k in range(K + 1):
            n = part.size[k]
            if n == 0:
                continue
            s = min(max(sigma[k], 0.0), float(K))
            k0 = int(np.floor(s))
            k1, w = min(k0 + 1, K), s - k0
            here = slice(part.start[k], part.start[k] + n)
            sources = [(j, wt) for j, wt in ((k0, 1.0 - w), (k1, w))
                       if part.size[j] == n and wt > 0.0]
            total = sum(wt for _, wt in sources)
            if total > 0.0:
                out[here] = sum(wt * v[part.start[j]:part.start[j] + n]
                                for j, wt in sources) / total
    return out
