"""Exported C code: one compiled problem as a small C project that builds and runs alone.

``export_c(problem, folder)`` writes, next to a verbatim C library (``c_templates/``):

- ``ocg_generated.c/.h``: CasADi-generated C of four Functions the Python path evaluates
  too — nothing here computes anything of its own:

  ``ocg_gen_nlpsol(x0, p) -> (x, f, g, lam_g, lam_x)``  the Transcription's solver (IPOPT, or
  fatrop on the stage form: ``solver.backend``) with the bounds computed from p (its
  stage-wise derivatives come from nlpsol's cache), and ``ocg_gen_nlpsol_warm`` the same from
  a primal-dual point (IPOPT's warm start; fatrop's primal);
  ``ocg_gen_guess(p) -> x0``  the first geodesic guess (:attr:`Transcription.guess_function`)
  through :attr:`Transcription.point_function`;
  ``ocg_gen_pack(values) -> (p, bad)``  :attr:`ParameterValues.pack_function`, the packing of
  the numbers of a parameter file into p;
  ``ocg_gen_post(x, p, lam_g) -> (...)``  :attr:`Transcription.readout_function`, the read-out
  a Solution is made of;
  ``ocg_gen_verify(x, p, lam_g) -> (ratios, figures)``  the verdict's checks
  (:mod:`~ocgroupoid.solve.verify_graph`: residuals, the plan replayed through the continuous
  problem — landing, bounds along it), so that the C solver's ``success`` means what
  Python's means, IPOPT's status kept apart.

- ``ocg_model.h/.c``: the dimensions and the tables the JSON writer and the parameter-file
  reader need (the ranges of the keys generated from :mod:`~ocgroupoid.model.ranges`, which
  the problem files are checked against too); ``params.txt``: the exported instance;
  ``Makefile`` and ``README.md``.

One export serves every instance of the model: boundary values, physical parameters and T
are inputs. Multi-start, continuation and the model's own guess hooks stay in Python: the
C solver starts from the geodesic guess, from a point the caller gives, or from an earlier
result's primal-dual point (``ocg_solve_warm``).
"""

from __future__ import annotations

import hashlib
import json
import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Collection, Sequence

import casadi as ca
import numpy as np

from .._version import __version__
from ..errors import ConfigError, ExportError
from ..model.problem import Problem
from ..model.ranges import (
    FILE_BYTES,
    POSITIVE,
    SIGNED,
    TIME,
    Range,
    block_range,
    positive_parameters,  # noqa: F401  (re-exported: the export API names it)
)
from ..nlp.parameters import ParameterValues
from ..nlp.schemes import DEFAULT_RULE, DEFAULT_SCHEME
from ..nlp.transcription import C_READOUT_OUTPUTS, DEFAULT_BACKEND, MAX_SECONDS, Transcription
from ..solve.diagnostics import replay_of
from ..solve.outputs import check_folder, write_atomic
from ..solve.solver import Solver
from ..solve.verdict import REPLAY_TOLERANCE, check_tolerance
from ..solve.verify_graph import CHECKS, FIGURES, verify_function

TEMPLATES = Path(__file__).resolve().parent / "c_templates"
VERBATIM = ("ocg_solver.h", "ocg_solver.c", "ocg_ipopt_hooks.h", "ocg_fatrop_hooks.h", "main.c",
            "ocg_params.h", "ocg_params.c")
