"""Real-time iteration: one SQP step per sample, split into preparation and feedback.

SQP-RTI (Diehl, Bock, Schlöder, "A real-time iteration scheme for nonlinear optimization in
optimal feedback control", SIAM J. Control Optim. 43(5), 2005): at each sample one full-step
SQP iteration with the Hessian of the Lagrangian (exact, or made positive definite stage by
stage: below), from the previous iterate shifted by one interval. With the initial state
embedded (:mod:`~ocgroupoid.mpc.embedding`) it splits:

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
  :data:`HPIPM_INF` = 1e4 is no bound in practice, and the same QPs solve in 7-11 iterations.
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

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..nlp.assembly import assemble
from ..nlp.stageform import NotStaged, stage_form
from ..nlp.transcription import Transcription
from .convexify import StageProjection
from .embedding import embed

#: CasADi conic plug-ins that take the stage structure (N, nx, nu, ng); the first is used
QP_SOLVERS = ("hpipm", "fatrop")
#: HPIPM's options: its robust mode (measured on the four models with active bounds: the
#: speed mode stops at its iteration limit or minimum step on the reaction wheels and the
#: free flyer, balance takes as many iterations as robust and more time); at most 30
#: iterations (the QPs of the four models take 3-13)
HPIPM = {"mode": "robust", "iter_max": 30}
#: the value CasADi's HPIPM interface puts for an infinite bound (module docstring)
HPIPM_INF = 1e4
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
    """The RTI of a transcription (module docstring); ``qp``: one of :data:`QP_SOLVERS`,
    ``hessian``: one of :data:`HESSIANS`."""

    def __init__(self, tr: Transcription, qp: str = "hpipm", hessian: str = HESSIANS[0]
                 ) -> None:
        if qp not in QP_SOLVERS:
            raise ConfigError(f"unknown RTI QP solver {qp!r}; choose one of "
                              f"{', '.join(QP_SOLVERS)}")
        if hessian not in HESSIANS:
            raise ConfigError(f"unknown RTI Hessian {hessian!r}; choose one of "
                              f"{', '.join(HESSIANS)}")
        self.tr, self.qp_name, self.hessian = tr, qp, hessian
        self.embedding = emb = embed(tr)
        try:
            self.form = sf = stage_form(emb.blocks, emb.n_vars)
        except NotStaged as err:
            raise ConfigError(f"real-time iterations need the NLP as a chain of stages, and "
                              f"this one is not ({err}); use converged MPC (no --rti)") from None
        z, p = ca.MX.sym("z", sf.nz), ca.MX.sym("p", tr.np)
        fns = assemble(sf.blocks, z, p)
        order = sf.order.tolist()
        g, jac = fns["nlp_jac_g"](z, p)
        _, grad = fns["nlp_grad_f"](z, p)
        lam = ca.MX.sym("lam_g", sf.order.size)
        hess = ca.triu2symm(fns["nlp_hess_l"](z, p, 1.0, lam[sf.rank.tolist()]))
        #: ``linearise(z, p, lam) -> (H, grad f, A, g)`` in stage order
        self.linearise = ca.Function("rti_linearise", [z, p, lam],
                                     [hess, grad, jac[order, :], g[order]],
                                     ["z", "p", "lam_g"], ["H", "g", "A", "c"])
        structure = {"N": sf.K, "nx": sf.nx, "nu": sf.nu, "ng": sf.ng}
        if sf.nu[-1]:  # CasADi's HPIPM interface has no controls at the last stage: one more
            # stage without variables or rows takes that place (the same QP)
            structure = {"N": sf.K + 1, "nx": [*sf.nx, 0], "nu": [*sf.nu, 0],
                         "ng": [*sf.ng, 0]}
        options: dict[str, Any] = {**structure, "print_time": False, "error_on_fail": False}
        if qp == "hpipm":
            options.update(hpipm=dict(HPIPM), inf=HPIPM_INF)
        else:
            options.update(structure_detection="manual", fatrop={"print_level": 0})
        self.project = StageProjection(hess.sparsity(), [a + b for a, b in zip(sf.nx, sf.nu)])
        self.solver = ca.conic("rti_qp", qp, {"h": self.project.sparsity,
                                              "a": jac[order, :].sparsity()}, options)
        self._embedded = sf.z_slot[tr.nx + np.arange(emb.ne)]
        self._prepared: dict[str, Any] | None = None

    def _z(self, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        return self.form.z_of(np.concatenate([x, p[self.embedding.p_index]]))

    def prepare(self, guess: Iterate, p_predicted: np.ndarray) -> float:
        """Linearise at ``guess`` with the predicted parameters (the state expected at the
        next sample, the horizon of the next solve); returns the seconds it took."""
        t0 = time.perf_counter()
        tr, sf = self.tr, self.form
        z = self._z(guess.x, p_predicted)
        lam_z = sf.rows_z(guess.lam_g)
        H, grad, A, c = self.linearise(z, p_predicted, lam_z)
        if self.hessian == "projected":
            H = self.project(H)
        lbg, ubg, lbx, ubx = (np.array(v).ravel() for v in tr.bounds_function(p_predicted))
        lbx = np.concatenate([lbx, np.full(self.embedding.ne, -np.inf)])
        ubx = np.concatenate([ubx, np.full(self.embedding.ne, np.inf)])
        lbz, ubz = sf.bounds_z(lbx, ubx)
        c = np.array(c).ravel()
        self._prepared = {"z": z, "H": H, "g": grad, "A": A,
                          "lba": sf.rows_z(lbg) - c, "uba": sf.rows_z(ubg) - c,
                          "lbx": lbz - z, "ubx": ubz - z, "e": p_predicted[self.embedding.p_index]}
        return time.perf_counter() - t0

    def feedback(self, p_measured: np.ndarray) -> Feedback:
        """Insert the measured state (p's embedded entries) and take the step."""
        if self._prepared is None:
            raise ConfigError("feedback before prepare: linearise first (prepare)")
        q, sf = self._prepared, self.form
        delta = p_measured[self.embedding.p_index] - q["e"]
        lbx, ubx = q["lbx"].copy(), q["ubx"].copy()
        lbx[self._embedded] = ubx[self._embedded] = delta
        t0 = time.perf_counter()
        H, projected = q["H"], self.hessian == "projected"
        while True:
            r = self.solver(h=H, g=q["g"], a=q["A"], lba=q["lba"], uba=q["uba"], lbx=lbx,
                            ubx=ubx)
            stats = self.solver.stats()
            dz = np.array(r["x"]).ravel()
            ok = bool(stats.get("success", False)) and bool(np.all(np.isfinite(dz)))
            if ok or projected:
                break
            H, projected = self.project(H), True
        seconds = time.perf_counter() - t0
        nx = self.tr.nx
        if not ok:
            dz = np.zeros_like(dz)
        w = sf.x_of(q["z"] + dz)
        lam_g = sf.rows_x(np.array(r["lam_a"]).ravel()) if ok else np.zeros(self.tr.ng)
        lam_x = sf.x_of(np.array(r["lam_x"]).ravel())[:nx] if ok else np.zeros(nx)
        status = ("QP_Solved (projected Hessian)" if projected and self.hessian == "exact"
                  else "QP_Solved") if ok else f"QP_Failed ({stats.get('return_status', '?')})"
        self._prepared = None
        return Feedback(Iterate(w[:nx], lam_g, lam_x), ok, status,
                        int(stats.get("iter_count", 0) or 0), seconds)
