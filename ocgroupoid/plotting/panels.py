"""The panels of a Solution's figure, as data: what is drawn where, with which labels.

Every quantity is drawn against time (``time t [s]``) with its meaning as the title, its
symbol and unit as the y label and one legend entry per component, in one panel per quantity
group and unit (:mod:`ocgroupoid.model.units`): never two units in one panel (an SE(3)
twist, a wrench, the quadrotor's thrust and torques are split). On top
of these, by manifold (``Solution.manifolds``): a rotation (SO(3), the rotation of an SE(3)
pose) gets its attitude error angle ``|log(R_T^T R(t))|`` in degrees; a direction on S^2 its
angle to the final direction; a point of a plane (an R^2 state in one declared length unit,
the position of an SE(2) pose) its x-y path with start and target marked; an SE(3) pose its
position against time. Bounds are dashed lines (off scale, and said in the legend, when far
from the values), prescribed final values stars, a free final time a dotted vertical line.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..model.units import TANGENTS
from .names import Names, Quantity, called, manifold, with_unit

MISS = 1e-6  # rad: a final attitude or direction farther than this from its target is named
FAR = 1.0  # a bound farther from the values than FAR times their range is drawn off scale


@dataclass
class Curve:
    """One line or set of markers (``style`` goes to ``Axes.plot``); label None: no legend."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray | None = None
    label: str | None = None
    gid: str | None = None
    style: dict[str, Any] = field(default_factory=dict)
    scale: bool = True  # whether the axes' limits fit it (False: a bound drawn off scale)


@dataclass
class Panel:
    """One axes: ``kind`` "time" (against time) or "plane" (an x-y path, equal axes)."""

    kind: str
    title: str
    xlabel: str
    ylabel: str
    curves: list[Curve]
    gid: str
    final_time: float | None = None  # a free final time, drawn as a vertical line
    final_time_label: str | None = None


# ------------------------------------------------------------------ geometry