GENERATED = "ocg_generated"
# Prepended to the CasADi-generated file: CasADi's uniform calling convention leaves
# arguments (mem, iw, w) unused, and the two IPOPT calls are routed through ocg_solver.c.
GENERATED_PRELUDE = """\
/* ocgroupoid: CasADi passes every generated function the same arguments (mem, iw, w), and
 * many functions ignore some of them; that one warning is off in this file only. */
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif
/* The solver's return status and iteration count, which the generated solver keeps to
 * itself, are recorded by the wrappers of ocg_ipopt_hooks.h (and ocg_fatrop_hooks.h). */
#define OCG_ROUTE_IPOPT
#include "ocg_ipopt_hooks.h"
"""
FATROP_PRELUDE = """\
#define OCG_ROUTE_FATROP
#include "ocg_fatrop_hooks.h"
"""
#: outputs of the generated solvers (ocg_gen_nlpsol, ocg_gen_nlpsol_warm)
SOLVE_OUTPUTS = ("x", "f", "g", "lam_g", "lam_x")
#: the libraries each backend links with (all in the casadi wheel)
BACKEND_LIBS = {"ipopt": "-lipopt", "fatrop": "-lipopt -lfatrop -lblasfeo"}
EXPORT_IPOPT = {"print_level": 0, "sb": "yes"}  # stdout carries the JSON, nothing else
# What export_c wrote (file -> sha256): a folder holding it is one export_c may overwrite.
MANIFEST = ".ocgroupoid-export.json"


# ----------------------------------------------------------------- parameter files


def params_text(values: ParameterValues, numbers: np.ndarray, header: str = "") -> str:
    """A parameter file: one ``KEY v1 v2 ...`` line per value block, with its meaning."""
    lines = [f"# {line}".rstrip() for line in header.splitlines()]
    for b in values.blocks:
        nums = " ".join(f"{x:.17g}" for x in numbers[b.values])
        lines.append(f"{b.key} {nums}  # {_one_line(b.meaning)}"
                     + (f" ({b.note})" if b.note else ""))
    return "\n".join(lines) + "\n"


def write_params(path: str | Path, tr: Transcription, p: np.ndarray, header: str = "") -> Path:
    """Write the parameter file of the instance p (for ``DIR/solve PATH``)."""
    path = Path(path)
    write_atomic(path, params_text(tr.values, tr.values.values_of(p), header))
    return path


# ----------------------------------------------------------------- the Functions


def guess_function(tr: Transcription) -> ca.Function:
    """``ocg_gen_guess(p) -> x0``: the point of the first geodesic guess."""
    p = ca.MX.sym("p", tr.np)
    first = tr.guess_function(p)
    first = first[0] if isinstance(first, (list, tuple)) else first
    return ca.Function("ocg_gen_guess", [p], [tr.point_function(first, p)], ["p"], ["x0"])


def post_function(tr: Transcription) -> ca.Function:
    """``ocg_gen_post(x, p, lam_g)``: the read-out outputs exported C reads (enum ocg_output)."""
    x, p, lam = ca.MX.sym("x", tr.nx), ca.MX.sym("p", tr.np), ca.MX.sym("lam_g", tr.ng)
    outs = tr.readout_function(x, p, lam)
    return ca.Function("ocg_gen_post", [x, p, lam], list(outs)[:len(C_READOUT_OUTPUTS)],
                       ["x", "p", "lam_g"], list(C_READOUT_OUTPUTS))


#: RK4 substeps per piece of the exported replay (its own error is checked against half as
#: many: a replay that has not converged fails the verdict)
EXPORT_SUBSTEPS = 32


def verify_export(tr: Transcription, ipopt: dict[str, Any] | None) -> ca.Function:
    """``ocg_gen_verify(x, p, lam_g) -> (ratios, figures)``."""
    fn = verify_function(tr, replay_of(tr), EXPORT_SUBSTEPS, check_tolerance(ipopt),
                         REPLAY_TOLERANCE)
    x, p, lam = ca.MX.sym("x", tr.nx), ca.MX.sym("p", tr.np), ca.MX.sym("lam_g", tr.ng)
    return ca.Function("ocg_gen_verify", [x, p, lam], fn(x, p, lam),  # type: ignore[call-overload]
                       ["x", "p", "lam_g"], ["ratios", "figures"])  # (stubs: one MX, not two)


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


