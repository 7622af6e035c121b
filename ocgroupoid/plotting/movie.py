"""The 3-D view as a movie: a Scene drawn frame by frame on matplotlib's 3-D axes and
written by PillowWriter (GIF) or FFMpegWriter (MP4). No pyplot: a Figure on an Agg canvas."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import DependencyError
from .scene import AXIS_COLORS, Scene

SIZE, DPI = (6.0, 5.0), 80  # inches, dots per inch: 480 x 400 pixels


def movie(sc: Scene, path: Path, kind: str, fps: int, dense: Scene | None = None) -> None:
    """Write every frame of ``sc`` to ``path`` as a ``gif`` or an ``mp4`` at ``fps`` frames
    a second, the paths drawn from ``dense`` (the same motion sampled finer; default ``sc``).
    DependencyError when the MP4 writer's ``ffmpeg`` is not on PATH."""
    from matplotlib import animation
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    if kind == "mp4":
        if shutil.which("ffmpeg") is None:
            raise DependencyError("writing .mp4 needs ffmpeg on PATH: install it (e.g. "
                                  "apt-get install ffmpeg) or write .gif or .html instead")
        writer: Any = animation.FFMpegWriter(fps=fps)
    else:
        writer = animation.PillowWriter(fps=fps)
    fig = Figure(figsize=SIZE, dpi=DPI)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(projection="3d", computed_zorder=False)
    update = _artists(ax, sc, dense or sc)
    path.parent.mkdir(parents=True, exist_ok=True)
    with writer.saving(fig, str(path), DPI):
        for i in range(sc.t.size):
            update(i)
            writer.grab_frame()


def _artists(ax: Any, sc: Scene, dense: Scene) -> Any:
    """Draw what stays (limits, labels, the full paths faint, from ``dense``) and return
    ``update(i)``, which moves the body, its axes, the travelled paths and the plate to
    frame i."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    lo, hi = sc.bounds()
    span = np.maximum(hi - lo, 0.2 * float(np.max(hi - lo)))
    mid = 0.5 * (lo + hi)
    ax.set_xlim(mid[0] - span[0] / 2, mid[0] + span[0] / 2)
    ax.set_ylim(mid[1] - span[1] / 2, mid[1] + span[1] / 2)
    ax.set_zlim(mid[2] - span[2] / 2, mid[2] + span[2] / 2)
    ax.set_box_aspect(tuple(span))
    ax.set_xlabel("X")
    ax.set_ylabel("Y")
    ax.set_zlabel("Z")
    ax.view_init(elev=25, azim=-55)
    ax.figure.suptitle(sc.title, fontsize=10)
    paths, now = dense.paths(), sc.paths()
    done = []
    for q, tr in zip(paths, sc.traces):
        ax.plot(q[:, 0], q[:, 1], q[:, 2], color=tr.color, alpha=0.3, lw=1)
        done.append(ax.plot([], [], [], color=tr.color, lw=1.5,
                            label=f"path of the {tr.label}")[0])
    ax.legend(loc="upper left", fontsize=7, frameon=False)
    plate = [ax.plot([], [], [], color="0.7", lw=0.8)[0] for _ in range(14)] \
        if sc.plate_angle is not None else []
    body = Poly3DCollection([], facecolor=(0.6, 0.68, 0.8, 0.8), edgecolor="#334")
    if sc.shape == "box":
        ax.add_collection3d(body)
    circles = [ax.plot([], [], [], color=c, lw=1)[0] for c in AXIS_COLORS] \
        if sc.shape == "sphere" else []
    ball: list[Any] = []  # the sphere's surface, drawn anew at every frame
    axes = [ax.plot([], [], [], color=c, lw=3)[0] for c in AXIS_COLORS]
    names = [ax.text(0, 0, 0, a, color=c, fontweight="bold") for a, c in zip("xyz", AXIS_COLORS)]
    clock = ax.text2D(0.02, 0.02, "", transform=ax.transAxes)
    if sc.pivot:
        ax.scatter([0], [0], [0], color="k", s=20)

    def update(i: int) -> None:
        R, p = sc.R[i], sc.p[i]
        centre = p + R @ np.asarray(sc.centre)
        k = int(np.searchsorted(dense.t, sc.t[i], side="right"))
        for line, q, end in zip(done, paths, now):
            q = np.vstack([q[:k], end[i]])
            line.set_data_3d(q[:, 0], q[:, 1], q[:, 2])
        if sc.shape == "box":
            body.set_verts([centre + f @ R.T for f in _faces(np.asarray(sc.size))])
        if circles:
            for old in ball:
                old.remove()
            u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
            r = sc.size[0]
            ball[:] = [ax.plot_surface(centre[0] + r * np.cos(u) * np.sin(v),
                                       centre[1] + r * np.sin(u) * np.sin(v),
                                       centre[2] + r * np.cos(v), color=(0.75, 0.8, 0.9),
                                       alpha=0.35, linewidth=0, shade=True, zorder=1)]
        for k, line in enumerate(circles):
            th = np.linspace(0, 2 * np.pi, 49)
            u, v = np.eye(3)[(k + 1) % 3], np.eye(3)[(k + 2) % 3]
            q = centre + sc.size[0] * (np.outer(np.cos(th), u) + np.outer(np.sin(th), v)) @ R.T
            line.set_data_3d(q[:, 0], q[:, 1], q[:, 2])
        for k, (line, name) in enumerate(zip(axes, names)):
            tip = centre + sc.axis_length * R[:, k]
            line.set_data_3d([centre[0], tip[0]], [centre[1], tip[1]], [centre[2], tip[2]])
            name.set_position_3d(centre + 1.1 * sc.axis_length * R[:, k])
        if plate:
            _plate(plate, sc.plate_half(), float(sc.plate_angle[i]))  # type: ignore[index]
        clock.set_text(f"t = {sc.t[i]:.3f} {sc.time_unit}")

    return update


def _faces(h: np.ndarray) -> list[np.ndarray]:
    """The six faces (4 x 3 corners) of the box of half-sides h, centred at the origin."""
    faces = []
    for a in range(3):
        u, v = (a + 1) % 3, (a + 2) % 3
        for s in (-1.0, 1.0):
            f = np.zeros((4, 3))
            f[:, a] = s * h[a]
            f[:, u] = np.array([-1, 1, 1, -1]) * h[u]
            f[:, v] = np.array([-1, -1, 1, 1]) * h[v]
            faces.append(f)
    return faces


def _plate(lines: list[Any], half: float, angle: float) -> None:
    """The plate's grid lines (half of them each way) turned by ``angle`` about Z."""
    c, s = np.cos(angle), np.sin(angle)
    n = len(lines) // 2
    for k, x in enumerate(np.linspace(-half, half, n)):
        for j, (a, b) in enumerate((((x, -half), (x, half)), ((-half, x), (half, x)))):
            pts = np.array([a, b])
            lines[2 * k + j].set_data_3d(c * pts[:, 0] - s * pts[:, 1],
                                         s * pts[:, 0] + c * pts[:, 1], [0.0, 0.0])
