"""Exported C code: one compiled problem as a small C project that builds and runs alone.

``export_c(problem, folder)`` writes, next to a verbatim C library (``c_templates/``):

- ``ocg_generated.c/.h``: CasADi-generated C of four functions of the runtime parameters p
  (``p = [physical parameters | initial pack | V_0 | final pack | V_N | T]``, see
  :class:`~ocgroupoid.transcribe.Transcription`):

  ``ocg_gen_nlpsol(x0, p) -> (x, f, g, lam_g)``  the nlpsol IPOPT instance of the Transcription
  (its stage-wise derivatives come from nlpsol's cache, see :mod:`ocgroupoid.assembly`),
  called with ``lbg = ubg = 0``;
  ``ocg_gen_guess(p) -> x0``  the first geodesic guess of :func:`ocgroupoid.solve.geodesic_guesses`
  followed by forward composition (``Transcription.point``), as a graph of p;
  ``ocg_gen_pack(values) -> (p, bad)``  ``Transcription.pack`` from the numbers of a parameter
  file (quaternions and directions normalised, tangent bases completed);
  ``ocg_gen_post(x, p, lam_g) -> (...)``  the read-out of :func:`ocgroupoid.solve.make_solution`:
  states reconstructed from s_0 and the velocities, node controls and velocities, the
  multipliers lambda^k of Phi_d and of the final conditions.

- ``ocg_model.h/.c``: the dimensions and the tables the JSON writer and the parameter-file
  reader need; ``params.txt``: the exported instance; ``Makefile`` and ``README.md``.

One export serves every instance of the model: boundary values, physical parameters and T
are inputs. Multi-start, continuation and the model's own guess hooks stay in Python: the
C solver starts from the geodesic guess, or from a warm start the caller gives.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import casadi as ca
import numpy as np

from .discretize import DEFAULT_RULE
from .errors import ConfigError, ExportError
from .groupoid.action import SphereAction, tangent_basis
from .groupoid.base import Factor
from .groupoid.lie_group import LieGroupFactor
from .groupoid.pair import Pair, hermite_basis
from .lie import so3
from .lie._backend import safe_if
from .lie.retraction import Retraction
from .problem import Problem
from .solve import Solver, geodesic_guesses
from .transcribe import Transcription

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


# ----------------------------------------------------------------- instance values


@dataclass(frozen=True)
class ValueBlock:
    """One key of a parameter file: its numbers and where they go in p."""

    key: str  # "inertia", "initial.R", "final.Omega", "T", ...
    kind: str  # "vector", "rotation" (unit quaternion), "direction" (unit 3-vector), "horizon"
    values: slice  # slot in the values vector
    p: slice  # slot in p (a direction's slot also holds its tangent basis)
    prescribed: tuple[bool, ...]  # per number: False = free, the number is ignored
    meaning: str

    @property
    def size(self) -> int:
        return self.values.stop - self.values.start

    @property
    def note(self) -> str:
        """Which numbers are free here (read and ignored), or ''."""
        free = [i for i, on in enumerate(self.prescribed) if not on]
        if not free:
            return ""
        return "free: ignored" if len(free) == self.size else f"components {free} free: ignored"


class ValueLayout:
    """The numbers that describe one instance (a parameter file), and their map to p.

    The values hold each state once (a rotation as its quaternion, a direction as its unit
    vector) where p holds the packed boundary targets; ``pack`` is ``Transcription.pack``.
    """

    def __init__(self, tr: Transcription) -> None:
        self.tr = tr
        pb, G, lay, masks = tr.problem, tr.problem.groupoid, tr.p_layout, tr.masks
        blocks: list[ValueBlock] = []
        n = 0

        def add(key: str, kind: str, size: int, p0: int, psize: int,
                prescribed: Sequence[bool], meaning: str) -> None:
            nonlocal n
            blocks.append(ValueBlock(key, kind, slice(n, n + size), slice(p0, p0 + psize),
                                     tuple(bool(b) for b in prescribed), meaning))
            n += size

        P0 = lay["P"].start
        for name, sl in pb.parameter_slices.items():
            size = sl.stop - sl.start
            add(name, "vector", size, P0 + sl.start, size, [True] * size,
                pb.params[name].doc or "physical parameter")
        for end, key_s, key_v, masks_s, masks_v in (
                ("initial", "start", "V0", masks.start_state, masks.start_velocity),
                ("final", "end", "VN", masks.end_state, masks.end_velocity)):
            for f, ts, m in zip(G.factors, G.target_layout.slices, masks_s):
                kind = _kind(f)
                size = f.state_size
                flags = list(m) if f.componentwise else [bool(np.all(m))] * size
                add(f"{end}.{f.state}", kind, size, lay[key_s].start + ts.start,
                    f.target_size, flags, _MEANING[kind])
            if pb.order == 2:
                for f, vs in zip(G.factors, G.velocity_layout.slices):
                    add(f"{end}.{f.velocity}", "vector", f.algebra_dim,
                        lay[key_v].start + vs.start, f.algebra_dim, list(masks_v[vs]),
                        "velocity")
        add("T", "horizon", 1, lay["T"].start, 1, [True], "horizon T > 0")
        self.blocks = blocks
        self.size = n

    def values_of(self, p: np.ndarray) -> np.ndarray:
        """The values of a numeric p (the inverse of ``pack`` on packed vectors)."""
        p = np.asarray(p, dtype=float)
        out = np.zeros(self.size)
        for b in self.blocks:
            out[b.values] = p[b.p][: b.size]
        return out

    def pack_function(self) -> ca.Function:
        """``ocg_gen_pack(values) -> (p, bad)``: bad[i] = 1 when block i is outside its domain
        (a zero quaternion, a direction whose length differs from 1 by more than 1e-6 —
        the tolerance of ``SphereAction.parse_state`` — or T <= 0)."""
        v = ca.SX.sym("values", self.size)
        p = ca.SX.zeros(self.tr.np)
        bad = []
        for b in self.blocks:
            x = v[b.values]
            flag = ca.SX(0)
            if not any(b.prescribed):
                bad.append(flag)
                continue
            if b.kind == "rotation":
                n = ca.norm_2(x)
                flag = n < 1e-12
                packed = x / safe_if(flag, 1.0, n) * ca.if_else(x[0] < 0, -1, 1)
            elif b.kind == "direction":
                n = ca.norm_2(x)
                flag = ca.fabs(n - 1) > 1e-6
                g = x / safe_if(n > 0, n, 1.0)
                packed = ca.vertcat(g, *tangent_basis(g))
            elif b.kind == "horizon":
                flag = ca.logic_not(x > 0)
                packed = x
            else:
                packed = ca.vertcat(*[x[i] if on else 0 for i, on in enumerate(b.prescribed)])
            p[b.p] = packed
            bad.append(flag)
        return ca.Function("ocg_gen_pack", [v], [p, ca.vertcat(*bad)], ["values"], ["p", "bad"])

    def text(self, values: np.ndarray, header: str = "") -> str:
        """A parameter file: one ``KEY v1 v2 ...`` line per block, with its meaning."""
        lines = [f"# {line}".rstrip() for line in header.splitlines()]
        for b in self.blocks:
            nums = " ".join(f"{x:.17g}" for x in values[b.values])
            lines.append(f"{b.key} {nums}  # {b.meaning}" + (f" ({b.note})" if b.note else ""))
        return "\n".join(lines) + "\n"


_MEANING = {"rotation": "unit quaternion w x y z (normalised; sign free)",
            "direction": "unit 3-vector (|v| = 1 to 1e-6)",
            "vector": "vector (one number per component)"}


def _kind(f: Factor) -> str:
    if isinstance(f, LieGroupFactor):
        return "rotation"
    if isinstance(f, SphereAction):
        return "direction"
    if isinstance(f, Pair):
        return "vector"
    raise ExportError(f"export_c knows the factors LieGroupFactor, SphereAction and Pair, not "
                      f"{type(f).__name__}: add its guess and packing to ocgroupoid/codegen.py")


def write_params(path: str | Path, tr: Transcription, p: np.ndarray, header: str = "") -> Path:
    """Write the parameter file of the instance p (for ``DIR/solve PATH``)."""
    layout = ValueLayout(tr)
    path = Path(path)
    path.write_text(layout.text(layout.values_of(p), header))
    return path


# ----------------------------------------------------------------- symbolic helpers


def _conj(q: Any) -> Any:
    return ca.vertcat(q[0], -q[1:4])


def _hermite(s0: Any, v0: Any, sT: Any, vT: Any, T: Any, N: int) -> Any:
    """:meth:`Pair.hermite` on a graph: difference quotients (n x N) of the cubic through
    (s0, v0) at t = 0 and (sT, vT) at t = T, sampled on the N + 1 nodes."""
    Q = ca.mtimes(ca.DM(hermite_basis(N)), ca.horzcat(s0, T * v0, sT, T * vT).T)
    return ((Q[1:, :] - Q[:-1, :]) / (T / N)).T


def _preferred_velocity(f: Factor, ret: Retraction, start: Any, end: Any, V0: Any, VN: Any,
                        T: Any, N: int, m_end: np.ndarray, m0: np.ndarray,
                        mN: np.ndarray) -> Any:
    """The first alternative of ``factor_guesses`` for one factor, as a (dim x N) graph."""
    dim = f.algebra_dim
    if isinstance(f, Pair):
        s0 = start[: f.state_size]
        goal = ca.vertcat(*[end[i] if m_end[i] else s0[i] + T * (V0[i] if m0[i] else 0)
                            for i in range(dim)])
        v0 = ca.vertcat(*[V0[i] if m0[i] else (goal[i] - s0[i]) / T for i in range(dim)])
        vT = ca.vertcat(*[VN[i] if mN[i] else (goal[i] - s0[i]) / T for i in range(dim)])
        return _hermite(s0, v0, goal, vT, T, N)
    if not np.all(m_end):
        return ca.MX.zeros(dim, N)  # "rest"
    if isinstance(f, LieGroupFactor):
        q0, qT = start[:4], end[:4]
        rel = so3.quat_multiply(_conj(q0), qT) if f.side == "right" else \
            so3.quat_multiply(qT, _conj(q0))
        W = so3.exp(so3.quat_log(rel) / N)  # "geodesic"
    elif isinstance(f, SphereAction):
        g0, gT = start[:3], end[:3]
        axis = ca.cross(g0, gT)
        sin, cos = ca.norm_2(axis), ca.dot(g0, gT)
        turns = sin > 1e-12
        axis = ca.if_else(turns, axis / safe_if(turns, sin, 1.0), tangent_basis(g0)[0])
        W = so3.exp(-axis * ca.atan2(sin, cos) / N)  # "great circle"
    else:
        raise ExportError(f"no guess for {type(f).__name__} in export_c")
    return ca.repmat(ret.tau_inv(W) / (T / N), 1, N)


def guess_function(tr: Transcription) -> ca.Function:
    """``ocg_gen_guess(p) -> x0``: ``tr.point(geodesic_guesses(tr, p)[0], p)`` as a graph of p."""
    G, N, lay, masks = tr.problem.groupoid, tr.N, tr.p_layout, tr.masks
    p = ca.MX.sym("p", tr.np)
    T = p[lay["T"].start]
    start, end, V0, VN = (p[lay[k]] for k in ("start", "end", "V0", "VN"))
    XI = ca.vertcat(*[
        _preferred_velocity(f, r, start[ts], end[ts], V0[vs], VN[vs], T, N, me, m0, mN)
        for f, r, ts, vs, me, m0, mN in zip(
            G.factors, tr.stages.retractions, G.target_layout.slices, G.velocity_layout.slices,
            masks.end_state, masks.start_velocity_by(G), masks.end_velocity_by(G))])
    w = ca.vertcat(ca.MX.zeros(tr.nx), p)
    S = tr.stages.step.mapaccum(N)(w[tr.iw_s[:, 0].tolist()], XI, T)
    dg, ds = G.algebra_dim, G.state_size
    source = ca.vertcat(ca.vec(XI), ca.vec(S), ca.MX.zeros(1))
    index = np.full(tr.nx, dg * N + ds * N)  # free initial components start at zero
    index[tr.iw_xi] = np.arange(dg * N).reshape(N, dg).T
    index[tr.iw_s[:, 1:]] = dg * N + np.arange(ds * N).reshape(N, ds).T
    for iw, k in ((tr.iw_V0, 0), (tr.iw_VN, N - 1)):  # free end velocities: the end xi
        free = iw < tr.nx
        index[iw[free]] = k * dg + np.flatnonzero(free)
    return ca.Function("ocg_gen_guess", [p], [source[index.tolist()]], ["p"], ["x0"])


# ------------------------------------------------------------------ read-out


# in the order of enum ocg_output (ocg_solver.h): OCG_X = 0 ... OCG_FINAL_MULTIPLIERS = 10
POST_OUTPUTS = ("x_solution", "t", "states", "node_states", "velocity_t", "velocities",
                "control_t", "controls", "multiplier_t", "multipliers", "final_multipliers")


def _shown(f: Factor, s: Any) -> Any:
    """``Factor.format_state`` on a graph, flattened row-major (a rotation as its matrix)."""
    return ca.vec(so3.quat_to_matrix(s).T) if isinstance(f, LieGroupFactor) else s


def post_function(tr: Transcription) -> ca.Function:
    """``ocg_gen_post(x, p, lam_g)``: what ``make_solution`` reads off a result, each output a
    (width x count) matrix, i.e. one column per time (one row per time in C, row-major)."""
    pb, G, N = tr.problem, tr.problem.groupoid, tr.N
    dg, ds = G.algebra_dim, G.state_size
    x, p, lam = ca.MX.sym("x", tr.nx), ca.MX.sym("p", tr.np), ca.MX.sym("lam_g", tr.ng)
    w = ca.vertcat(x, p)
    pick = lambda idx: w[np.asarray(idx).ravel(order="F").tolist()]  # noqa: E731
    XI = ca.reshape(pick(tr.iw_xi), dg, N)
    s0, T, P = pick(tr.iw_s[:, 0]), pick(tr.iw_T), pick(tr.iw_P)
    V0, VN = pick(tr.iw_V0), pick(tr.iw_VN)
    S = tr.stages.step.mapaccum(N)(s0, XI, T)  # Transcription.reconstruct
    index = np.arange(tr.nx)
    index[tr.iw_s[:, 1:]] = tr.nx + np.arange(ds * N).reshape(N, ds).T
    x_rec = ca.vertcat(x, ca.vec(S))[index.tolist()]
    S_all = ca.horzcat(s0, S)
    s = ca.SX.sym("s", ds)
    show = ca.Function("show", [s], [ca.vertcat(*[_shown(f, s[ss]) for f, ss in
                                                 zip(G.factors, G.state_layout.slices)])])
    t = T * ca.DM(np.arange(N + 1) / N).T
    node = tr.stages.node
    if pb.order == 2:  # diagnostics.node_velocities / node_controls
        vel = ca.horzcat(V0, (XI[:, :-1] + XI[:, 1:]) / 2, VN)
        vt = t
        prev = ca.horzcat(2 * V0 - XI[:, 0], XI)
        nxt = ca.horzcat(XI, 2 * VN - XI[:, -1])
        u = node.map(N + 1)(S_all, prev, nxt, T, P)[2]
        ut = t
    else:
        vel = XI
        vt = T * ca.DM((np.arange(N) + 0.5) / N).T
        u = node.map(N)(S_all[:, :-1], XI, T, P)[2]
        ut = vt
        if u.size1():
            u = ca.horzcat(u[:, 0] - (u[:, 1] - u[:, 0]) / 2, u,
                           u[:, -1] + (u[:, -1] - u[:, -2]) / 2)
            ut = ca.horzcat(0, vt, T)
    rows, final = tr.phi_rows(), tr.rows("final")
    phi = ca.reshape(lam[rows.ravel(order="F").tolist()], *rows.shape) if rows.size \
        else ca.MX(0, 1)
    lam_final = lam[final.ravel().tolist()] if final.size else ca.MX(0, 1)
    outs = [x_rec, t, show.map(N + 1)(S_all), S_all, vt, vel, ut, u, vt, phi, lam_final]
    return ca.Function("ocg_gen_post", [x, p, lam], [ca.densify(o) for o in outs],
                       ["x", "p", "lam_g"], list(POST_OUTPUTS))


def nlpsol_function(tr: Transcription) -> ca.Function:
    """``ocg_gen_nlpsol(x0, p) -> (x, f, g, lam_g)``: the Transcription's IPOPT instance with
    ``lbg = ubg = 0`` (all constraints are equalities)."""
    x0, p = ca.MX.sym("x0", tr.nx), ca.MX.sym("p", tr.np)
    r = tr.solver(x0=x0, p=p, lbg=0, ubg=0)
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


def model_sources(tr: Transcription, layout: ValueLayout, default_p: np.ndarray,
                  guess: str) -> tuple[str, str]:
    """ocg_model.h and ocg_model.c: dimensions, parameter-file keys, JSON field tables."""
    from . import __version__

    pb, G = tr.problem, tr.problem.groupoid
    state_fields, k = [], 0
    for f in G.factors:
        rows, cols = (3, 3) if isinstance(f, LieGroupFactor) else (0, f.state_size)
        state_fields.append((f.state, k, rows, cols))
        k += max(rows, 1) * cols
    velocity_fields = [(f.velocity, vs.start, 0, vs.stop - vs.start)
                       for f, vs in zip(G.factors, G.velocity_layout.slices)]
    P0 = tr.p_layout["P"].start
    param_fields = [(name, P0 + sl.start, 0, sl.stop - sl.start)
                    for name, sl in pb.parameter_slices.items()]
    controls = [n for n, _ in pb.controls]
    multipliers = [n for n, c in pb.constraints for _ in range(c.numel())]
    blocks = ",\n".join(
        f"  {{{_c_string(b.key)}, {b.values.start}, {b.size}, {_c_string(b.meaning)}}}"
        for b in layout.blocks)
    defines = {
        "OCG_PROBLEM": _c_string(pb.name), "OCG_N": tr.N, "OCG_ORDER": pb.order,
        "OCG_NX": tr.nx, "OCG_NP": tr.np, "OCG_NG": tr.ng, "OCG_NV": layout.size,
        "OCG_P_T": tr.p_layout["T"].start, "OCG_N_BLOCKS": len(layout.blocks),
        "OCG_N_STATE_FIELDS": len(state_fields), "OCG_N_VELOCITY_FIELDS": len(velocity_fields),
        "OCG_N_PARAMETER_FIELDS": len(param_fields), "OCG_NU": len(controls),
        "OCG_N_MULTIPLIER_NAMES": len(multipliers),
        "OCG_RETRACTION": _c_string(tr.disc.retraction), "OCG_RULE": _c_string(tr.disc.rule),
        "OCG_GUESS_LABEL": _c_string(guess),
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
        f"const double ocg_default_values[] = {_c_doubles(layout.values_of(default_p))};",
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


def _blocks_table(layout: ValueLayout) -> str:
    rows = ["| key | numbers | meaning |", "|---|---|---|"]
    for b in layout.blocks:
        rows.append(f"| `{b.key}` | {b.size} | {b.meaning}" + (f" ({b.note})" if b.note else "")
                    + " |")
    return "\n".join(rows)


def _generate(tr: Transcription, layout: ValueLayout, folder: Path) -> None:
    cg = ca.CodeGenerator(GENERATED, {"with_header": True})
    for fn in (nlpsol_function(tr), guess_function(tr), layout.pack_function(),
               post_function(tr)):
        cg.add(fn)
    cg.generate(str(folder) + "/")
    path = folder / f"{GENERATED}.c"
    path.write_text(GENERATED_PRELUDE + path.read_text())


def export_c(problem: Problem | Solver, folder: str | Path, N: int = 64,
             retraction: str = "cayley", rule: str = DEFAULT_RULE,
             ipopt: dict[str, Any] | None = None, build: bool = False,
             ipopt_lib: str | Path | None = None, ipopt_include: str | Path | None = None,
             cflags: str = "") -> Export:
    """Write ``problem`` compiled on N intervals as a C project in ``folder``.

    ``problem`` may also be a compiled :class:`Solver` (its N, retraction, rule and IPOPT
    options are kept). IPOPT's own printing is switched off (``print_level 0``) in a
    problem compiled here: the driver's stdout carries the solution JSON only.
    ``ipopt_lib``/``ipopt_include`` default to the libipopt and headers inside the casadi
    wheel; the Makefile records them (overridable: ``make IPOPT_LIB=... IPOPT_INCLUDE=...``)
    and links with an rpath. ``build=True`` runs ``make`` (with ``cflags``) and checks that
    ``folder/solve`` exists.
    """
    if isinstance(problem, Solver):
        solver = problem
    elif isinstance(problem, Problem):
        solver = Solver(problem, N, retraction, rule, {**(ipopt or {}), **EXPORT_IPOPT})
    else:
        raise ConfigError(f"export_c takes a Problem or a compiled Solver, got "
                          f"{type(problem).__name__}")
    tr = solver.transcription
    lib, include = _ipopt_paths(ipopt_lib, ipopt_include)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    layout = ValueLayout(tr)
    p = tr.pack()
    _generate(tr, layout, folder)
    guess = geodesic_guesses(tr, p)[0].label  # what the C solver starts from
    header, source = model_sources(tr, layout, p, guess)
    (folder / "ocg_model.h").write_text(header)
    (folder / "ocg_model.c").write_text(source)
    for name in VERBATIM:
        shutil.copyfile(TEMPLATES / name, folder / name)
    from . import __version__

    pb = tr.problem
    info = {"PROBLEM": pb.name, "N": tr.N, "RETRACTION": tr.disc.retraction,
            "RULE": tr.disc.rule, "ORDER": pb.order, "NX": tr.nx, "NP": tr.np, "NG": tr.ng,
            "NV": layout.size, "VERSION": __version__, "CASADI": ca.__version__,
            "IPOPT_LIB": lib, "IPOPT_INCLUDE": include, "GUESS": guess,
            "KEYS": _blocks_table(layout)}
    (folder / "Makefile").write_text(_fill((TEMPLATES / "Makefile.in").read_text(), info))
    (folder / "README.md").write_text(_fill((TEMPLATES / "README.md.in").read_text(), info))
    (folder / "params.txt").write_text(layout.text(layout.values_of(p), (
        f"{pb.name}: the exported instance (N={tr.N}, {tr.disc.retraction}). "
        "Edit values, drop keys to keep their defaults,\nthen run ./solve params.txt. "
        "Format: README.md.")))
    binary = make(folder, cflags) if build else None
    return Export(folder, pb.name, tr.N, tr.nx, tr.np, tr.ng, layout.size, binary, solver)


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