def pack_function(tr: Transcription) -> ca.Function:
    """``ocg_gen_pack(values) -> (p, bad)``."""
    v = ca.SX.sym("values", tr.values.size)
    p, bad = tr.values.pack_function(v)
    return ca.Function("ocg_gen_pack", [v], [p, bad], ["values"], ["p", "bad"])


def solver_function(tr: Transcription, warm: bool = False) -> ca.Function:
    """``ocg_gen_nlpsol(x0, p) -> (x, f, g, lam_g, lam_x)``: the Transcription's solver
    (:meth:`Transcription.solve_graph`) with the bounds of
    :attr:`Transcription.bounds_function`, computed from p (a bound given by a parameter is a
    runtime input of the exported solver); with ``warm``, ``ocg_gen_nlpsol_warm(x0, p, lam_g0,
    lam_x0)``, its primal-dual warm start (fatrop: the primal point)."""
    ins = [ca.MX.sym("x0", tr.nx), ca.MX.sym("p", tr.np)]
    if warm:
        ins += [ca.MX.sym("lam_g0", tr.ng), ca.MX.sym("lam_x0", tr.nx)]
    r = tr.solve_graph(*ins)
    return ca.Function("ocg_gen_nlpsol_warm" if warm else "ocg_gen_nlpsol", ins,
                       [r[k] for k in SOLVE_OUTPUTS], [v.name() for v in ins],
                       list(SOLVE_OUTPUTS))


# ------------------------------------------------------------------ the C project


@dataclass(frozen=True)
class Export:
    """What ``export_c`` wrote, and the compiled Solver it was exported from."""

    folder: Path
    problem: str
    N: int
    n_x: int  # NLP variables (length of a warm start)
    n_p: int  # runtime parameters p
    n_g: int  # constraints
    n_values: int  # numbers of a parameter file
    binary: Path | None  # DIR/solve when built
    solver: Solver


def casadi_dir() -> Path:
    """The folder of the casadi package: libipopt.so and include/coin-or live there."""
    return Path(ca.__file__).resolve().parent


def _ipopt_paths(lib: str | Path | None, include: str | Path | None) -> tuple[Path, Path]:
    lib = Path(lib) if lib is not None else casadi_dir()
    include = Path(include) if include is not None else casadi_dir() / "include"
    if not any(lib.glob("libipopt.so*")) and not any(lib.glob("libipopt*.dylib")):
        raise ExportError(f"no libipopt in {lib}; pass ipopt_lib= (or IPOPT_LIB=... to make) "
                          "with the folder that holds libipopt.so")
    if not (include / "coin-or" / "IpStdCInterface.h").is_file():
        raise ExportError(f"no coin-or/IpStdCInterface.h under {include}; pass ipopt_include= "
                          "(or IPOPT_INCLUDE=... to make) with IPOPT's include folder")
    return lib, include


