"""Exported C code: one compiled problem as a small C project that builds and runs alone.

``export_c(problem, folder)`` writes, next to a verbatim C library (``c_templates/``):

- ``ocg_generated.c/.h``: CasADi-generated C of four Functions the Python path evaluates
  too — nothing here computes anything of its own:

  ``ocg_gen_nlpsol(x0, p) -> (x, f, g, lam_g)``  the Transcription's IPOPT instance, called
  with ``lbg = ubg = 0`` (its stage-wise derivatives come from nlpsol's cache);
  ``ocg_gen_guess(p) -> x0``  the first geodesic guess (:attr:`Transcription.guess_function`)
  through :attr:`Transcription.point_function`;
  ``ocg_gen_pack(values) -> (p, bad)``  :attr:`ParameterValues.pack_function`, the packing of
  the numbers of a parameter file into p;
  ``ocg_gen_post(x, p, lam_g) -> (...)``  :attr:`Transcription.readout_function`, the read-out
  a Solution is made of.

- ``ocg_model.h/.c``: the dimensions and the tables the JSON writer and the parameter-file
  reader need; ``params.txt``: the exported instance; ``Makefile`` and ``README.md``.

One export serves every instance of the model: boundary values, physical parameters and T
are inputs. Multi-start, continuation and the model's own guess hooks stay in Python: the
C solver starts from the geodesic guess, or from a warm start the caller gives.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import casadi as ca
import numpy as np

from .._version import __version__
from ..errors import ConfigError, ExportError
from ..model.problem import Problem
from ..nlp.parameters import ParameterValues
from ..nlp.schemes import DEFAULT_RULE, DEFAULT_SCHEME
from ..nlp.transcription import C_READOUT_OUTPUTS, Transcription
from ..solve.solver import Solver

TEMPLATES = Path(__file__).resolve().parent / "c_templates"
VERBATIM = ("ocg_solver.h", "ocg_solver.c", "ocg_ipopt_hooks.h", "main.c")
GENERATED = "ocg_generated"
# Prepended to the CasADi-generated file: CasADi's uniform calling convention leaves
# arguments (mem, iw, w) unused, and the two IPOPT calls are routed through ocg_solver.c.
GENERATED_PRELUDE = """\
/* ocgroupoid: CasADi passes every generated function the same arguments (mem, iw, w), and
 * many functions ignore some of them; that one warning is off in this file only. */
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif
/* IPOPT's return status and iteration count, which the generated solver keeps to itself,
 * are recorded by the wrappers of ocg_ipopt_hooks.h. */
#define OCG_ROUTE_IPOPT
#include "ocg_ipopt_hooks.h"

