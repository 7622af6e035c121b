"""The real-time iteration's arithmetic as CasADi Functions: one definition for Python and C.

A real-time iteration (:mod:`ocgroupoid.mpc.rti`, ``DIR/mpc --rti`` of an export) is one
full-step SQP iteration of the NLP with the initial state embedded
(:mod:`~ocgroupoid.nlp.embedding`), in the stage order of :mod:`~ocgroupoid.nlp.stageform`.
Its pieces, each a Function that Python evaluates and the export generates C of:

* :attr:`RtiFunctions.prepare` — ``(x, lam_g, p) -> (z, H, g, A, lba, uba, lbx, ubx, e)``:
  at a primal-dual point and the predicted parameters, the QP in the step ``dz``: the exact
  Hessian of the Lagrangian, the gradient, the constraint Jacobian, the row and variable
  bounds less the linearisation, and ``e``, the embedded variables' values (the predicted
  state);
* :attr:`RtiFunctions.fix` — ``(lbx, ubx, e, p) -> (lbx, ubx)``: the embedded variables'
  step fixed at the measured state in p less e (the feedback's only change of the QP);
* :attr:`RtiFunctions.solver` — the QP: CasADi's ``hpipm`` (or ``fatrop``) conic with the
  stage structure (:data:`HPIPM`, :data:`HPIPM_INF`: :mod:`ocgroupoid.mpc.rti` says why);
* :attr:`RtiFunctions.update` — ``(z, dz, lam_a, lam_x) -> (x, lam_g, lam_x)``: the full
  step and the QP's multipliers, back in the NLP's variables and rows.

Between ``prepare`` and the QP the Hessian's stage blocks may be projected onto the positive
definite matrices (``hessian="projected"``, :data:`FLOOR`): numpy's ``eigh`` in Python
(:mod:`ocgroupoid.mpc.convexify`), Jacobi rotations in the exported C — an
eigendecomposition has no CasADi operation to generate.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..errors import ConfigError
from .assembly import assemble
from .embedding import embed
from .stageform import NotStaged, stage_form
from .transcription import Transcription

#: CasADi conic plug-ins that take the stage structure (N, nx, nu, ng); the first is used
QP_SOLVERS = ("hpipm", "fatrop")
#: HPIPM's options: its robust mode (measured on the four models with active bounds: the
#: speed mode stops at its iteration limit or minimum step on the reaction wheels and the
#: free flyer, balance takes as many iterations as robust and more time); at most 30
#: iterations (the QPs of the four models take 3-13)
HPIPM = {"mode": "robust", "iter_max": 30}
#: the value CasADi's HPIPM interface puts for an infinite bound (:mod:`ocgroupoid.mpc.rti`)
HPIPM_INF = 1e4
#: the smallest eigenvalue a projected stage block keeps, relative to the largest |H| entry
#: (:mod:`ocgroupoid.mpc.convexify`; the exported C's projection takes it too)
FLOOR = 1e-8


class RtiFunctions:
    """The Functions of one transcription's real-time iteration (module docstring), named
    ``{name}prepare``, ``{name}fix``, ``{name}qp`` and ``{name}update``."""

    def __init__(self, tr: Transcription, qp: str = QP_SOLVERS[0], name: str = "rti_") -> None:
        if qp not in QP_SOLVERS:
            raise ConfigError(f"unknown RTI QP solver {qp!r}; choose one of "
                              f"{', '.join(QP_SOLVERS)}")
        self.embedding = emb = embed(tr)
        try:
            self.form = sf = stage_form(emb.blocks, emb.n_vars)
        except NotStaged as err:
            raise ConfigError(f"real-time iterations need the NLP as a chain of stages, and "
                              f"this one is not ({err}); use converged MPC (no --rti)") from None
        ne = emb.ne
        x, lam_g, p = (ca.MX.sym(n, k) for n, k in (("x", tr.nx), ("lam_g", tr.ng), ("p", tr.np)))
        e = p[emb.p_index.tolist()]
        zs, lam = ca.MX.sym("z", sf.nz), ca.MX.sym("lam_g", sf.order.size)
        fns = assemble(sf.blocks, zs, p, whole=True)  # the whole Hessian, from the stages
        order = sf.order.tolist()
        g, jac = fns["nlp_jac_g"](zs, p)
        _, grad = fns["nlp_grad_f"](zs, p)
        _, hess = fns["nlp_hess_l"](zs, p, 1.0, lam[sf.rank.tolist()])
        #: the stage sizes ``nx + nu``, and the Hessian's pattern: their dense diagonal blocks
        self.stage_sizes = [a + b for a, b in zip(sf.nx, sf.nu)]
        self.hessian_sparsity = ca.diagcat(*[ca.Sparsity.dense(s, s) for s in self.stage_sizes])
        linearise = ca.Function(f"{name}linearise", [zs, p, lam],
                                [ca.project(hess, self.hessian_sparsity), grad, jac[order, :],
                                 g[order]])
        z = sf.z_of(ca.vertcat(x, e))
        H, grad, A, c = linearise(z, p, sf.rows_z(lam_g))
        lbg, ubg, lbx, ubx = tr.bounds_function(p)
        free = ca.MX(ca.DM.ones(ne))
        lbz, ubz = sf.bounds_z(ca.vertcat(lbx, -np.inf * free), ca.vertcat(ubx, np.inf * free))
        self.prepare = ca.Function(
            f"{name}prepare", [x, lam_g, p],
            [z, H, grad, A, sf.rows_z(lbg) - c, sf.rows_z(ubg) - c, lbz - z, ubz - z, e],
            ["x", "lam_g", "p"], ["z", "H", "g", "A", "lba", "uba", "lbx", "ubx", "e"])
        embedded = sf.z_slot[tr.nx + np.arange(ne)].tolist()
        lo, up, e0 = ca.MX.sym("lbx", sf.nz), ca.MX.sym("ubx", sf.nz), ca.MX.sym("e", ne)
        delta = e - e0  # e: the measured state's entries of p
        lo_fixed, up_fixed = ca.MX(lo), ca.MX(up)
        lo_fixed[embedded] = delta
        up_fixed[embedded] = delta
        self.fix = ca.Function(f"{name}fix", [lo, up, e0, p], [lo_fixed, up_fixed],
                               ["lbx", "ubx", "e", "p"], ["lbx_fixed", "ubx_fixed"])
        zz, dz, lam_a, lam_x = (ca.MX.sym(n, k) for n, k in (
            ("z", sf.nz), ("dz", sf.nz), ("lam_a", sf.order.size), ("lam_x", sf.nz)))
        self.update = ca.Function(
            f"{name}update", [zz, dz, lam_a, lam_x],
            [sf.x_of(zz + dz)[:tr.nx], sf.rows_x(lam_a), sf.x_of(lam_x)[:tr.nx]],
            ["z", "dz", "lam_a", "lam_x"], ["x_next", "lam_g_next", "lam_x_next"])
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
        self.solver = ca.conic(f"{name}qp", qp, {"h": self.hessian_sparsity,
                                                  "a": A.sparsity()}, options)
