"""What the 3-D view of a Solution shows: the body's pose at dense times, its shape and the
points whose paths it traces (:class:`Scene`), read from the solution's states.

The body moves by ``x -> p + R x`` (``R`` body to space, ``p`` in space; z is up). The kind
of body follows from the manifolds of the states:

- ``se3``: a state on SE(3) (free flyer, quadrotor): a box moving along the path of its
  position;
- ``se2``: a state on SE(2) (Dubins car): the same, in the plane z = 0;
- ``ball``: a state on R^2 (the centre ``xy``) and one on SO(3) with a radius parameter
  ``r`` (plate-ball): a sphere rolling on a plate turning at ``Omega_p``, tracing the contact
  point;
- ``top``: a state on S^2 (``Gamma``, the upward vertical seen from the body) with its body
  angular velocity (heavy top): a body on a fixed pivot, tracing its tip. The attitude is
  ``R`` with ``R^T e3 = Gamma``; its rotation about the vertical, which Gamma does not hold,
  is integrated from ``dR/dt = R hat(Omega)``;
- ``so3``: a state on SO(3) (rigid body, reaction wheels): a box turning about a fixed
  point, tracing the tips of its three axes.

The trajectory is sampled between the nodes by splines: ``RotationSpline`` on SO(3) (C2,
through every node) and cubic splines on R^n.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ConfigError
from ..solve.solution import Solution
from .names import Names, manifold

KINDS = ("so3", "se3", "se2", "ball", "top")
MIN_FRAMES, MAX_FRAMES, FRAMES_PER_SECOND = 200, 600, 60


@dataclass(frozen=True)
class Trace:
    """A traced point: ``p + R body + space`` at every frame (a body point, plus an offset
    in space: the ball's contact point lies ``r`` below its centre)."""

    label: str
    color: str
    body: tuple[float, float, float]
    space: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def points(self, R: np.ndarray, p: np.ndarray) -> np.ndarray:
        """The path, (frames, 3)."""
        return p + R @ np.asarray(self.body) + np.asarray(self.space)


@dataclass(frozen=True)
class Scene:
    """The body's poses at ``t`` (``R``: frames x 3 x 3, ``p``: frames x 3), its shape (a
    ``box`` of half-sides ``size`` centred at the body point ``centre``, or a ``sphere`` of
    radius ``size[0]``), the traced points, and a plate (``ball``) turning by ``plate_angle``
    (frames) about the vertical."""

    kind: str
    title: str
    time_unit: str
    t: np.ndarray
    R: np.ndarray
    p: np.ndarray
    shape: str
    size: tuple[float, float, float]
    centre: tuple[float, float, float]
    axis_length: float
    traces: tuple[Trace, ...]
    plate_angle: np.ndarray | None = None
    pivot: bool = False

    def paths(self) -> list[np.ndarray]:
        """The path of every trace, (frames, 3) each."""
        return [tr.points(self.R, self.p) for tr in self.traces]

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners of a box holding the body (its corners, or its sphere),
        its axes and paths at every frame, the origin and the plate."""
        centres = self.p + self.R @ np.asarray(self.centre)
        if self.shape == "sphere":
            ends = [centres - self.size[0], centres + self.size[0]]
        else:
            corners = np.array(np.meshgrid(*[[-h, h] for h in self.size])).reshape(3, -1).T
            ends = [(centres[:, None, :] + corners @ self.R.transpose(0, 2, 1)).reshape(-1, 3)]
        tips = centres[:, None, :] + self.axis_length * self.R.transpose(0, 2, 1)
        pts = [*ends, tips.reshape(-1, 3), *self.paths(), np.zeros((1, 3))]
        if self.plate_angle is not None:
            h = self.plate_half()
            pts.append(np.array([[-h, -h, 0.0], [h, h, 0.0]]))
        return np.min([q.min(axis=0) for q in pts], axis=0), \
            np.max([q.max(axis=0) for q in pts], axis=0)

    def plate_half(self) -> float:
        """Half the side of the plate (the ball's): the contact path with a margin."""
        xy = self.paths()[0][:, :2]
        return float(np.max(np.abs(xy)) + 1.2 * self.size[0])


def scene(sol: Solution, frames: int | None = None) -> Scene:
    """The Scene of a Solution, sampled at ``frames`` times (by default 60 a second of the
    horizon, 200 to 600). ConfigError when no state moves a body the view knows."""
    kinds = {name: manifold(sol, name) for name in sol.states}
    t_nodes = np.asarray(sol.t, dtype=float)
    if t_nodes.size < 2 or not np.all(np.isfinite(t_nodes)) or np.any(np.diff(t_nodes) <= 0):
        raise ConfigError(f"{sol.problem}: the solution's times are not increasing (or fewer "
                          "than two); give a solution file written by `ocgroupoid solve`")
    n = frames or int(np.clip(FRAMES_PER_SECOND * (t_nodes[-1] - t_nodes[0]),
                              MIN_FRAMES, MAX_FRAMES))
    if n < 2:
        raise ConfigError(f"frames = {n}: the view needs at least 2 frames")
    t = np.linspace(t_nodes[0], t_nodes[-1], n)
    names = Names(sol)
    title = f"{sol.problem} (T = {sol.T:.4g} {names.time_unit}, cost {sol.cost:.6g})"
    common = {"title": title, "time_unit": names.time_unit, "t": t}
    by = {m: k for k, m in reversed(list(kinds.items()))}  # the first state on each manifold
    for name, values in sol.states.items():
        if name in by.values() and not np.all(np.isfinite(values)):
            raise ConfigError(f"{sol.problem}: the state {name} holds NaN or infinite values "
                              "(a failed solve?); view a solution whose states are finite")
    if "SE(3)" in by:
        return _rigid(sol, "se3", by["SE(3)"], t, common)
    if "SE(2)" in by:
        return _rigid(sol, "se2", by["SE(2)"], t, common)
    if "SO(3)" in by and "R^2" in by and "r" in sol.parameters:
        return _ball(sol, by["R^2"], by["SO(3)"], t, common)
    if "S^2" in by:
        return _top(sol, by["S^2"], t, common)
    if "SO(3)" in by:
        return _so3(sol, by["SO(3)"], t, common)
    states = ", ".join(f"{k} ({m})" for k, m in kinds.items()) or "none"
    raise ConfigError(f"{sol.problem}: no body to draw: the view draws a state on SO(3), "
                      f"SE(3), SE(2), the heavy top's S^2 or the plate-ball, and this solution's "
                      f"states are {states}; plot it with `ocgroupoid plot` instead")


def rotations(t_nodes: np.ndarray, R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Attitudes at t on the C2 rotation spline through the nodes' (frames x 3 x 3)."""
    from scipy.spatial.transform import Rotation, RotationSpline

    return RotationSpline(t_nodes, Rotation.from_matrix(R))(t).as_matrix()


def curve(t_nodes: np.ndarray, x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Values at t of the cubic spline through the nodes' (rows), held at the end values
    outside the nodes' times."""
    from scipy.interpolate import CubicSpline

    return CubicSpline(t_nodes, x, axis=0)(np.clip(t, t_nodes[0], t_nodes[-1]))


def box_sides(inertia: Any, length: float = 1.0) -> tuple[float, float, float]:
    """Half-sides of a uniform box with the principal inertias' proportions, the longest
    ``length``: ``a_i^2 ~ I_j + I_k - I_i``, none thinner than a quarter of the longest."""
    I = np.abs(np.asarray(inertia, dtype=float).ravel())
    if I.size != 3 or not np.all(np.isfinite(I)) or I.max() <= 0:
        return (length, 0.6 * length, 0.35 * length)
    sq = np.maximum(I.sum() - 2 * I, 0.0)
    a = np.sqrt(sq / sq.max()) if sq.max() > 0 else np.ones(3)
    a = np.maximum(a, 0.25)
    return tuple(float(v) for v in length * a / a.max())  # type: ignore[return-value]


def _inertia(sol: Solution) -> Any:
    """The principal inertias among the parameters (inertia, J or Ibar, 3 values), or None."""
    for key in ("inertia", "J", "Ibar", "I"):
        v = sol.parameters.get(key)
        if v is not None and np.size(v) == 3:
            return v
    return None


def _axes_traces(length: float) -> tuple[Trace, ...]:
    return tuple(Trace(f"tip of body {a}", c, tuple(length * e))
                 for a, c, e in zip("xyz", AXIS_COLORS, np.eye(3)))


AXIS_COLORS = ("#d62728", "#2ca02c", "#1f77b4")


def _so3(sol: Solution, name: str, t: np.ndarray, common: dict[str, Any]) -> Scene:
    R = rotations(sol.t, sol.states[name], t)
    size = box_sides(_inertia(sol), 0.6)
    return Scene(kind="so3", R=R, p=np.zeros((t.size, 3)), shape="box", size=size,
                 centre=(0.0, 0.0, 0.0), axis_length=1.0, traces=_axes_traces(1.0), **common)


def _rigid(sol: Solution, kind: str, name: str, t: np.ndarray,
           common: dict[str, Any]) -> Scene:
    g = np.asarray(sol.states[name], dtype=float)
    if kind == "se2":  # (heading, x, y) as a 3 x 3 matrix: a pose of the plane z = 0
        lift = np.zeros((g.shape[0], 4, 4))
        lift[:, :2, :2], lift[:, 2, 2], lift[:, :2, 3], lift[:, 3, 3] = \
            g[:, :2, :2], 1.0, g[:, :2, 2], 1.0
        g = lift
    p = curve(sol.t, g[:, :3, 3], t)
    extent = float(np.max(np.ptp(p, axis=0))) if p.size else 0.0
    length = max(0.15 * extent, 1e-3) if extent > 0 else 0.5
    size = box_sides(_inertia(sol) if kind == "se3" else (1.0, 3.0, 3.5), length)
    return Scene(kind=kind, R=rotations(sol.t, g[:, :3, :3], t), p=p, shape="box", size=size,
                 centre=(0.0, 0.0, 0.0), axis_length=1.8 * length,
                 traces=(Trace("position", "#444444", (0.0, 0.0, 0.0)),), **common)


def _ball(sol: Solution, xy: str, att: str, t: np.ndarray, common: dict[str, Any]) -> Scene:
    r = float(np.ravel(sol.parameters["r"])[0])
    spin = float(np.ravel(sol.parameters.get("Omega_p", [0.0]))[0])
    centre = curve(sol.t, np.asarray(sol.states[xy], dtype=float)[:, :2], t)
    p = np.column_stack([centre, np.full(t.size, r)])
    return Scene(kind="ball", R=rotations(sol.t, sol.states[att], t), p=p, shape="sphere",
                 size=(r, r, r), centre=(0.0, 0.0, 0.0), axis_length=1.4 * r,
                 traces=(Trace("contact point", "#444444", (0.0, 0.0, 0.0), (0.0, 0.0, -r)),),
                 plate_angle=spin * (t - t[0]), **common)


def _top(sol: Solution, name: str, t: np.ndarray, common: dict[str, Any]) -> Scene:
    from scipy.spatial.transform import Rotation

    Gamma = np.asarray(sol.states[name], dtype=float)
    k = list(sol.states).index(name)
    vels = list(sol.velocities.values())
    if k >= len(vels) or np.shape(vels[k])[1:] != (3,) or len(sol.velocity_t) < 2 \
            or not np.all(np.isfinite(vels[k])) or np.any(np.diff(sol.velocity_t) <= 0):
        raise ConfigError(f"{sol.problem}: the state {name} on S^2 has no body angular "
                          "velocity (3 finite components at increasing times) beside it; the "
                          "view cannot turn the top")
    sub = 8  # integration steps per frame
    ts = np.linspace(t[0], t[-1], (t.size - 1) * sub + 1)
    G = curve(sol.t, Gamma, ts)
    G /= np.linalg.norm(G, axis=1, keepdims=True)
    W = curve(np.asarray(sol.velocity_t, dtype=float), np.asarray(vels[k], dtype=float),
              0.5 * (ts[1:] + ts[:-1]))
    steps = Rotation.from_rotvec(W * np.diff(ts)[:, None])
    R = np.empty((ts.size, 3, 3))
    R[0] = _onto_vertical(np.eye(3), G[0])
    for j in range(ts.size - 1):  # dR/dt = R hat(Omega), kept on R^T e3 = Gamma
        R[j + 1] = _onto_vertical(R[j] @ steps[j].as_matrix(), G[j + 1])
    a, b, c = box_sides(_inertia(sol), 0.5)
    size = (0.5 * a, 0.5 * b, c)  # slender: a top reads better than a block
    length = 2 * c
    return Scene(kind="top", R=R[::sub], p=np.zeros((t.size, 3)), shape="box", size=size,
                 centre=(0.0, 0.0, c), axis_length=0.8 * length,
                 traces=(Trace("tip", "#444444", (0.0, 0.0, length)),), pivot=True, **common)


def _onto_vertical(R: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    """``Q R`` with Q the smallest rotation that makes ``(Q R)^T e3 = gamma``: the spatial
    direction ``R gamma`` turned onto the vertical e3."""
    from scipy.spatial.transform import Rotation

    v = R @ gamma
    axis = np.cross(v, (0.0, 0.0, 1.0))
    s, c = np.linalg.norm(axis), float(v[2])
    if s < 1e-15:
        return R if c > 0 else np.diag([1.0, -1.0, -1.0]) @ R
    return Rotation.from_rotvec(axis / s * np.arctan2(s, c)).as_matrix() @ R
