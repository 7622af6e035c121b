"""Exported C code: one compiled problem as a small C project that builds and runs alone.

``export_c(problem, folder)`` writes a C project in which every file is rendered from a
template of ``c_templates/`` (``@KEY@`` placeholders, :func:`_fill`; Python computes only the
values) except CasADi's own output:

- ``{prefix}generated.c/.h``, ``{prefix}generated_warm.c/.h``, ``{prefix}generated_once.c/.h``:
  the CasADi-generated Functions of :mod:`~ocgroupoid.export.functions` (the solvers and the
  read-out; the warm solver; what a solve runs once: the guess, the packing of a parameter
  file, the verdict's checks), after ``prelude.c.in``; with ``solver.backend: fatrop`` the
  solvers are fatrop's driver instead (no ``generated_warm``; :mod:`~ocgroupoid.export.fatrop`);
- the library, one job a file: ``{prefix}solver.c/.h`` the public API, ``{prefix}json.c``
  the JSON writer, ``{prefix}functions.c/.h`` the calls of the generated functions,
  ``{prefix}hooks.c/.h`` with ``{prefix}ipopt_hooks.h`` what the backend reports of a solve,
  ``{prefix}result.h`` what a result holds, ``{prefix}model.c/.h`` the dimensions and the
  tables (the ranges of the keys from :mod:`~ocgroupoid.model.ranges`, which the problem
  files are checked against too);
- the driver: ``main.c`` and ``{prefix}params.c/.h`` (the parameter-file reader);
  ``params.txt`` the exported instance; ``Makefile`` and ``README.md``.

Every symbol, macro and file name of an export starts with its ``prefix`` (``ocg_``/``OCG_``
by default), so that exports of different problems link into one program. A solve keeps its
state in its result and on the stack; what stays global is read-only (the tables) or per
export and one solve at a time: the memory CasADi's generated solver checks out, and the
hooks' pointer to the running solve's record (``hooks.c.in`` says why).

One export serves every instance of the model: boundary values, physical parameters and T
are inputs. Multi-start, continuation, the rescue of a failed order4 solve through order2
and the model's own guess hooks stay in Python: the C solver starts from the geodesic
guess, from a point the caller gives, or from an earlier result's primal-dual point
(``{prefix}solve_warm``).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Collection

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
from ..nlp.method import Method
from ..nlp.options import SolverOptions
from ..nlp.parameters import ParameterValues
from ..nlp.program import C_READOUT_OUTPUTS
from ..nlp.shortcuts import choose
from ..nlp.transcription import Transcription
from ..solve.compiled import CompiledProblem
from ..solve.outputs import write_atomic
from ..verify.graph import CHECKS, FIGURES
from . import fatrop as exported_fatrop, mpc as closed_loop
from .build import casadi_dir, ipopt_paths, make  # noqa: F401  (casadi_dir: the export API)
from .folder import MANIFEST, claim_folder, digest, manifest
from .functions import CHECK_FAILURES, generate
from .literals import c_double, c_doubles, c_names, c_string

TEMPLATES = Path(__file__).resolve().parent / "c_templates"
#: the exported files rendered from c_templates/NAME.in, named with the prefix
#: (``{prefix}solver.c`` from ``solver.c.in``; main.c keeps its name)
PREFIXED = ("solver.h", "solver.c", "result.h", "json.c", "functions.h", "functions.c",
            "hooks.h", "hooks.c", "ipopt_hooks.h", "model.h", "model.c",
            "params.h", "params.c")
#: the prefix of every symbol, macro (upper case) and file of an export unless told
DEFAULT_PREFIX = "ocg_"
_PREFIX = re.compile(r"[a-z][a-z0-9_]*_")
#: the libraries each backend links with (all in the casadi wheel)
BACKEND_LIBS = {"ipopt": "-lipopt", "fatrop": "-lipopt -lfatrop -lblasfeo"}


def solver_files(tr: Transcription, prefix: str) -> dict[str, str]:
    """The solvers' objects and headers the Makefile and ``{prefix}functions.h`` name: IPOPT's
    warm twin, generated apart, or fatrop's driver (:mod:`~ocgroupoid.export.fatrop`)."""
    objects, headers = (("generated_warm.o",), ("generated_warm.h",)) if tr.fatrop is None \
        else (exported_fatrop.OBJECTS, exported_fatrop.HEADERS)
    return {"SOLVER_OBJECTS": " ".join(prefix + o for o in objects),
            "SOLVER_HEADERS": " ".join(prefix + h for h in headers),
            "SOLVER_HEADER": prefix + headers[0]}
