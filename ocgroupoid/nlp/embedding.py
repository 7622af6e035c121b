"""Initial-value embedding: the measured state as variables of the NLP, fixed by their bounds.

The transcription reads the initial state (``p``'s ``start`` and ``V0`` slices) as
parameters. A real-time iteration linearises before the state is measured, so the measured
state must enter the linearisation linearly. As in acados (Gros, Zanon, Quirynen, Bemporad,
Diehl, "From linear to nonlinear MPC: bridging the gap via the real-time iteration", Int. J.
Control 93(1), 2020, §4.1), the measured quantities become decision variables ``e`` of the
first stage, fixed by ``lbx = ubx = e_measured``: the QP's constraint Jacobian and Hessian then
carry their first-order effect (the tangential predictor), and the feedback phase only
changes two bound vectors. The blocks are re-indexed into ``w = [x; e; p]`` (p keeps its size;
its embedded entries are no longer read); nothing else of the NLP changes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from .assembly import Block
from .transcription import Transcription

#: the slices of p the plant measures
MEASURED = ("start", "V0")


@dataclass(frozen=True)
class Embedding:
    """The blocks over ``[x; e; p]``, the number of variables ``nx + ne``, and the p-indices
    the embedded variables ``e`` stand for (in order)."""

    blocks: list[Block]
    n_vars: int
    p_index: np.ndarray

    @property
    def ne(self) -> int:
        return int(self.p_index.size)


def check_measurable(tr: Transcription) -> None:
    """Refuse a problem whose initial state is not wholly prescribed: a closed loop sets every
    component from the measurement."""
    free = [f.state for f, m in zip(tr.problem.groupoid.factors, tr.masks.start_state)
            if not m.all()]
    if tr.problem.end_velocities and not tr.masks.start_velocity.all():
        free.append("initial velocity")
    if free:
        raise ConfigError(f"MPC sets the whole initial state from the measurement, but "
                          f"{', '.join(free)} is left free in {tr.problem.name!r}: prescribe "
                          "every initial component in the problem (its value is the first "
                          "measurement)")


def embed(tr: Transcription) -> Embedding:
    """The blocks of ``tr`` with p's :data:`MEASURED` entries turned into variables."""
    check_measurable(tr)
    nx = tr.nx
    p_index = np.concatenate([np.arange(tr.np)[tr.layout.p_slices[k]] for k in MEASURED])
    ne = p_index.size
    where = np.full(tr.np, -1)
    where[p_index] = np.arange(ne)
    out = []
    for b in tr.blocks:
        idx = b.idx.copy()
        in_p = idx >= nx
        j = np.where(in_p, idx - nx, 0)
        embedded = in_p & (where[j] >= 0)
        idx[embedded] = nx + where[j[embedded]]
        idx[in_p & ~embedded] += ne
        out.append(Block(b.name, b.fun, idx, b.n_param, b.kind, b.rows, b.columns, b.times,
                         b.points, b.bounds, b.g_offset, next=b.next))
    return Embedding(out, nx + ne, p_index)