def _c_string(s: str) -> str:
    """A C string literal of any text: printable ASCII as is (``?`` escaped: no trigraphs),
    every other byte of its UTF-8 as a three-digit octal escape."""
    out = []
    for byte in s.encode("utf-8", "surrogatepass"):
        c = chr(byte)
        if c in '"\\?':
            out.append("\\" + c)
        elif 32 <= byte < 127:
            out.append(c)
        else:
            out.append(f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def _one_line(text: str) -> str:
    """Text on one line (line breaks and other control characters as spaces)."""
    return " ".join("".join(c if c.isprintable() else " " for c in text).split())


def plain_name(name: str) -> str:
    """A problem name as comments and the Makefile show it: letters, digits and ``_-.+,=:()``
    and spaces, anything else as ``_`` (no line break, ``*/``, backslash or ``$``)."""
    return re.sub(r"[^A-Za-z0-9 _\-.+,=:()]", "_", _one_line(name)) or "_"


def _make_value(path: Path) -> str:
    """A path as the value of a Makefile variable (``$`` and ``#`` escaped)."""
    text = str(path)
    if any(not c.isprintable() for c in text):
        raise ExportError(f"{text!r}: a folder with a line break or control character cannot "
                          "go into a Makefile; move IPOPT to a plain path")
    return text.replace("$", "$$").replace("#", "\\#")


def _c_doubles(values: np.ndarray) -> str:
    if not len(values):
        return "{0.0}"
    return "{" + ", ".join(f"{float(v):.17g}" for v in values) + "}"


def _c_double(x: float) -> str:
    """A double as a C literal that reads back exactly (Python's repr: ``1e-12``, ``600.0``)."""
    return repr(float(x))


def _c_range(r: Range) -> str:
    """One row of ``ocg_ranges``: the range of a key (:mod:`~ocgroupoid.model.ranges`)."""
    return f"  {{{r.kind}, {_c_double(r.lo)}, {_c_double(r.hi)}, {_c_double(r.ratio)}}}"


def _fields(rows: list[tuple[str, int, int, int]]) -> str:
    body = ",\n".join(f"  {{{_c_string(n)}, {o}, {r}, {c}}}" for n, o, r, c in rows)
    return "{\n" + (body or "  {0, 0, 0, 0}") + "\n}"


def _names(names: Sequence[str]) -> str:
    return "{" + (", ".join(_c_string(n) for n in names) or "0") + "}"


def static_labels(pb: Problem) -> dict[str, Any]:
    """``Problem.labels`` as the exported solver writes them whatever its parameters: a side
    of a bound that depends on the parameters (they change at run time) only by its affine
    form in them, which a reader evaluates at the solution's parameters; a bound that depends
    on them otherwise is left out."""
    labels = pb.labels()
    kept = []
    for b in labels["bounds"]:
        for key in ("lower", "upper"):
            if f"{key}_affine" in b:
                b[key] = None
        if all(b.get(f"{k}_affine", True) is not None for k in ("lower", "upper")):
            kept.append(b)
    labels["bounds"] = kept
    return labels


def model_sources(tr: Transcription, default_p: np.ndarray, guess: str,
                  positive: Collection[str] = ()) -> tuple[str, str]:
    """ocg_model.h and ocg_model.c: dimensions, parameter-file keys (with the physical
    parameters in ``positive`` flagged: their numbers must be > 0), JSON field tables."""
    pb, G, values = tr.problem, tr.problem.groupoid, tr.values
    state_fields, k = [], 0
    for f in G.factors:  # a shown state is a vector (rows 0) or a matrix, row-major
        shape = f.shown_shape
        rows, cols = (0, shape[0]) if len(shape) == 1 else shape
        state_fields.append((f.state, k, rows, cols))
        k += int(np.prod(shape))
    velocity_fields = [(f.velocity, vs.start, 0, vs.stop - vs.start)
                       for f, vs in zip(G.factors, G.velocity_layout.slices)]
    P0 = tr.layout.p_slices["P"].start
    param_fields = [(name, P0 + sl.start, 0, sl.stop - sl.start)
                    for name, sl in pb.parameter_slices.items()]
    controls = [n for n, _ in pb.controls]
    multipliers = [n for n, c in pb.constraints for _ in range(c.numel())]
    unknown = set(positive) - set(pb.params)
    if unknown:
        raise ConfigError(f"positive={sorted(unknown)}: not parameters of {pb.name!r}; "
                          f"its parameters are {list(pb.params)}")
    flagged = [b.kind == "vector" and b.key in positive and b.key in pb.params
               for b in values.blocks]
    blocks = ",\n".join(
        f"  {{{_c_string(b.key)}, {b.values.start}, {b.size}, {_c_string(b.meaning)}, "
        f"{int(on)}}}" for b, on in zip(values.blocks, flagged))
    ranges = ",\n".join(_c_range(block_range(b.key, b.kind, on))
                         for b, on in zip(values.blocks, flagged))
    defines = {
        "OCG_PROBLEM": _c_string(pb.name), "OCG_N": tr.N, "OCG_ORDER": pb.order,
        "OCG_NX": tr.nx, "OCG_NP": tr.np, "OCG_NG": tr.ng, "OCG_NV": values.size,
        "OCG_P_T": tr.layout.p_slices["T"].start, "OCG_N_BLOCKS": len(values.blocks),
        "OCG_N_STATE_FIELDS": len(state_fields), "OCG_N_VELOCITY_FIELDS": len(velocity_fields),
        "OCG_N_PARAMETER_FIELDS": len(param_fields), "OCG_NU": len(controls),
        "OCG_N_MULTIPLIER_NAMES": len(multipliers), "OCG_N_POST": len(C_READOUT_OUTPUTS),
        "OCG_SCHEME": _c_string(tr.disc.scheme),
        "OCG_BACKEND_FATROP": int(tr.fatrop is not None), "OCG_BACKEND": _c_string(tr.backend),
        "OCG_MAX_ITER": tr.fatrop.max_iter if tr.fatrop is not None else 0,
        "OCG_RETRACTION": _c_string(tr.scheme.retraction), "OCG_RULE": _c_string(tr.disc.rule),
        "OCG_GUESS_LABEL": _c_string(guess),
        "OCG_MANIFOLDS_JSON": _c_string(json.dumps({f.state: f.manifold for f in G.factors})),
        "OCG_LABELS_JSON": _c_string(json.dumps(static_labels(pb))),
        "OCG_N_CHECKS": len(CHECKS), "OCG_N_FIGURES": len(FIGURES),
        "OCG_CHECK_NAMES": _names(CHECKS), "OCG_FIGURE_NAMES": _names(FIGURES),
        "OCG_CHECK_FAILURES": _names([CHECK_FAILURES[c] for c in CHECKS]),
        "OCG_PARAMS_MAX_BYTES": FILE_BYTES,
        "OCG_RANGE_SIGNED": SIGNED, "OCG_RANGE_POSITIVE": POSITIVE, "OCG_RANGE_TIME": TIME,
    }
    header = "\n".join([
        f"/* Generated by ocgroupoid {__version__} for {plain_name(pb.name)}: the exported "
        "instance's "
        "dimensions and tables. */",
        "#ifndef OCG_MODEL_H", "#define OCG_MODEL_H", "",
        *[f"#define {k} {v}" for k, v in defines.items()], "",
        "/* The wall time of one run of ./solve (solver.max_seconds): past it, it stops with a "
        "message. */",
        "#ifndef OCG_MAX_SECONDS",
        f"#define OCG_MAX_SECONDS {_c_double(tr.max_seconds)}",
        "#endif", "",
        "/* A key of a parameter file: numbers values[offset .. offset+size); positive: each "
        "must be > 0. */",
        "typedef struct { const char *key; int offset; int size; const char *meaning; "
        "int positive; } ocg_block;",
        "/* The range of a key's numbers (ocgroupoid.model.ranges): kind OCG_RANGE_*, each in "
        "[lo, hi], and at most ratio apart (0: no limit). */",
        "typedef struct { int kind; double lo; double hi; double ratio; } ocg_range;",
        "/* A named slice of an output row: offset, and rows x cols (rows 0: a vector). */",
        "typedef struct { const char *name; int offset; int rows; int cols; } ocg_field;", "",
        "extern const ocg_block ocg_blocks[];",
        "extern const ocg_range ocg_ranges[];",
        "extern const double ocg_default_values[];",
        "extern const ocg_field ocg_state_fields[];",
        "extern const ocg_field ocg_velocity_fields[];",
        "extern const ocg_field ocg_parameter_fields[];",
        "extern const char *const ocg_control_names[];",
        "extern const char *const ocg_multiplier_names[];", "",
        "#endif", ""])
    source = "\n".join([
        f"/* Generated by ocgroupoid {__version__} for {plain_name(pb.name)}. */",
        '#include <stddef.h>', '#include "ocg_model.h"', "",
        f"const ocg_block ocg_blocks[] = {{\n{blocks}\n}};",
        f"const ocg_range ocg_ranges[] = {{\n{ranges}\n}};",
        f"const double ocg_default_values[] = {_c_doubles(values.values_of(default_p))};",
        f"const ocg_field ocg_state_fields[] = {_fields(state_fields)};",
        f"const ocg_field ocg_velocity_fields[] = {_fields(velocity_fields)};",
        f"const ocg_field ocg_parameter_fields[] = {_fields(param_fields)};",
        f"const char *const ocg_control_names[] = {_names(controls)};",
        f"const char *const ocg_multiplier_names[] = {_names(multipliers)};", ""])
    return header, source


def _fill(template: str, values: dict[str, Any]) -> str:
    """``@KEY@`` replaced by its value, in one pass (a value holding ``@X@`` stays as is)."""
    left = set(re.findall(r"@([A-Z_]+)@", template)) - set(values)
    if left:
        raise ExportError(f"template placeholders without a value: {sorted(left)}")
    return re.sub(r"@([A-Z_]+)@", lambda m: str(values[m.group(1)]), template)


def _blocks_table(values: ParameterValues) -> str:
    rows = ["| key | numbers | meaning |", "|---|---|---|"]
    for b in values.blocks:
        rows.append(f"| `{b.key}` | {b.size} | {_one_line(b.meaning)}"
                    + (f" ({b.note})" if b.note else "") + " |")
    return "\n".join(rows)


def _generate(tr: Transcription, ipopt: dict[str, Any] | None = None) -> dict[str, str]:
    """The CasADi-generated ``ocg_generated.c`` (with :data:`GENERATED_PRELUDE`) and ``.h``,
    and ``ocg_generated_warm.c/.h`` (the warm-start solver: a second IPOPT instance, whose
    generated callbacks would clash with the first's in one file), generated in a temporary
    folder."""
    prelude = GENERATED_PRELUDE + (FATROP_PRELUDE if tr.fatrop is not None else "")
    out = {}
    for name, fns in ((GENERATED, (solver_function(tr), guess_function(tr), pack_function(tr),
                                   post_function(tr), verify_export(tr, ipopt))),
                      (f"{GENERATED}_warm", (solver_function(tr, warm=True),))):
        cg = ca.CodeGenerator(name, {"with_header": True})
        for fn in fns:
            cg.add(fn)
        with tempfile.TemporaryDirectory(prefix="ocgroupoid-export-") as tmp:
            cg.generate(tmp + "/")
            c, h = (Path(tmp) / f"{name}.{ext}" for ext in ("c", "h"))
            out[c.name], out[h.name] = prelude + "\n" + _empty_copies(c.read_text()), \
                h.read_text()
    return out


#: CasADi 3.8 writes the copy of an empty matrix (a problem without parameters, broadcast
#: over the stages) as ``casadi_copy(0, 0, 0+ i*0)``: a null destination given as an integer,
#: which C compilers warn about; the copy moves nothing
_EMPTY_COPY = re.compile(r"casadi_copy\(0, 0, 0\+ i\*0\);")


def _empty_copies(source: str) -> str:
    """Generated C without the empty copies of :data:`_EMPTY_COPY`."""
    return _EMPTY_COPY.sub("/* an empty copy */", source)


def _digest(data: str | bytes) -> str:
    return hashlib.sha256(data.encode() if isinstance(data, str) else data).hexdigest()


def _manifest(folder: Path) -> dict[str, list[str]] | None:
    """What an earlier export wrote in ``folder`` (file -> accepted digests), or None."""
    try:
        files = json.loads((folder / MANIFEST).read_text())["files"]
        return {str(k): [str(d) for d in v] for k, v in files.items()}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


def claim_folder(folder: str | Path, force: bool = False, what: str = "export folder") -> Path:
    """Check, before anything is compiled, that ``folder`` may receive an export: it is new,
    empty, or an earlier export whose files are unchanged (``MANIFEST`` records them).
    Anything else (a README.md, Makefile, main.c... that export_c did not write, or one that
    was edited since) is an ExportError unless ``force``. Returns the folder as a Path."""
    folder = check_folder(folder, what)
    if force or not folder.is_dir():
        return folder
    present = sorted(p.name for p in folder.iterdir() if p.name != MANIFEST)
    if not present and not (folder / MANIFEST).exists():
        return folder
    known = _manifest(folder)
    if known is None:
        shown = ", ".join(present[:5]) + (", ..." if len(present) > 5 else "")
        raise ExportError(f"{what} {folder}: is not empty ({shown}) and was not written by "
                          "export-c; export into a new or empty folder, or pass --force "
                          "(force=True) to overwrite its files")
    for name in present:
        path = folder / name
        if name not in known:
            continue  # the user's own files and the build's products are left alone
        if not path.is_file() or _digest(path.read_bytes()) not in known[name]:
            raise ExportError(f"{what} {folder}: {name} was changed since export-c wrote it; "
                              "move your edits "
                              "elsewhere (e.g. copy params.txt), or pass --force (force=True) "
                              "to overwrite it")
    return folder


def _write_all(folder: Path, files: dict[str, str | bytes]) -> None:
    """Write every file atomically; the manifest first accepts the old and the new contents
    (an interrupted export can be redone), then only the new ones."""
    old = _manifest(folder) or {}
    new = {name: [_digest(data)] for name, data in files.items()}
    both = {name: sorted(set(old.get(name, [])) | set(new.get(name, [])))
            for name in set(old) | set(new)}

    def record(entries: dict[str, list[str]]) -> None:
        write_atomic(folder / MANIFEST, json.dumps(
            {"ocgroupoid": __version__, "files": dict(sorted(entries.items()))}, indent=1) + "\n")

    record(both)
    for name, data in files.items():
        write_atomic(folder / name, data)
    record({**{k: v for k, v in old.items() if k not in new}, **new})


def export_c(problem: Problem | Solver, folder: str | Path, N: int = 64,
             retraction: str = "cayley", rule: str = DEFAULT_RULE,
             ipopt: dict[str, Any] | None = None, build: bool = False,
             ipopt_lib: str | Path | None = None, ipopt_include: str | Path | None = None,
             cflags: str = "", scheme: str = DEFAULT_SCHEME, steps: str = "uniform",
             force: bool = False, positive: Collection[str] = (),
             backend: str = DEFAULT_BACKEND, max_seconds: float = MAX_SECONDS) -> Export:
    """Write ``problem`` compiled on N intervals as a C project in ``folder``.

    ``problem`` may also be a compiled :class:`Solver` (its N, scheme, retraction, rule and
    IPOPT options are kept). IPOPT's own printing is switched off (``print_level 0``) in a
    problem compiled here: the driver's stdout carries the solution JSON only.
    ``ipopt_lib``/``ipopt_include`` default to the libipopt and headers inside the casadi
    wheel; the Makefile records them (overridable: ``make IPOPT_LIB=... IPOPT_INCLUDE=...``)
    and links with an rpath. ``build=True`` runs ``make`` (with ``cflags``) and checks that
    ``folder/solve`` exists. Bounds that are parameter expressions are runtime inputs; adaptive
    steps are not exported (they need a second solve).

    ``folder`` must be new, empty or an unchanged earlier export (:func:`claim_folder`;
    ``force=True`` overwrites whatever is there); every file is written atomically.
    ``positive`` names physical parameters whose numbers must be > 0 in a parameter file (the
    driver refuses others with the message the problem files give;
    :func:`positive_parameters` reads them off a model's schema). ``max_seconds``: the wall
    time of one run of ``./solve`` (IPOPT's ``max_wall_time``; the driver stops anything that
    runs longer, e.g. fatrop).
    """
    if steps == "adaptive" or (isinstance(problem, Solver) and problem.disc.steps == "adaptive"):
        raise ConfigError("adaptive steps come from a second, phased solve placed on the "
                          "switches of a first one, which the exported solver does not run; "
                          "export with uniform steps (--set discretization.steps=uniform)")
    if not isinstance(problem, (Solver, Problem)):
        raise ConfigError(f"export_c takes a Problem or a compiled Solver, got "
                          f"{type(problem).__name__}")
    folder = claim_folder(folder, force)
    lib, include = _ipopt_paths(ipopt_lib, ipopt_include)
    if isinstance(problem, Solver):
        solver = problem
    else:
        solver = Solver(problem, N, retraction, rule, {**(ipopt or {}), **EXPORT_IPOPT}, scheme,
                        steps, backend=backend, max_seconds=max_seconds)
    tr = solver.transcription
    p = tr.pack()
    files: dict[str, str | bytes] = dict(_generate(tr, solver.ipopt))
    guess = tr.guess_labels[0]  # what the C solver starts from
    files["ocg_model.h"], files["ocg_model.c"] = model_sources(tr, p, guess, positive)
    for name in VERBATIM:
        files[name] = (TEMPLATES / name).read_bytes()
    pb = tr.problem
    info = {"PROBLEM": plain_name(pb.name), "N": tr.N, "RETRACTION": tr.disc.retraction,
            "RULE": tr.disc.rule, "ORDER": pb.order, "NX": tr.nx, "NP": tr.np, "NG": tr.ng,
            "NV": tr.values.size, "VERSION": __version__, "CASADI": ca.__version__,  # type: ignore[attr-defined]  # not in its stubs
            "IPOPT_LIB": lib, "IPOPT_INCLUDE": include, "GUESS": _one_line(guess),
            "BACKEND": tr.backend, "BACKEND_LIBS": BACKEND_LIBS[tr.backend],
            "KEYS": _blocks_table(tr.values)}
    files["Makefile"] = _fill((TEMPLATES / "Makefile.in").read_text(), {
        **info, "IPOPT_LIB": _make_value(lib), "IPOPT_INCLUDE": _make_value(include)})
    files["README.md"] = _fill((TEMPLATES / "README.md.in").read_text(), info)
    files["params.txt"] = params_text(tr.values, tr.values.values_of(p), (
        f"{plain_name(pb.name)}: the exported instance (N={tr.N}, {tr.disc.retraction}). "
        "Edit values, drop keys to keep their defaults,\nthen run ./solve params.txt. "
        "Format: README.md."))
    folder.mkdir(parents=True, exist_ok=True)
    _write_all(folder, files)
    binary = make(folder, cflags) if build else None
    return Export(folder, pb.name, tr.N, tr.nx, tr.np, tr.ng, tr.values.size, binary, solver)


def make(folder: str | Path, cflags: str = "", target: str = "solve",
         timeout: float = 600.0) -> Path:
    """Run ``make -C folder target`` with extra ``CFLAGS``; the path of the built target
    (``solve``, or a program ``target`` built from ``folder/target.c`` and libocg.a)."""
    folder = Path(folder)
    tool = shutil.which("make")
    if tool is None:
        raise ExportError("`make` was not found on PATH; install make and a C compiler "
                          "(e.g. apt-get install build-essential) or build by hand (README)")
    cmd = [tool, "-C", str(folder), target] + ([f"CFLAGS={cflags}"] if cflags else [])
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    if r.returncode != 0:
        tail = "\n".join((r.stdout + r.stderr).strip().splitlines()[-20:])
        raise ExportError(f"building {folder / target} failed (make exit {r.returncode}):\n"
                          f"{tail}\nCheck that a C compiler is installed and that IPOPT_LIB/"
                          "IPOPT_INCLUDE in the Makefile point at libipopt and its headers.")
    return folder / target