"""
EXPORT_IPOPT = {"print_level": 0, "sb": "yes"}  # stdout carries the JSON, nothing else


# ----------------------------------------------------------------- parameter files


def params_text(values: ParameterValues, numbers: np.ndarray, header: str = "") -> str:
    """A parameter file: one ``KEY v1 v2 ...`` line per value block, with its meaning."""
    lines = [f"# {line}".rstrip() for line in header.splitlines()]
    for b in values.blocks:
        nums = " ".join(f"{x:.17g}" for x in numbers[b.values])
        lines.append(f"{b.key} {nums}  # {b.meaning}" + (f" ({b.note})" if b.note else ""))
    return "\n".join(lines) + "\n"


def write_params(path: str | Path, tr: Transcription, p: np.ndarray, header: str = "") -> Path:
    """Write the parameter file of the instance p (for ``DIR/solve PATH``)."""
    path = Path(path)
    path.write_text(params_text(tr.values, tr.values.values_of(p), header))
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


def pack_function(tr: Transcription) -> ca.Function:
    """``ocg_gen_pack(values) -> (p, bad)``."""
    v = ca.SX.sym("values", tr.values.size)
    p, bad = tr.values.pack_function(v)
    return ca.Function("ocg_gen_pack", [v], [p, bad], ["values"], ["p", "bad"])


def nlpsol_function(tr: Transcription) -> ca.Function:
    """``ocg_gen_nlpsol(x0, p) -> (x, f, g, lam_g)``: the Transcription's IPOPT instance with
    the bounds of :attr:`Transcription.bounds_function`, computed from p (a bound given by a
    parameter is a runtime input of the exported solver)."""
    x0, p = ca.MX.sym("x0", tr.nx), ca.MX.sym("p", tr.np)
    lbg, ubg, lbx, ubx = tr.bounds_function(p)
    r = tr.solver(x0=x0, p=p, lbg=lbg, ubg=ubg, lbx=lbx, ubx=ubx)
    return ca.Function("ocg_gen_nlpsol", [x0, p], [r["x"], r["f"], r["g"], r["lam_g"]],
                       ["x0", "p"], ["x", "f", "g", "lam_g"])


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


def _ipopt_paths(lib: Path | None, include: Path | None) -> tuple[Path, Path]:
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
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _c_doubles(values: np.ndarray) -> str:
    if not len(values):
        return "{0.0}"
    return "{" + ", ".join(f"{float(v):.17g}" for v in values) + "}"


def _fields(rows: list[tuple[str, int, int, int]]) -> str:
    body = ",\n".join(f"  {{{_c_string(n)}, {o}, {r}, {c}}}" for n, o, r, c in rows)
    return "{\n" + (body or "  {0, 0, 0, 0}") + "\n}"


def _names(names: Sequence[str]) -> str:
    return "{" + (", ".join(_c_string(n) for n in names) or "0") + "}"


def model_sources(tr: Transcription, default_p: np.ndarray, guess: str) -> tuple[str, str]:
    """ocg_model.h and ocg_model.c: dimensions, parameter-file keys, JSON field tables."""
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
    blocks = ",\n".join(
        f"  {{{_c_string(b.key)}, {b.values.start}, {b.size}, {_c_string(b.meaning)}}}"
        for b in values.blocks)
    defines = {
        "OCG_PROBLEM": _c_string(pb.name), "OCG_N": tr.N, "OCG_ORDER": pb.order,
        "OCG_NX": tr.nx, "OCG_NP": tr.np, "OCG_NG": tr.ng, "OCG_NV": values.size,
        "OCG_P_T": tr.layout.p_slices["T"].start, "OCG_N_BLOCKS": len(values.blocks),
        "OCG_N_STATE_FIELDS": len(state_fields), "OCG_N_VELOCITY_FIELDS": len(velocity_fields),
        "OCG_N_PARAMETER_FIELDS": len(param_fields), "OCG_NU": len(controls),
        "OCG_N_MULTIPLIER_NAMES": len(multipliers), "OCG_N_POST": len(C_READOUT_OUTPUTS),
        "OCG_SCHEME": _c_string(tr.disc.scheme),
        "OCG_RETRACTION": _c_string(tr.scheme.retraction), "OCG_RULE": _c_string(tr.disc.rule),
        "OCG_GUESS_LABEL": _c_string(guess),
        "OCG_MANIFOLDS_JSON": _c_string(json.dumps({f.state: f.manifold for f in G.factors})),
    }
    header = "\n".join([
        f"/* Generated by ocgroupoid {__version__} for {pb.name}: the exported instance's "
        "dimensions and tables. */",
        "#ifndef OCG_MODEL_H", "#define OCG_MODEL_H", "",
        *[f"#define {k} {v}" for k, v in defines.items()], "",
        "/* A key of a parameter file: numbers values[offset .. offset+size). */",
        "typedef struct { const char *key; int offset; int size; const char *meaning; } "
        "ocg_block;",
        "/* A named slice of an output row: offset, and rows x cols (rows 0: a vector). */",
        "typedef struct { const char *name; int offset; int rows; int cols; } ocg_field;", "",
        "extern const ocg_block ocg_blocks[];",
        "extern const double ocg_default_values[];",
        "extern const ocg_field ocg_state_fields[];",
        "extern const ocg_field ocg_velocity_fields[];",
        "extern const ocg_field ocg_parameter_fields[];",
        "extern const char *const ocg_control_names[];",
        "extern const char *const ocg_multiplier_names[];", "",
        "#endif", ""])
    source = "\n".join([
        f"/* Generated by ocgroupoid {__version__} for {pb.name}. */",
        '#include <stddef.h>', '#include "ocg_model.h"', "",
        f"const ocg_block ocg_blocks[] = {{\n{blocks}\n}};",
        f"const double ocg_default_values[] = {_c_doubles(values.values_of(default_p))};",
        f"const ocg_field ocg_state_fields[] = {_fields(state_fields)};",
        f"const ocg_field ocg_velocity_fields[] = {_fields(velocity_fields)};",
        f"const ocg_field ocg_parameter_fields[] = {_fields(param_fields)};",
        f"const char *const ocg_control_names[] = {_names(controls)};",
        f"const char *const ocg_multiplier_names[] = {_names(multipliers)};", ""])
    return header, source


def _fill(template: str, values: dict[str, Any]) -> str:
    text = template
    for k, v in values.items():
        text = text.replace(f"@{k}@", str(v))
    left = set(re.findall(r"@[A-Z_]+@", text))
    if left:
        raise ExportError(f"template placeholders without a value: {sorted(left)}")
    return text


def _blocks_table(values: ParameterValues) -> str:
    rows = ["| key | numbers | meaning |", "|---|---|---|"]
    for b in values.blocks:
        rows.append(f"| `{b.key}` | {b.size} | {b.meaning}" + (f" ({b.note})" if b.note else "")
                    + " |")
    return "\n".join(rows)


def _generate(tr: Transcription, folder: Path) -> None:
    cg = ca.CodeGenerator(GENERATED, {"with_header": True})
    for fn in (nlpsol_function(tr), guess_function(tr), pack_function(tr), post_function(tr)):
        cg.add(fn)
    cg.generate(str(folder) + "/")
    path = folder / f"{GENERATED}.c"
    path.write_text(GENERATED_PRELUDE + path.read_text())


def export_c(problem: Problem | Solver, folder: str | Path, N: int = 64,
             retraction: str = "cayley", rule: str = DEFAULT_RULE,
             ipopt: dict[str, Any] | None = None, build: bool = False,
             ipopt_lib: str | Path | None = None, ipopt_include: str | Path | None = None,
             cflags: str = "", scheme: str = DEFAULT_SCHEME, steps: str = "uniform") -> Export:
    """Write ``problem`` compiled on N intervals as a C project in ``folder``.

    ``problem`` may also be a compiled :class:`Solver` (its N, scheme, retraction, rule and
    IPOPT options are kept). IPOPT's own printing is switched off (``print_level 0``) in a
    problem compiled here: the driver's stdout carries the solution JSON only.
    ``ipopt_lib``/``ipopt_include`` default to the libipopt and headers inside the casadi
    wheel; the Makefile records them (overridable: ``make IPOPT_LIB=... IPOPT_INCLUDE=...``)
    and links with an rpath. ``build=True`` runs ``make`` (with ``cflags``) and checks that
    ``folder/solve`` exists. Bounds that are parameter expressions are runtime inputs; adaptive
    steps are not exported (they need a second solve).
    """
    if steps == "adaptive" or (isinstance(problem, Solver) and problem.disc.steps == "adaptive"):
        raise ConfigError("adaptive steps come from a second, phased solve placed on the "
                          "switches of a first one, which the exported solver does not run; "
                          "export with uniform steps (--set discretization.steps=uniform)")
    if isinstance(problem, Solver):
        solver = problem
    elif isinstance(problem, Problem):
        solver = Solver(problem, N, retraction, rule, {**(ipopt or {}), **EXPORT_IPOPT}, scheme,
                        steps)
    else:
        raise ConfigError(f"export_c takes a Problem or a compiled Solver, got "
                          f"{type(problem).__name__}")
    tr = solver.transcription
    lib, include = _ipopt_paths(ipopt_lib, ipopt_include)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    p = tr.pack()
    _generate(tr, folder)
    guess = tr.guess_labels[0]  # what the C solver starts from
    header, source = model_sources(tr, p, guess)
    (folder / "ocg_model.h").write_text(header)
    (folder / "ocg_model.c").write_text(source)
    for name in VERBATIM:
        shutil.copyfile(TEMPLATES / name, folder / name)
    pb = tr.problem
    info = {"PROBLEM": pb.name, "N": tr.N, "RETRACTION": tr.disc.retraction,
            "RULE": tr.disc.rule, "ORDER": pb.order, "NX": tr.nx, "NP": tr.np, "NG": tr.ng,
            "NV": tr.values.size, "VERSION": __version__, "CASADI": ca.__version__,
            "IPOPT_LIB": lib, "IPOPT_INCLUDE": include, "GUESS": guess,
            "KEYS": _blocks_table(tr.values)}
    (folder / "Makefile").write_text(_fill((TEMPLATES / "Makefile.in").read_text(), info))
    (folder / "README.md").write_text(_fill((TEMPLATES / "README.md.in").read_text(), info))
    (folder / "params.txt").write_text(params_text(tr.values, tr.values.values_of(p), (
        f"{pb.name}: the exported instance (N={tr.N}, {tr.disc.retraction}). "
        "Edit values, drop keys to keep their defaults,\nthen run ./solve params.txt. "
        "Format: README.md.")))
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
