"""Real-time iteration: one SQP step per sample, split into preparation and feedback.

SQP-RTI (Diehl, Bock, Schlöder, "A real-time iteration scheme for nonlinear optimization in
optimal feedback control", SIAM J. Control Optim. 43(5), 2005): at each sample one full-step
SQP iteration with the Hessian of the Lagrangian (exact, or made positive definite stage by
stage: below), from the previous iterate shifted by one interval. With the initial state
embedded (:mod:`~ocgroupoid.nlp.embedding`) it splits:

* :meth:`RealTimeIteration.prepare` — before the measurement: evaluate the QP (Hessian,
  gradient, constraint Jacobian and residuals) at the shifted primal-dual point and the
  predicted state;
* :meth:`RealTimeIteration.feedback` — once the state is measured: fix the embedded
  variables at it (two bound vectors) and solve the QP; the new iterate is the old one plus
  the step, the multipliers the QP's (full step).

The QP keeps the NLP's stage structure (:mod:`~ocgroupoid.nlp.stageform`: variables
``[x_0, u_0, ..., x_K, u_K]``, rows ``[gaps into x_1, stage 0 rows, ...]``) and is solved by
HPIPM's Riccati-based interior point method (CasADi's ``hpipm`` conic plug-in), in time linear
in N. CasADi's ``fatrop`` conic plug-in is the other choice (``qp="fatrop"``); with CasADi 3.8
it prints its debug output and failed 1 of 15 so3 steps where HPIPM solved all.

Two things made HPIPM fail on the free flyer, the reaction wheels and the quadrotor (every
step of the last two, at 100 iterations each), and both are fixed here:

* CasADi's interface boxes every variable, an infinite bound becoming ``±inf`` (its option,
  default 1e8). HPIPM's complementarity residual for a slack of 1e8 does not reach its
  tolerance (1e-8 in robust mode), so the method ran to its iteration limit with the step
  found (to 6e-5 of IPOPT's on the same QP). The QP's variables are steps, so
  :data:`~ocgroupoid.nlp.rti.HPIPM_INF` = 1e4 is no bound in practice, and the same QPs
  solve in 7-11 iterations.
* The Riccati recursion factors every stage's Hessian plus cost-to-go, which the exact
  Hessian of the Lagrangian leaves indefinite on these models (:mod:`~ocgroupoid.mpc.convexify`).
  ``hessian="projected"`` (the default) projects each stage block onto the positive definite
  matrices before the QP: the step is an SQP step with a modified Hessian (first-order
  accurate in the measurement). Measured at N = 32, a receding horizon for N samples, bounds
  active, kicks of 1e-4: no QP of the rigid body, the free flyer, the reaction wheels or the
  quadrotor fails (before: 6 of 31 free-flyer QPs needed a regularised retry, p99 231 ms, and
  30 and 31 of 31 failed on the other two). ``hessian="exact"`` keeps the exact Hessian — the
  tangential predictor below — and solves the QP again with the projected one when HPIPM
  fails on it (the status says so): never on the rigid body, 11 of 31 samples on the
  reaction wheels, 18 on the free flyer, all 31 on the quadrotor.

A QP that fails leaves the iterate where it was (``success`` False).

Theory, for the exact Hessian (Diehl et al. 2005, Thm. 5.3; Zanon et al. 2021): started at
the exact solution for a predicted state, one RTI step for a measured state ``p̄ + Δ`` lands
``O(|Δ|^2)`` from the exact solution for it (the tangential predictor), and along a slowly
varying trajectory the distance stays of the order of the square of the per-sample change.
With a projected block the step is exact only to first order, ``O(|Δ|)``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ConfigError
from ..nlp.rti import QP_SOLVERS, RtiFunctions
from ..nlp.transcription import Transcription
from .convexify import StageProjection

__all__ = ["QP_SOLVERS", "HESSIANS", "Iterate", "Feedback", "RealTimeIteration"]

#: the QP's Hessian: each stage block projected onto the positive definite matrices (the
#: default), or the exact Hessian of the Lagrangian (a projected one when the QP fails with
#: it); module docstring
HESSIANS = ("projected", "exact")


@dataclass
class Iterate:
    """A primal-dual point of the NLP in its original variables."""

    x: np.ndarray
    lam_g: np.ndarray
    lam_x: np.ndarray


@dataclass
class Feedback:
    """What one feedback phase returns: the new iterate, whether the QP solved, its
    iterations, and the seconds of the QP alone."""

    iterate: Iterate
    success: bool
    status: str
    iterations: int
    qp_seconds: float


class RealTimeIteration:
    """The RTI of a transcription (module docstring) on the Functions of
    :class:`~ocgroupoid.nlp.rti.RtiFunctions` (those the exported C runs); ``qp``: one of
    :data:`QP_SOLVERS`, ``hessian``: one of :data:`HESSIANS`."""

    def __init__(self, tr: Transcription, qp: str = "hpipm", hessian: str = HESSIANS[0]
                 ) -> None:
        if hessian not in HESSIANS:
            raise ConfigError(f"unknown RTI Hessian {hessian!r}; choose one of "
                              f"{', '.join(HESSIANS)}")
        self.tr, self.qp_name, self.hessian = tr, qp, hessian
        self.functions = fns = RtiFunctions(tr, qp)
        self.solver = fns.solver
        self.project = StageProjection(fns.hessian_sparsity, fns.stage_sizes)
        self._prepared: dict[str, Any] | None = None

    def prepare(self, guess: Iterate, p_predicted: np.ndarray) -> float:
        """Linearise at ``guess`` with the predicted parameters (the state expected at the
        next sample, the horizon of the next solve); returns the seconds it took."""
        t0 = time.perf_counter()
        q = dict(zip(self.functions.prepare.name_out(),
                     self.functions.prepare(guess.x, guess.lam_g, p_predicted)))
        if self.hessian == "projected":
            q["H"] = self.project(q["H"])
        self._prepared = q
        return time.perf_counter() - t0

    def feedback(self, p_measured: np.ndarray) -> Feedback:
        """Insert the measured state (p's embedded entries) and take the step."""
        if self._prepared is None:
            raise ConfigError("feedback before prepare: linearise first (prepare)")
        q, fns = self._prepared, self.functions
        lbx, ubx = fns.fix(q["lbx"], q["ubx"], q["e"], p_measured)
        t0 = time.perf_counter()
        H, projected = q["H"], self.hessian == "projected"
        while True:
            r = self.solver(h=H, g=q["g"], a=q["A"], lba=q["lba"], uba=q["uba"], lbx=lbx,
                            ubx=ubx)
            stats = self.solver.stats()
            ok = bool(stats.get("success", False)) and bool(np.all(np.isfinite(np.array(r["x"]))))
            if ok or projected:
                break
            H, projected = self.project(H), True
        seconds = time.perf_counter() - t0
        nx, ng = self.tr.nx, self.tr.ng
        if ok:
            x, lam_g, lam_x = (np.array(v).ravel()
                               for v in fns.update(q["z"], r["x"], r["lam_a"], r["lam_x"]))
        else:  # the iterate where it was (zero step), no multipliers
            x = np.array(fns.update(q["z"], 0.0, 0.0, 0.0)[0]).ravel()
            lam_g, lam_x = np.zeros(ng), np.zeros(nx)
        status = ("QP_Solved (projected Hessian)" if projected and self.hessian == "exact"
                  else "QP_Solved") if ok else f"QP_Failed ({stats.get('return_status', '?')})"
        self._prepared = None
        return Feedback(Iterate(x, lam_g, lam_x), ok, status,
                        int(stats.get("iter_count", 0) or 0), seconds)
