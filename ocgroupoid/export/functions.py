"""The Functions an export generates C of, and their C (CasADi's code generator).

Each is a Function the Python path evaluates too (nothing here computes anything of its own),
named after the export's prefix (``ocg_`` by default), so that two exports link into one
program:

``{prefix}gen_nlpsol(x0, p) -> (x, f, g, lam_g, lam_x)``  the Transcription's IPOPT solver
with the bounds computed from p, and ``{prefix}gen_nlpsol_warm`` the same from a primal-dual
point (with ``solver.backend: fatrop`` both are fatrop's driver instead, and the stage form's
Functions are generated: :mod:`~ocgroupoid.export.fatrop`); ``{prefix}gen_guess(p) -> x0``
the first geodesic guess; ``{prefix}gen_pack(values) -> (p, bad)`` the packing of a
parameter file's numbers; ``{prefix}gen_post(x, p, lam_g)`` the read-out a Solution is made
of; ``{prefix}gen_verify(x, p, lam_g) -> (ratios, figures)`` the verdict's checks
(:mod:`~ocgroupoid.verify.graph`).
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path
from typing import Any, Sequence

import casadi as ca

from ..errors import ExportError
from ..nlp.program import C_READOUT_OUTPUTS
from ..nlp.transcription import Transcription
from ..verify.diagnostics import replay_of
from ..verify.graph import verify_function
from ..verify.verdict import REPLAY_TOLERANCE, check_tolerance
from . import fatrop as exported_fatrop

#: outputs of the generated solvers ({prefix}gen_nlpsol, {prefix}gen_nlpsol_warm)
SOLVE_OUTPUTS = ("x", "f", "g", "lam_g", "lam_x")
#: RK4 substeps per piece of the exported replay (its own error is checked against half as
#: many: a replay that has not converged fails the verdict)
EXPORT_SUBSTEPS = 32


def guess_function(tr: Transcription, prefix: str) -> ca.Function:
    """``{prefix}gen_guess(p) -> x0``: the point of the first geodesic guess."""
    p = ca.MX.sym("p", tr.np)
    first = tr.guess_function(p)
    first = first[0] if isinstance(first, (list, tuple)) else first
    return ca.Function(f"{prefix}gen_guess", [p], [tr.point_function(first, p)], ["p"], ["x0"])


def post_function(tr: Transcription, prefix: str) -> ca.Function:
    """``{prefix}gen_post(x, p, lam_g)``: the read-out outputs exported C reads (enum
    {prefix}output)."""
    x, p, lam = ca.MX.sym("x", tr.nx), ca.MX.sym("p", tr.np), ca.MX.sym("lam_g", tr.ng)
    outs = tr.readout_function(x, p, lam)
    return ca.Function(f"{prefix}gen_post", [x, p, lam], list(outs)[:len(C_READOUT_OUTPUTS)],
                       ["x", "p", "lam_g"], list(C_READOUT_OUTPUTS))


def verify_export(tr: Transcription, ipopt: dict[str, Any] | None, prefix: str) -> ca.Function:
    """``{prefix}gen_verify(x, p, lam_g) -> (ratios, figures)``."""
    fn = verify_function(tr, replay_of(tr), EXPORT_SUBSTEPS, check_tolerance(ipopt),
                         REPLAY_TOLERANCE)
    x, p, lam = ca.MX.sym("x", tr.nx), ca.MX.sym("p", tr.np), ca.MX.sym("lam_g", tr.ng)
    return ca.Function(f"{prefix}gen_verify", [x, p, lam],  # type: ignore[call-overload]
                       fn(x, p, lam), ["x", "p", "lam_g"],  # (stubs: one MX, not two)
                       ["ratios", "figures"])


#: what a failed check of the exported verdict says (the order of verify_graph.CHECKS)
CHECK_FAILURES = {
    "residual": "a residual or a bound at its points exceeds the check tolerance",
    "landing": "the plan does not land: replayed through the continuous problem it misses "
               "a final value by more than the landing tolerance; increase N",
    "bounds": "a bound is violated between the points where it is imposed (along the "
              "replayed plan); increase N or discretization.bound_points",
    "constraints": "the constraints hold only where the scheme imposes them (along the "
                   "replayed path they miss); increase N",
    "integration": "the replay did not converge (or nothing can replay this problem): "
                   "not verified",
}


def pack_function(tr: Transcription, prefix: str) -> ca.Function:
    """``{prefix}gen_pack(values) -> (p, bad)``."""
    v = ca.SX.sym("values", tr.values.size)
    p, bad = tr.values.pack_function(v)
    return ca.Function(f"{prefix}gen_pack", [v], [p, bad], ["values"], ["p", "bad"])


def solver_function(tr: Transcription, prefix: str, warm: bool = False) -> ca.Function:
    """``{prefix}gen_nlpsol(x0, p) -> (x, f, g, lam_g, lam_x)``: the Transcription's IPOPT solver
    (:meth:`Transcription.solve_graph`) with the bounds of
    :attr:`Transcription.bounds_function`, computed from p (a bound given by a parameter is a
    runtime input of the exported solver); with ``warm``, ``{prefix}gen_nlpsol_warm(x0, p, lam_g0,
    lam_x0)``, its primal-dual warm start."""
    ins = [ca.MX.sym("x0", tr.nx), ca.MX.sym("p", tr.np)]
    if warm:
        ins += [ca.MX.sym("lam_g0", tr.ng), ca.MX.sym("lam_x0", tr.nx)]
    r = tr.solve_graph(*ins)
    return ca.Function(f"{prefix}gen_nlpsol_warm" if warm else f"{prefix}gen_nlpsol", ins,
                       [r[k] for k in SOLVE_OUTPUTS], [v.name() for v in ins],
                       list(SOLVE_OUTPUTS))


def generate(tr: Transcription, ipopt: dict[str, Any] | None, prefix: str,
             prelude: str, loop: Sequence[ca.Function] = ()) -> dict[str, str]:
    """The CasADi-generated C files, each after ``prelude``, generated in a temporary folder:
    ``{prefix}generated.c/.h``, what runs at every iteration of a solve (IPOPT's solver, or
    with fatrop the Functions its driver runs instead, :mod:`~ocgroupoid.export.fatrop`) and
    the read-out, which the closed loop runs at every sample; with IPOPT
    ``{prefix}generated_warm.c/.h``, the warm-start solver (a second IPOPT instance, whose
    generated callbacks would clash with the first's in one file);
    ``{prefix}generated_once.c/.h``, what a solve runs once (the guess, the packing of a
    parameter file, the verdict's checks; with fatrop the maps to and from its stage form),
    which the Makefile compiles with less optimisation (``OPT_ONCE``); with ``loop``
    (:mod:`~ocgroupoid.export.mpc`) ``{prefix}generated_mpc.c/.h`` of its Functions. The file
    name is CasADi's prefix of its internal symbols."""
    post = post_function(tr, prefix)
    once = (guess_function(tr, prefix), pack_function(tr, prefix),
            verify_export(tr, ipopt, prefix))
    groups: list[tuple[str, Sequence[ca.Function]]]
    if tr.fatrop is None:
        groups = [(f"{prefix}generated", (solver_function(tr, prefix), post)),
                  (f"{prefix}generated_warm", (solver_function(tr, prefix, warm=True),)),
                  (f"{prefix}generated_once", once)]
    else:
        stage, maps = exported_fatrop.functions(tr, prefix)
        groups = [(f"{prefix}generated", (*stage, post)),
                  (f"{prefix}generated_once", (*maps, *once))]
    if loop:
        groups.append((f"{prefix}generated_mpc", loop))
    out = {}
    for name, fns in groups:
        cg = ca.CodeGenerator(name, {"with_header": True})
        for fn in fns:
            cg.add(fn)
        with tempfile.TemporaryDirectory(prefix="ocgroupoid-export-") as tmp:
            cg.generate(tmp + "/")
            c, h = (Path(tmp) / f"{name}.{ext}" for ext in ("c", "h"))
            out[c.name] = prelude + hpipm_iterations(
                hpipm_defaults(_empty_copies(c.read_text())), prefix)
            out[h.name] = h.read_text()
    return out


#: CasADi 3.8 writes the copy of an empty matrix (a problem without parameters, broadcast
#: over the stages) as ``casadi_copy(0, 0, 0+ i*0)``: a null destination given as an integer,
#: which C compilers warn about; the copy moves nothing
_EMPTY_COPY = re.compile(r"casadi_copy\(0, 0, 0\+ i\*0\);")


def _empty_copies(source: str) -> str:
    """Generated C without the empty copies of :data:`_EMPTY_COPY`."""
    return _EMPTY_COPY.sub("/* an empty copy */", source)


#: CasADi 3.8's generated HPIPM call writes HPIPM's options field by field into a struct
#: that was never initialised, and leaves five fields out (``dual_gap_max``, ``lam0_min``,
#: ``t0_min``, ``t0_init``, ``update_fact_exit``): measured, a QP then ran to its iteration
#: limit and reported failure. CasADi's own interface sets HPIPM's defaults of the mode first.
_HPIPM_OPTIONS = re.compile(r"^(\s*)(\w+)\.hpipm_options\.mu0 = ", re.M)
_HPIPM_MODE = re.compile(r"\.hpipm_options\.mode = (\d+);")


def hpipm_defaults(source: str) -> str:
    """Generated C whose HPIPM options start from HPIPM's defaults of their mode
    (``d_ocp_qp_ipm_arg_set_default``; :data:`_HPIPM_OPTIONS`); other code unchanged."""
    def first(m: re.Match[str]) -> str:
        mode = _HPIPM_MODE.search(source, m.end())
        if mode is None:
            raise ExportError("CasADi's generated HPIPM call sets no mode: this CasADi's "
                              "code generation is not the one the export knows (3.8)")
        return (f"{m.group(1)}d_ocp_qp_ipm_arg_set_default((enum hpipm_mode){mode.group(1)}, "
                f"&{m.group(2)}.hpipm_options);\n{m.group(0)}")
    return _HPIPM_OPTIONS.sub(first, source)


#: CasADi 3.8's generated HPIPM call reads HPIPM's iteration count into its own data, which
#: it drops on return; Python's conic reports it (``stats()["iter_count"]``)
_HPIPM_ITER = re.compile(r"^(\s*)d_ocp_qp_ipm_get_iter\(&workspace, &(\w+)->iter_count\);$",
                         re.M)


def hpipm_iterations(source: str, prefix: str) -> str:
    """Generated C whose HPIPM call hands its iteration count to the hooks
    (``{prefix}hooks_qp_iterations``: into the running record, as IPOPT's); other code
    unchanged."""
    out, n = _HPIPM_ITER.subn(lambda m: f"{m.group(0)}\n{m.group(1)}{prefix}hooks_qp_iterations("
                              f"{m.group(2)}->iter_count);", source)
    if n == 0 and "d_ocp_qp_ipm_solve(" in source:
        raise ExportError("CasADi's generated HPIPM call reads no iteration count: this "
                          "CasADi's code generation is not the one the export knows (3.8)")
    return out
