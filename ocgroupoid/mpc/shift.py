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

The move is one CasADi Function with sigma an input,
:func:`~ocgroupoid.nlp.loop.shift_function` (tent weights on sigma, normalised: the linear
interpolation above), which this loop evaluates and the exported C loop runs generated: both
horizons do the same arithmetic in Python and in C.
"""

from __future__ import annotations

import numpy as np

from ..nlp.buffered import Buffered
from ..nlp.loop import shift_function, stages_after
from ..nlp.stageform import stage_form
from ..nlp.transcription import Transcription
from .rti import Iterate


class Shift:
    """Moves points of one transcription along time (module docstring)."""

    def __init__(self, tr: Transcription) -> None:
        self.tr = tr
        self.form = stage_form(tr.blocks, tr.nx)
        self.function = shift_function(tr, self.form)
        self._call = Buffered(self.function)

    def sigma(self, h: float, T: float, T_next: float) -> np.ndarray:
        """The fractional stage of the last point where each new stage sits."""
        return stages_after(self.form.K, h, T, T_next)

    def __call__(self, it: Iterate, sigma: np.ndarray) -> Iterate:
        """The point ``it`` moved to the stages ``sigma`` (:meth:`sigma`)."""
        return Iterate(*self._call(x=it.x, lam_g=it.lam_g, lam_x=it.lam_x,
                                   sigma=sigma).values())