EXPORT_IPOPT = {"print_level": 0, "sb": "yes"}  # stdout carries the JSON, nothing else


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


# ------------------------------------------------------------------ the C project


@dataclass(frozen=True)
class Export:
    """What ``export_c`` wrote, and the compiled CompiledProblem it was exported from."""

    folder: Path
    problem: str
    N: int
    n_x: int  # NLP variables (length of a warm start)
    n_p: int  # runtime parameters p
    n_g: int  # constraints
    n_values: int  # numbers of a parameter file
    binary: Path | None  # DIR/solve when built
    solver: CompiledProblem
    mpc: Path | None = None  # DIR/mpc (built with the export's build) when the loop was written


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


def _c_range(r: Range) -> str:
    """One row of ``ocg_ranges``: the range of a key (:mod:`~ocgroupoid.model.ranges`)."""
    return f"  {{{r.kind}, {c_double(r.lo)}, {c_double(r.hi)}, {c_double(r.ratio)}}}"


def _fields(rows: list[tuple[str, int, int, int]]) -> str:
    body = ",\n".join(f"  {{{c_string(n)}, {o}, {r}, {c}}}" for n, o, r, c in rows)
    return "{\n" + (body or "  {0, 0, 0, 0}") + "\n}"


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


def model_values(tr: Transcription, default_p: np.ndarray, guess: str,
                 positive: Collection[str] = ()) -> dict[str, Any]:
    """What model.h.in and model.c.in are filled with: dimensions, parameter-file keys (with
    the physical parameters in ``positive`` flagged: their numbers must be > 0), JSON field
    tables, the verdict's names; C literals and initializers."""
    pb, G, values = tr.problem, tr.problem.groupoid, tr.values
    state_fields, k = [], 0
    for f in G.factors:  # a shown state is a vector (rows 0) or a matrix, row-major
        shape = f.matrix_shape
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
        f"  {{{c_string(b.key)}, {b.values.start}, {b.size}, {c_string(b.meaning)}, "
        f"{int(on)}}}" for b, on in zip(values.blocks, flagged))
    ranges = ",\n".join(_c_range(block_range(b.key, b.kind, on))
                         for b, on in zip(values.blocks, flagged))
    labels = static_labels(pb)
    return {
        "COMMENT_NAME": plain_name(pb.name), "PROBLEM": c_string(pb.name), "N": tr.N,
        "ORDER": pb.order, "NX": tr.nx, "NP": tr.np, "NG": tr.ng, "NV": values.size,
        "P_T": tr.layout.p_slices["T"].start, "N_BLOCKS": len(values.blocks),
        "N_STATE_FIELDS": len(state_fields), "N_VELOCITY_FIELDS": len(velocity_fields),
        "N_PARAMETER_FIELDS": len(param_fields), "NU": len(controls),
        "N_MULTIPLIER_NAMES": len(multipliers), "N_POST": len(C_READOUT_OUTPUTS),
        "SCHEME": c_string(tr.disc.scheme), "BACKEND_FATROP": int(tr.fatrop is not None),
        "BACKEND": c_string(tr.backend),
        "MAX_ITER": tr.fatrop.max_iter if tr.fatrop is not None else 0,
        "RETRACTION": c_string(tr.scheme.retraction), "RULE": c_string(tr.disc.rule),
        "GUESS_LABEL": c_string(guess),
        "MANIFOLDS_JSON": c_string(json.dumps({f.state: f.manifold for f in G.factors})),
        "LABELS_JSON": c_string(json.dumps(labels)),
        "BOUNDS_JSON": c_string(json.dumps(labels["bounds"])),  # the C loop's mpc.json
        "N_CHECKS": len(CHECKS), "N_FIGURES": len(FIGURES), "PARAMS_MAX_BYTES": FILE_BYTES,
        "RANGE_SIGNED": SIGNED, "RANGE_POSITIVE": POSITIVE, "RANGE_TIME": TIME,
        "MAX_SECONDS": c_double(tr.max_seconds),
        "BLOCKS": f"{{\n{blocks}\n}}", "RANGES": f"{{\n{ranges}\n}}",
        "DEFAULT_VALUES": c_doubles(values.values_of(default_p)),
        "STATE_FIELDS": _fields(state_fields), "VELOCITY_FIELDS": _fields(velocity_fields),
        "PARAMETER_FIELDS": _fields(param_fields), "CONTROL_NAMES": c_names(controls),
        "MULTIPLIER_NAMES": c_names(multipliers), "CHECK_NAMES": c_names(CHECKS),
        "FIGURE_NAMES": c_names(FIGURES),
        "CHECK_FAILURES": c_names([CHECK_FAILURES[c] for c in CHECKS]),
    }


