"""The two feedback laws of the loop, with one interface: prepare, then feedback.

Both start from the last point shifted along time (:mod:`~ocgroupoid.mpc.shift`):

* :class:`Converged` re-solves the NLP to convergence from it. IPOPT starts from the whole
  primal-dual point (``warm_start_init_point``, small bound pushes, ``mu_init`` 1e-6:
  :data:`~ocgroupoid.nlp.transcription.WARM_IPOPT`). CasADi's fatrop interface takes no
  multipliers: with ``backend="fatrop"`` it starts from the shifted primal point only.
  Its preparation does nothing: everything waits for the measurement.
* :class:`RealTime` takes one SQP step (:mod:`~ocgroupoid.mpc.rti`): the linearisation is
  prepared before the measurement, the QP solved after it.

A step whose solver fails keeps the shifted point, so the loop applies the last plan's
continuation and counts the failure.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..nlp.transcription import Guess, Transcription
from .rti import HESSIANS, Iterate, RealTimeIteration


@dataclass
class Outcome:
    """A feedback phase's result: the point to apply and how the solver fared."""

    iterate: Iterate
    success: bool
    status: str
    iterations: int
    seconds: float


class Converged:
    """Warm-started converged re-solves (module docstring)."""

    name = "converged"

    def __init__(self, tr: Transcription) -> None:
        self.tr = tr
        self._guess: Iterate | None = None

    def prepare(self, guess: Iterate, p_predicted: np.ndarray) -> float:
        """Keep the shifted point; nothing can be computed before the measurement."""
        self._guess = guess
        return 0.0

    def feedback(self, p_measured: np.ndarray) -> Outcome:
        """Solve from the prepared point with the measured state."""
        assert self._guess is not None, "prepare() first"
        g = self._guess
        t0 = time.perf_counter()
        r = self.tr.solve(Guess("shifted", np.zeros((0, 0)), g.x, g.lam_g, g.lam_x), p_measured)
        seconds = time.perf_counter() - t0
        it = Iterate(r.x, r.lam_g, r.lam_x if r.lam_x.size == g.x.size else g.lam_x) \
            if r.success else g
        return Outcome(it, r.success, r.status, r.iterations, seconds)


class RealTime:
    """One real-time iteration per sample (module docstring)."""

    name = "rti"

    def __init__(self, tr: Transcription, qp: str = "hpipm", hessian: str = HESSIANS[0]
                 ) -> None:
        self.rti = RealTimeIteration(tr, qp, hessian)
        self._guess: Iterate | None = None

    def prepare(self, guess: Iterate, p_predicted: np.ndarray) -> float:
        """Linearise at the shifted point and the predicted state."""
        self._guess = guess
        return self.rti.prepare(guess, p_predicted)

    def feedback(self, p_measured: np.ndarray) -> Outcome:
        """Solve the prepared QP with the measured state."""
        assert self._guess is not None, "prepare() first"
        t0 = time.perf_counter()
        fb = self.rti.feedback(p_measured)
        seconds = time.perf_counter() - t0
        return Outcome(fb.iterate if fb.success else self._guess, fb.success, fb.status,
                       fb.iterations, seconds)
