"""The closed loop in exported C: ``{prefix}mpc.c/.h`` and the driver ``DIR/mpc``.

The C loop (``c_templates/mpc.c.in``) is Python's loop (:func:`ocgroupoid.mpc.mpc`), its
sample h = T/N, with a receding or a shrinking horizon (``@prefix@mpc_set_horizon``,
``DIR/mpc --horizon``: the final time fixed, p's T the time left at every sample, the last
plan held once fewer than ``min_horizon`` samples are left); its arithmetic is the Functions
of :mod:`ocgroupoid.nlp.loop` the Python loop evaluates, generated here into
``{prefix}generated_mpc.c``: the plant piece, the shift (the fractional stages sigma an
input, computed in C per sample as :func:`~ocgroupoid.nlp.loop.stages_after` computes them),
the measured state into p, the initial state of p, distances, terminal errors and the bound
violation.

An export writes the loop when the problem has one (:func:`reason`): a fixed final time and
continuous second-order dynamics, as Python's loop requires.

Real-time iterations (``@prefix@mpc_set_rti``, ``DIR/mpc --rti``): with an NLP in stage form,
the Functions of :class:`~ocgroupoid.nlp.rti.RtiFunctions` (the preparation, the bounds fixed
at the measured state, HPIPM's QP, the full step), which Python's ``og.mpc(rti=True)``
evaluates, are generated too, and the driver links HPIPM and blasfeo from the casadi wheel.
The stage projection of ``hessian="projected"`` (in Python numpy's eigendecomposition, which
has no CasADi operation to generate) is the template's C: Jacobi rotations. CasADi 3.8's
generated HPIPM call leaves five of HPIPM's options unset (among them ``dual_gap_max``, so a
QP ran to its iteration limit); :func:`~ocgroupoid.export.functions.hpipm_defaults` sets
HPIPM's defaults of the mode first, as CasADi's own interface does. The generated call also
drops HPIPM's iteration count, which Python's RTI reports (the conic's ``iter_count``);
:func:`~ocgroupoid.export.functions.hpipm_iterations` hands it to the hooks, so that C's
steps report the same.
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from ..errors import ConfigError
from ..nlp.assembly import Kind
from ..nlp.loop import (
    MIN_HORIZON,
    check_fixed_horizon,
    distance_function,
    distance_names,
    initial_state,
    plant_dynamics,
    plant_piece,
    shift_function,
    terminal_function,
    terminal_names,
    violation_function,
    with_state_function,
)
from ..nlp.program import C_READOUT_OUTPUTS
from ..nlp.rti import FLOOR, RtiFunctions
from ..nlp.stageform import stage_form
from ..nlp.transcription import Transcription
from .literals import c_names

#: the loop's files rendered from c_templates (prefixed as the library's) and the driver's
PREFIXED = ("mpc.h", "mpc.c")
DRIVER = "mpc_main.c"


def reason(tr: Transcription) -> str | None:
    """Why ``tr`` has no closed loop (the message Python's ``og.mpc`` raises), or None."""
    try:
        check_fixed_horizon(tr.problem)
        plant_dynamics(tr)
    except ConfigError as err:
        return str(err)
    return None


def wanted(tr: Transcription, mpc: bool | None) -> bool:
    """Whether an export writes the loop: ``mpc`` None writes it when the problem has one,
    True requires it (a ConfigError says why not), False leaves it out."""
    why = reason(tr)
    if mpc and why is not None:
        raise ConfigError(f"export with mpc: {why}; or export without the loop "
                          "(mpc=False, export-c --no-mpc)")
    return mpc is not False and why is None


def rti(tr: Transcription, prefix: str) -> RtiFunctions | None:
    """The real-time iteration's Functions, named ``{prefix}gen_rti_...``, or None when the
    problem has none (its NLP is not a chain of stages, its initial state not prescribed)."""
    try:
        return RtiFunctions(tr, name=f"{prefix}gen_rti_")
    except ConfigError:
        return None


def functions(tr: Transcription, prefix: str, real_time: RtiFunctions | None
              ) -> list[ca.Function]:
    """The loop's Functions (:mod:`ocgroupoid.nlp.loop`), named ``{prefix}gen_...``, and those
    of ``real_time`` (:func:`rti`)."""
    m = len(tr.problem.controls)
    k = _coefficients(tr) // max(m, 1)
    G = tr.problem.groupoid
    n = f"{prefix}gen_"
    return [plant_piece(plant_dynamics(tr), G.state_size + G.algebra_dim, k, m,
                        tr.layout.p_slices["P"].stop - tr.layout.p_slices["P"].start,
                        n + "plant"),
            shift_function(tr, stage_form(tr.blocks, tr.nx), n + "shift"),
            with_state_function(tr, n + "with_state"),
            initial_state(tr, n + "initial_state"), distance_function(tr, n + "distance"),
            terminal_function(tr, n + "terminal"),
            violation_function(tr, tr.rows(Kind.INEQUALITY).ravel(), n + "violation")
            ] + ([] if real_time is None else [real_time.prepare, real_time.fix,
                                               real_time.solver, real_time.update])


def _coefficients(tr: Transcription) -> int:
    """The numbers of one piece of the read-out's control polynomial (k m)."""
    x, p, lam = ca.MX.sym("x", tr.nx), ca.MX.sym("p", tr.np), ca.MX.sym("lam_g", tr.ng)
    out = tr.readout_function(x, p, lam)[C_READOUT_OUTPUTS.index("control_coefficients")]
    return int(out.size1())


def values(tr: Transcription, real_time: RtiFunctions | None) -> dict[str, Any]:
    """What mpc.h.in and mpc.c.in are filled with."""
    G, P = tr.problem.groupoid, tr.layout.p_slices["P"]
    distances, terminals = distance_names(tr), terminal_names(tr)
    sizes = {"MPC_RTI": 0, "MPC_RTI_NZ": 1, "MPC_RTI_NROWS": 1, "MPC_RTI_NE": 1,
             "MPC_RTI_NNZ_H": 1, "MPC_RTI_NNZ_A": 1, "MPC_RTI_BLOCKS": "{1}",
             "MPC_RTI_MAX_BLOCK": 1, "MPC_RTI_FLOOR": repr(FLOOR)}
    if real_time is not None:
        out = real_time.prepare.sparsity_out
        sizes = {"MPC_RTI": 1, "MPC_RTI_NZ": real_time.form.nz,
                 "MPC_RTI_NROWS": int(real_time.form.order.size),
                 "MPC_RTI_NE": real_time.embedding.ne, "MPC_RTI_NNZ_H": out(1).nnz(),
                 "MPC_RTI_NNZ_A": out(3).nnz(), "MPC_RTI_FLOOR": repr(FLOOR),
                 "MPC_RTI_BLOCKS": "{" + ", ".join(map(str, real_time.stage_sizes)) + "}",
                 "MPC_RTI_MAX_BLOCK": max(max(real_time.stage_sizes), 1)}
    return {"MPC_NZ": G.state_size + G.algebra_dim, "MPC_NS": G.state_size,
            "MPC_NP_PLANT": P.stop - P.start, "MPC_P_OFFSET": P.start,
            "MPC_N_DISTANCES": len(distances), "MPC_N_TERMINAL": len(terminals),
            "MPC_DISTANCE_NAMES": c_names(distances), "MPC_TERMINAL_NAMES": c_names(terminals),
            "MPC_PIECE_COEFFICIENTS": max(_coefficients(tr), 1),
            "MPC_STAGES": stage_form(tr.blocks, tr.nx).K + 1, "MPC_MIN_HORIZON": MIN_HORIZON,
            **sizes}


def make_values(prefix: str, on: bool, real_time: bool) -> dict[str, str]:
    """The Makefile's lines of the loop: its objects, headers and the driver's rule (linked
    with HPIPM and blasfeo for ``real_time``)."""
    if not on:
        return {"MPC_OBJECTS": "", "MPC_HEADERS": "", "MPC_ALL": "", "MPC_RULE": "",
                "MPC_CLEAN": "", "MPC_LDLIBS": ""}
    return {"MPC_OBJECTS": f" {prefix}mpc.o {prefix}generated_mpc.o",
            "MPC_HEADERS": f" {prefix}mpc.h {prefix}generated_mpc.h", "MPC_ALL": " mpc",
            "MPC_RULE": ("# The closed loop (README.md, The closed loop): ./mpc --steps K ...\n"
                         "mpc: mpc_main.o @prefix@params.o libocg.a\n"
                         "\t$(CC) $(OPT) $(CFLAGS) $(LDFLAGS) -o $@ mpc_main.o @prefix@params.o "
                         "libocg.a $(OCG_LDLIBS) $(MPC_LDLIBS) $(LDLIBS)\n"
                         ).replace("@prefix@", prefix),
            "MPC_CLEAN": " mpc mpc_main.o",
            "MPC_LDLIBS": " -lhpipm -lblasfeo" if real_time else ""}