def _fill(template: str, values: dict[str, Any]) -> str:
    """``@KEY@`` replaced by its value, in one pass (a value holding ``@X@`` stays as is)."""
    left = set(_PLACEHOLDER.findall(template)) - set(values)
    if left:
        raise ExportError(f"template placeholders without a value: {sorted(left)}")
    return _PLACEHOLDER.sub(lambda m: str(values[m.group(1)]), template)


#: ``@KEY@`` in a template; ``@prefix@`` and ``@PREFIX@`` are the export's prefix
_PLACEHOLDER = re.compile(r"@([A-Za-z_]+)@")


def _render(name: str, values: dict[str, Any]) -> str:
    """The template ``c_templates/name`` filled with ``values``."""
    return _fill((TEMPLATES / name).read_text(), values)


def _blocks_table(values: ParameterValues) -> str:
    rows = ["| key | numbers | meaning |", "|---|---|---|"]
    for b in values.blocks:
        rows.append(f"| `{b.key}` | {b.size} | {_one_line(b.meaning)}"
                    + (f" ({b.note})" if b.note else "") + " |")
    return "\n".join(rows)


def check_prefix(prefix: str) -> str:
    """``prefix`` if it can start C names: lower-case letters, digits and ``_``, a letter
    first and ``_`` last (``so3_``); else a ConfigError with the fix."""
    if not isinstance(prefix, str) or not _PREFIX.fullmatch(prefix):
        raise ConfigError(f"prefix={prefix!r}: a prefix of C names is lower-case letters, "
                          "digits and '_', starting with a letter and ending with '_' "
                          "(e.g. 'so3_')")
    return prefix


def _write_all(folder: Path, files: dict[str, str | bytes]) -> None:
    """Write every file atomically; the manifest first accepts the old and the new contents
    (an interrupted export can be redone), then only the new ones."""
    old = manifest(folder) or {}
    new = {name: [digest(data)] for name, data in files.items()}
    both = {name: sorted(set(old.get(name, [])) | set(new.get(name, [])))
            for name in set(old) | set(new)}

    def record(entries: dict[str, list[str]]) -> None:
        write_atomic(folder / MANIFEST, json.dumps(
            {"ocgroupoid": __version__, "files": dict(sorted(entries.items()))}, indent=1) + "\n")

    record(both)
    for name, data in files.items():
        write_atomic(folder / name, data)
    record({**{k: v for k, v in old.items() if k not in new}, **new})