def rotation_angle(R: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The angle (rad) of ``target^T R`` for every rotation R (n x 3 x 3): 0 on target."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(np.einsum("ji,njk->nik", target, R)).magnitude()


def direction_angle(v: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The angle (rad) between every direction v (n x 3) and ``target``."""
    return np.arctan2(np.linalg.norm(np.cross(v, target), axis=1), v @ target)


def control_curve(sol: Any, per_piece: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """The control polynomial sampled densely, piece by piece, with a NaN row between pieces
    so that a jump at a breakpoint is drawn as a jump."""
    x = np.asarray(sol.control_ppoly["x"], dtype=float)
    ts: list[ArrayLike] = []
    us: list[np.ndarray] = []
    for a, b in zip(x[:-1], x[1:]):
        t = np.linspace(a, b, per_piece)
        ts += [t, [np.nan]]
        us += [sol.control(np.clip(t, a, b - 1e-12 * max(1.0, abs(b)))),
               np.full((1, sol.controls.shape[1]), np.nan)]
    return np.concatenate(ts), np.vstack(us)


# ------------------------------------------------------------------ building blocks


def _bounds(t: np.ndarray, y: np.ndarray, idx: list[int], bounds: dict[int, tuple[Any, Any]],
            colors: list[str]) -> list[Curve]:
    """Dashed lines at the bounds of the components ``idx`` (values ``y``): once in grey when
    they all share them, else in each component's colour; one legend entry. A bound farther
    from the values than ``FAR`` times their range is drawn off scale (the y axis fits the
    values, so that torques far inside their bounds stay readable) and named in the legend."""
    mine = [(bounds[i], c) for i, c in zip(idx, colors) if i in bounds]
    if not mine:
        return []
    if len(mine) == len(idx) and len({b for b, _ in mine}) == 1:
        mine = [(mine[0][0], "0.35")]
    span = np.array([np.nanmin(t), np.nanmax(t)])
    values = y[:, idx]
    low, high = np.nanmin(values, initial=np.inf), np.nanmax(values, initial=-np.inf)
    reach = FAR * (high - low)
    out: list[Curve] = []
    off: list[float] = []
    for (lo, hi), color in mine:
        for v in (lo, hi):
            if v is not None:
                near = low - reach <= v <= high + reach
                off += [] if near else [v]
                out.append(Curve(span, np.array([v, v]), gid="bound", scale=near, style={
                    "color": color, "linestyle": "--", "linewidth": 1.0}))
    if out:
        shown = ", ".join(f"{v:g}" for v in sorted(set(off)))
        out[0].label = f"bounds (off scale: {shown})" if off else "bounds"
    return out


def _targets(T: float, values: np.ndarray, prescribed: Any, colors: list[str]) -> list[Curve]:
    """Stars at the prescribed final values (``prescribed``: True or one flag per value)."""
    flags = prescribed if isinstance(prescribed, list) else [bool(prescribed)] * len(values)
    out: list[Curve] = []
    for v, on, color in zip(values, flags, colors):
        if on:
            out.append(Curve(np.array([T]), np.array([v]), label=None if out else "target",
                             gid="target", style={"marker": "*", "markersize": 11,
                                                  "color": color, "markeredgecolor": "k",
                                                  "linestyle": "none", "zorder": 4}))
    return out


def colours(n: int) -> list[str]:
    """n distinct line colours: matplotlib's ten (C0..C9), or twenty paired shades beyond."""
    if n <= 10:
        return [f"C{k}" for k in range(n)]
    from matplotlib import colormaps
    from matplotlib.colors import to_hex

    cmap = colormaps["tab20"]
    order = [*range(0, 20, 2), *range(1, 20, 2)]  # the dark shades first, then the light
    return [to_hex(cmap(order[k % 20])) for k in range(n)]


def titles(q: Quantity, keys: list[tuple[str, str, list[int]]]) -> list[str]:
    """One title per panel of ``q``: the meaning of the symbol its components share (a
    thrust f, torques tau) or of the quantity, then the group; panels that would read the
    same name their unit."""
    out = []
    for group, _, idx in keys:
        meaning = q.meanings.get(q.symbol(idx), q.meaning)
        out.append(f"{meaning}: {group}" if group else meaning)
    return [f"{t}: components in {u or 'no declared unit'}" if out.count(t) > 1 else t
            for t, (_, u, _) in zip(out, keys)]


def against_time(q: Quantity, t: np.ndarray, y: np.ndarray, names: Names, gid: str,
                 bounds: dict[int, tuple[Any, Any]] | None = None, T: float | None = None,
                 prescribed: Any = False, samples: tuple[np.ndarray, np.ndarray] | None = None
                 ) -> list[Panel]:
    """One panel per (group, unit) of ``q``: its components against time, their bounds,
    prescribed final values (``prescribed``, at time T) and sample points (``samples``: t,
    values). A lone component named as its panel gets no legend entry (the title says it)."""
    y = np.asarray(y, dtype=float).reshape(len(t), -1)
    keys = q.panels()
    out = []
    for (group, unit, idx), title in zip(keys, titles(q, keys)):
        colors = colours(len(idx))
        lone = len(idx) == 1 and q.components[idx[0]] in (q.meaning, title)
        curves = [Curve(t, y[:, i], label=None if lone else q.components[i], gid=f"{gid}[{i}]",
                        style={"color": c}) for i, c in zip(idx, colors)]
        if samples is not None:
            curves += [Curve(samples[0], samples[1][:, i], style={
                "color": c, "marker": ".", "markersize": 3.5, "linestyle": "none"})
                for i, c in zip(idx, colors)]
        curves += _bounds(t, y, idx, bounds or {}, colors)
        if T is not None and prescribed is not False:
            flags = prescribed if isinstance(prescribed, list) else [True] * y.shape[1]
            curves += _targets(T, y[-1, idx], [flags[i] for i in idx], colors)
        key = f"{group}:{unit}" if group else unit
        out.append(Panel("time", title, names.time_label, with_unit(q.symbol(idx), unit),
                         curves, f"{gid}:{key}" if len(keys) > 1 else gid))
    return out


def _path(name: str, title: str, xy: np.ndarray, q: Quantity, target: bool) -> Panel:
    """The path of a point of the plane (the two components of q) on equal axes: start a
    green dot, the end a red star when it is the prescribed target, else a square."""
    point = {"linestyle": "none", "markersize": 10, "markeredgecolor": "k", "zorder": 4}
    x, y = xy[:, 0], xy[:, 1]
    curves = [Curve(x, y, label="path", gid=f"path:{name}", style={"color": "C0"}),
              Curve(x[:1], y[:1], label="start", gid="start",
                    style={"marker": "o", "color": "C2", **point}),
              Curve(x[-1:], y[-1:], label="target" if target else "end (free)", gid="target",
                    style={"marker": "*" if target else "s", "color": "C3", **point})]
    return Panel("plane", title, with_unit(q.components[0], q.units[0]),
                 with_unit(q.components[1], q.units[1]), curves, f"path:{name}")


# ------------------------------------------------------------------ per quantity


def error_panel(name: str, meaning: str, what: str, t: np.ndarray, angle: np.ndarray,
                names: Names, whole: bool, pose: bool = False) -> Panel:
    """The angle (drawn in degrees) from the final value reached of a rotation or direction
    ``name``, titled as the error to the target when that is prescribed and reached (its star
    at 0); a final value off the target by more than ``MISS`` (``final_residual``: an angle,
    for a ``pose`` the norm of its log) is named in the title, without a star."""
    miss = names.final_miss(name)
    missed = whole and miss > MISS
    who = called(meaning, name)
    if not whole:
        title = f"{who}: error to the final {what} reached (final {what} free)"
    elif missed:
        off = f"pose residual {miss:.2g}" if pose else f"{np.degrees(miss):.2g}° off"
        title = f"{who}: error to the final {what} reached ({off} the target)"
    else:
        title = f"{who}: error to the target"
    gid = f"{what}-error:{name}"
    curves = [Curve(t, np.degrees(angle), gid=gid)]
    if whole and not missed:
        curves += _targets(float(t[-1]), np.array([0.0]), True, ["C0"])
    return Panel("time", title, names.time_label, f"{what} error angle [deg]", curves, gid)


def state_panels(sol: Any, names: Names, name: str) -> list[Panel]:
    """The panels of one state, by its manifold (module docstring)."""
    v = np.asarray(sol.states[name], dtype=float)
    kind = manifold(sol, name)
    t, T = sol.t, float(sol.t[-1])
    prescribed = names.final(name)
    whole = prescribed is True or (isinstance(prescribed, list) and all(prescribed))
    if kind in ("SO(3)", "SE(3)"):
        q = names.quantity("states", name, 3 if kind == "SO(3)" else 6, *TANGENTS[kind][:2])
        R = v[:, :3, :3]
        out = [error_panel(name, q.meaning, "attitude", t, rotation_angle(R, R[-1]), names,
                           whole, pose=kind == "SE(3)")]
        if kind == "SE(3)":
            pos = Quantity("position", f"{called(q.meaning, name)}: position", q.components[3:],
                           q.units[3:], q.groups[3:])
            out += against_time(pos, t, v[:, :3, 3], names, f"position:{name}", T=T,
                                prescribed=whole)
        return out
    if kind == "SE(2)":
        q = names.quantity("states", name, 3, *TANGENTS[kind][:2])
        heading = np.unwrap(np.arctan2(v[:, 1, 0], v[:, 0, 0]))
        pos = Quantity("position", f"{called(q.meaning, name)}: path in the plane",
                       q.components[1:], q.units[1:])
        return [_path(name, pos.meaning, v[:, :2, 2], pos, whole),
                *against_time(Quantity("heading", f"{called(q.meaning, name)}: heading",
                                       q.components[:1], [q.units[0] or "rad"]),
                              t, heading[:, None], names, f"heading:{name}", T=T,
                              prescribed=whole)]
    q = names.quantity("states", name, v.shape[1])
    out = against_time(q, t, v, names, f"state:{name}", bounds=names.bounds("states", name),
                       T=T, prescribed=prescribed)
    if kind == "S^2":
        out.append(error_panel(name, q.meaning, "direction", t, direction_angle(v, v[-1]),
                               names, whole))
    elif v.shape[1] == 2 and names.planar(q):
        out.insert(0, _path(name, f"{called(q.meaning, name)}: path in the plane", v, q, whole))
    return out


def _is_control(sol: Any, v: np.ndarray) -> bool:
    """Whether every component of a velocity is also a control (first-order problems report
    their velocities as controls): the controls' panel then shows it, once."""
    t = np.asarray(sol.velocity_t, dtype=float)
    if not sol.controls.size or not t.size:
        return False
    if sol.control_ppoly:  # the polynomial passes through the velocity samples
        u = np.atleast_2d(sol.control(t)).reshape(len(t), -1)
    elif t.shape == np.shape(sol.controls_t) and np.allclose(t, sol.controls_t):
        u = np.asarray(sol.controls, dtype=float)
    else:
        return False
    tol = 1e-8 * max(1.0, float(np.nanmax(np.abs(v), initial=0.0)))
    return all(any(np.allclose(v[:, i], u[:, j], rtol=0, atol=tol) for j in range(u.shape[1]))
               for i in range(v.shape[1]))


def control_panels(sol: Any, names: Names) -> list[Panel]:
    """The controls: the scheme's polynomial, the samples as dots, bounds dashed."""
    if not sol.controls.size:
        return []
    q = names.controls()
    bounds = names.bounds("controls")
    samples = (sol.controls_t, sol.controls)
    if sol.control_ppoly:
        t, u = control_curve(sol)
        return against_time(q, t, u, names, "controls", bounds, samples=samples)
    return against_time(q, sol.controls_t, sol.controls, names, "controls", bounds)


def multiplier_panels(sol: Any, names: Names) -> list[Panel]:
    """The multipliers of each constraint, one legend entry per row."""
    phi = np.asarray(sol.multipliers.get("Phi", []), dtype=float)
    if not phi.size:
        return []
    rows = list(sol.multipliers.get("names") or ["Phi"] * phi.shape[1])
    t = np.asarray(sol.multipliers["t"], dtype=float)
    out: list[Panel] = []
    for cname in dict.fromkeys(rows):
        idx = [i for i, r in enumerate(rows) if r == cname]
        n = len(idx)
        q = names.quantity("multipliers", cname, n,
                           [f"λ {cname}" if n == 1 else f"λ {cname}[{i + 1}]" for i in range(n)])
        q = Quantity("λ", f"multipliers of {q.meaning}", q.components, q.units, q.groups)
        out += against_time(q, t, phi[:, idx], names, f"multipliers:{cname}")
    return out


def panels(sol: Any) -> list[Panel]:
    """Every panel of a Solution's figure, in reading order: states, velocities, controls,
    multipliers; a free final time marked on every panel against time."""
    names = Names(sol)
    out: list[Panel] = []
    for name in sol.states:
        out += state_panels(sol, names, name)
    for name, v in sol.velocities.items():
        v = np.asarray(v, dtype=float)
        if not _is_control(sol, v):
            out += against_time(names.quantity("velocities", name, v.shape[1]), sol.velocity_t,
                                v, names, f"velocity:{name}",
                                bounds=names.bounds("velocities", name), T=float(sol.T),
                                prescribed=names.final(name) if "final" in names.labels else
                                False)
    controls = control_panels(sol, names)
    out += controls + multiplier_panels(sol, names)
    free = names.free_horizon()
    if free:
        lo, hi = ("" if v is None else f"{v:g}" for v in free)
        label = f"final time T* = {sol.T:.4g} {names.time_unit} (free in [{lo}, {hi or '∞'}])"
        timed = [p for p in out if p.kind == "time"]
        for p in timed:
            p.final_time = float(sol.T)
        if timed:
            (controls or timed)[0].final_time_label = label
    return out
