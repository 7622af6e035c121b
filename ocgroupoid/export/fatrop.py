"""The exported solver with ``solver.backend: fatrop``: the driver the Python API runs.

The export used to run CasADi's fatrop ``nlpsol``, generated as C: its build derives the
stage blocks by assigning them one at a time into a sparse matrix, in time N², and the export
built it twice (the solver and its warm twin). So3 at N = 1024 exported in 7.1 s against
IPOPT's 2.7 s, at N = 2048 in 18.5 s, and its C (5 MB at N = 256, twice IPOPT's) took 28 s to
compile against IPOPT's 15 s (measured 2026-12-04). The export now writes the driver of
:mod:`~ocgroupoid.nlp.backends.fatrop_ocp` (``fatrop_ocp.c``, fatrop's own C interface) with
its maps as tables, linear in N, and CasADi's code generator writes only the stage form's five
Functions and the two maps in and out of it (:attr:`FatropBackend.exported
<ocgroupoid.nlp.backends.fatrop.FatropBackend.exported>`): the same solve as the Python API's,
callback for callback.

The files: ``{prefix}fatrop_solver.c/.h`` (``{prefix}gen_nlpsol`` and
``{prefix}gen_nlpsol_warm`` in the calling convention of CasADi's generated functions, and
the driver's tables), ``{prefix}fatrop_ocp.c/.h`` (the driver, its names prefixed) and
``{prefix}fatrop_guard.c/.h`` (the guard's interface; the exported solve is unguarded:
``main.c``'s alarm ends a run past ``max_seconds``).
"""

from __future__ import annotations

import math
import re
from typing import Any

import casadi as ca
import numpy as np

from ..errors import ExportError
from ..nlp.backends import fatrop_ocp
from ..nlp.backends.fatrop import Exported
from ..nlp.jit import NLP_FUNCTIONS
from ..nlp.transcription import Transcription
from .literals import c_double, c_ints, c_items, c_string

#: the exported files rendered from c_templates/NAME.in, named with the prefix
TEMPLATES = ("fatrop_solver.c", "fatrop_solver.h", "fatrop_guard.c")
#: the driver's files, copied from the package with their names prefixed
DRIVER = (fatrop_ocp.SOURCE, fatrop_ocp.HEADER, fatrop_ocp.GUARD[1])
#: the objects the exported library adds (``{prefix}`` prefixed)
OBJECTS = ("fatrop_solver.o", "fatrop_ocp.o", "fatrop_guard.o")
HEADERS = ("fatrop_solver.h", "fatrop_ocp.h", "fatrop_guard.h")


def exported(tr: Transcription) -> Exported:
    """fatrop as the exported solver runs it (``solver.backend: fatrop``)."""
    assert tr.fatrop is not None, "the export chose fatrop's solver for an IPOPT problem"
    return tr.fatrop.exported


def functions(tr: Transcription, prefix: str
              ) -> tuple[tuple[ca.Function, ...], tuple[ca.Function, ...]]:
    """The Functions CasADi generates for the exported fatrop solver: the stage form's five
    (``{prefix}fatrop_nlp_f`` ...), which fatrop evaluates at every iteration, and the two
    maps a solve runs once, ``{prefix}fatrop_in`` and ``{prefix}fatrop_out``."""
    e = exported(tr)

    def named(name: str, fn: ca.Function) -> ca.Function:
        ins = fn.mx_in()
        return ca.Function(f"{prefix}{name}", ins, fn.call(ins), fn.name_in(), fn.name_out())

    return (tuple(named(f"fatrop_{name}", e.functions[name]) for name in NLP_FUNCTIONS),
            (named("fatrop_in", e.arguments), named("fatrop_out", e.unscaled)))


def values(tr: Transcription) -> dict[str, Any]:
    """What fatrop_solver.c.in is filled with (``FATROP_*``): the stage form's sizes, the
    driver's maps (:func:`~ocgroupoid.nlp.backends.fatrop_ocp.block_maps`) and fatrop's
    options."""
    e = exported(tr)
    sf, maps = e.form, e.maps
    kinds = [e.kinds[name] for name in e.options]
    for name, value in e.options.items():
        if not isinstance(value, str) and not math.isfinite(float(value)):
            raise ExportError(f"fatrop's option {name} = {value!r}: the exported solver takes "
                              "finite numbers only; set a finite one in solver.fatrop")
    strings = [str(v) if kind == fatrop_ocp.STRING else "" for v, kind in
               zip(e.options.values(), kinds)]
    numbers = [0.0 if kind == fatrop_ocp.STRING else float(v) for v, kind in
               zip(e.options.values(), kinds)]
    arrays = {"NX": sf.nx, "NU": sf.nu, "NG": sf.ng, "COL": maps.col, "ROW_AB": maps.row_ab,
              "ROW_CD": maps.row_cd, "AB_OFF": maps.ab_off, "CD_OFF": maps.cd_off,
              "RSQ_OFF": maps.rsq_off, "A_KIND": maps.a_kind, "A_INDEX": maps.a_index,
              "H_INDEX": maps.h_index, "OPTION_KINDS": kinds}
    out: dict[str, Any] = {name: c_ints(np.asarray(a)) for name, a in arrays.items()}
    out.update({
        "K": sf.K, "NZ": sf.nz, "NR": sf.order.size, "NQ": e.arguments.nnz_out(1),
        "NNZ_A": maps.a_kind.size, "NNZ_H": maps.h_index.size, "N_AB": int(maps.ab_off[-1]),
        "N_CD": int(maps.cd_off[-1]), "N_RSQ": int(maps.rsq_off[-1]),
        "N_OPTIONS": len(e.options), "OPTION_NAMES": c_items(map(c_string, e.options)),
        "OPTION_VALUES": c_items(map(c_double, numbers)),
        "OPTION_STRINGS": c_items(map(c_string, strings))})
    return {f"FATROP_{name}": value for name, value in out.items()}


def driver(prefix: str) -> dict[str, str]:
    """The driver's files as the export names them: ``ocg_`` and ``OCG_`` replaced by the
    prefix (upper case for macros) in every name, file names included."""
    upper = prefix.upper()
    out = {}
    for path in DRIVER:
        text = re.sub(r'#include "(fatrop_\w+\.h)"', rf'#include "{prefix}\1"', path.read_text())
        text = re.sub(r"\bOCG_", upper, re.sub(r"\bocg_", prefix, text))
        out[prefix + path.name] = text
    return out