def export_c(problem: Problem | CompiledProblem, folder: str | Path, N: int | None = None,
             retraction: str | None = None, rule: str | None = None,
             ipopt: dict[str, Any] | None = None, build: bool = False,
             ipopt_lib: str | Path | None = None, ipopt_include: str | Path | None = None,
             cflags: str = "", scheme: str | None = None, steps: str | None = None,
             force: bool = False, positive: Collection[str] = (),
             backend: str | None = None, max_seconds: float | None = None,
             prefix: str = DEFAULT_PREFIX, *, method: Method | None = None,
             options: SolverOptions | None = None, mpc: bool | None = None) -> Export:
    """Write ``problem`` compiled with ``method`` (N intervals, scheme, retraction, rule)
    and ``options`` (backend, IPOPT's options, ``max_seconds``) as a C project in
    ``folder``; the keywords N to max_seconds replace their fields, as in
    :func:`~ocgroupoid.solve.entry.compile_problem` (the exported solver is C of its own: no jit).

    ``problem`` may also be a compiled :class:`CompiledProblem` (its N, scheme, retraction, rule and
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
    runs longer, e.g. fatrop). ``prefix`` (lower case, ending in ``_``) starts every symbol,
    macro (in upper case) and C file name of the export: exports with different prefixes
    link into one program. ``mpc``: the closed loop in C (``{prefix}mpc.h``, ``DIR/mpc``:
    :mod:`~ocgroupoid.export.mpc`); None writes it when the problem has one, True requires it.
    """
    method, options = choose(method, options, N=N, retraction=retraction, rule=rule,
                             ipopt=ipopt, scheme=scheme, steps=steps, backend=backend,
                             max_seconds=max_seconds)
    if method.steps == "adaptive" or (isinstance(problem, CompiledProblem)
                                      and problem.disc.steps == "adaptive"):
        raise ConfigError("adaptive steps come from a second, phased solve placed on the "
                          "switches of a first one, which the exported solver does not run; "
                          "export with uniform steps (--set discretization.steps=uniform)")
    if not isinstance(problem, (CompiledProblem, Problem)):
        raise ConfigError(f"export_c takes a Problem or a compiled CompiledProblem, got "
                          f"{type(problem).__name__}")
    check_prefix(prefix)
    folder = claim_folder(folder, force)
    lib, include = ipopt_paths(ipopt_lib, ipopt_include)
    if isinstance(problem, CompiledProblem):
        solver = problem
    else:
        solver = CompiledProblem(problem, method, replace(
            options, ipopt={**options.ipopt, **EXPORT_IPOPT}, jit=False))
    tr = solver.transcription
    p = tr.pack()
    names = {"prefix": prefix, "PREFIX": prefix.upper(), "VERSION": __version__}
    loop = closed_loop.wanted(tr, mpc)
    real_time = closed_loop.rti(tr, prefix) if loop else None
    files: dict[str, str | bytes] = dict(generate(
        tr, solver.ipopt, prefix, _render("prelude.c.in", names),
        closed_loop.functions(tr, prefix, real_time) if loop else ()))
    guess = tr.guess_labels[0]  # what the C solver starts from
    model = {**names, **model_values(tr, p, guess, positive),
             **(closed_loop.values(tr, real_time) if loop else {})}
    model.update(solver_files(tr, prefix))
    if tr.fatrop is not None:
        model.update(exported_fatrop.values(tr))
        files.update(exported_fatrop.driver(prefix))
    for name in PREFIXED + (closed_loop.PREFIXED if loop else ()) + \
            (exported_fatrop.TEMPLATES if tr.fatrop is not None else ()):
        files[prefix + name] = _render(f"{name}.in", model)
    files["main.c"] = _render("main.c.in", names)
    if loop:
        files[closed_loop.DRIVER] = _render(f"{closed_loop.DRIVER}.in", model)
    pb = tr.problem
    info = {**names, "PROBLEM": plain_name(pb.name), "N": tr.N,
            "RETRACTION": tr.disc.retraction, "RULE": tr.disc.rule, "ORDER": pb.order,
            "NX": tr.nx, "NP": tr.np, "NG": tr.ng, "NV": tr.values.size,
            "CASADI": ca.__version__,  # type: ignore[attr-defined]  # not in its stubs
            "IPOPT_LIB": lib, "IPOPT_INCLUDE": include,
            "GUESS": _one_line(guess), "BACKEND": tr.backend,
            "BACKEND_LIBS": BACKEND_LIBS[tr.backend], "KEYS": _blocks_table(tr.values),
            **solver_files(tr, prefix), "SOLVER_README": _render(
                f"solver_{'fatrop' if tr.fatrop is not None else 'ipopt'}.md.in", names).strip()}
    files["Makefile"] = _render("Makefile.in", {
        **info, "IPOPT_LIB": _make_value(lib), "IPOPT_INCLUDE": _make_value(include),
        **closed_loop.make_values(prefix, loop, real_time is not None)})
    files["README.md"] = _render("README.md.in", info)
    files["params.txt"] = params_text(tr.values, tr.values.values_of(p), (
        f"{plain_name(pb.name)}: the exported instance (N={tr.N}, {tr.disc.retraction}). "
        "Edit values, drop keys to keep their defaults,\nthen run ./solve params.txt. "
        "Format: README.md."))
    folder.mkdir(parents=True, exist_ok=True)
    _write_all(folder, files)
    binary = make(folder, cflags) if build else None
    driver = (make(folder, cflags, "mpc") if build else folder / "mpc") if loop else None
    return Export(folder, pb.name, tr.N, tr.nx, tr.np, tr.ng, tr.values.size, binary, solver,
                  driver)
