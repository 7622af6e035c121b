"""Figures of a Solution: velocities, controls, multipliers, and attitudes on the sphere."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .solve.solution import write_atomic

Panel = tuple[str, np.ndarray, np.ndarray, list[str]]


def control_curve(sol: Any, per_piece: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """The control polynomial sampled densely, piece by piece, with a NaN row between pieces
    so that a jump at a breakpoint is drawn as a jump."""
    x = np.asarray(sol.control_ppoly["x"], dtype=float)
    ts, us = [], []
    for a, b in zip(x[:-1], x[1:]):
        t = np.linspace(a, b, per_piece)
        ts += [t, [np.nan]]
        us += [sol.control(np.clip(t, a, b - 1e-12 * max(1.0, abs(b)))),
               np.full((1, sol.controls.shape[1]), np.nan)]
    return np.concatenate(ts), np.vstack(us)


def manifold(sol: Any, name: str) -> str:
    """The manifold of a state: as the Solution names it, else from its shape (a solution
    written before manifolds were recorded: 3 x 3 matrices are rotations, 4 x 4 poses)."""
    shape = np.shape(sol.states[name])[1:]
    return sol.manifolds.get(name) or {(3, 3): "SO(3)", (4, 4): "SE(3)"}.get(shape, "")


def attitudes_and_positions(sol: Any) -> tuple[dict[str, np.ndarray], list[Panel]]:
    """Rotations (drawn as body axes) of rotation and pose states, and the position panels
    of poses (the translation of an SE(3) element, the plane's x, y and heading of SE(2))."""
    rotations: dict[str, np.ndarray] = {}
    panels: list[Panel] = []
    for k, g in sol.states.items():
        kind = manifold(sol, k)
        if kind == "SO(3)":
            rotations[k] = g
        elif kind == "SE(3)":
            rotations[k] = g[:, :3, :3]
            panels.append((f"position of {k}", sol.t, g[:, :3, 3], ["x", "y", "z"]))
        elif kind == "SE(2)":
            heading = np.unwrap(np.arctan2(g[:, 1, 0], g[:, 0, 0]))
            panels.append((f"pose {k}", sol.t, np.column_stack([g[:, :2, 2], heading]),
                           ["x", "y", "heading (rad)"]))
    return rotations, panels


def plot_solution(sol: Any, path: str | Path, dpi: int = 110) -> Path:
    """Write a PNG: one panel per quantity; rotations drawn as body axes on the unit sphere."""
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rotations, panels = attitudes_and_positions(sol)
    for k, v in sol.states.items():
        if np.ndim(v) == 2:
            panels.append((f"state {k}", sol.t, v, [f"{k}{i + 1}" for i in range(v.shape[1])]))
    for k, v in sol.velocities.items():
        panels.append((f"velocity {k}", sol.velocity_t, v,
                       [f"{k}{i + 1}" for i in range(v.shape[1])]))
    if sol.controls.size and sol.control_ppoly:
        t, u = control_curve(sol)
        panels.append(("controls (the scheme's polynomial; samples marked)", t, u,
                       sol.control_names))
    elif sol.controls.size:
        panels.append(("controls", sol.controls_t, sol.controls, sol.control_names))
    phi = np.asarray(sol.multipliers.get("Phi", []), dtype=float)
    if phi.size:
        names = sol.multipliers.get("names") or [f"lambda{i + 1}" for i in range(phi.shape[1])]
        panels.append(("multipliers lambda^k", np.asarray(sol.multipliers["t"]), phi,
                       [f"lambda {n}" for n in names]))
    n = len(panels) + len(rotations)
    cols = 2 if n > 1 else 1
    rows = int(np.ceil(n / cols))
    fig = plt.figure(figsize=(6 * cols, 3.6 * rows))
    for i, (title, t, y, labels) in enumerate(panels):
        ax = fig.add_subplot(rows, cols, i + 1)
        y = np.atleast_2d(np.asarray(y))
        for j in range(y.shape[1]):
            line, = ax.plot(t, y[:, j], label=labels[j] if j < len(labels) else str(j))
            if title.startswith("controls (") and j < sol.controls.shape[1]:
                ax.plot(sol.controls_t, sol.controls[:, j], ".", ms=3, color=line.get_color())
        ax.set_title(title)
        ax.set_xlabel("t")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    for i, (k, R) in enumerate(rotations.items()):
        ax = fig.add_subplot(rows, cols, len(panels) + i + 1, projection="3d")
        u, v = np.mgrid[0:2 * np.pi:30j, 0:np.pi:15j]
        ax.plot_wireframe(np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v),
                          color="0.85", linewidth=0.4)
        for axis, color in zip(range(3), ("tab:red", "tab:green", "tab:blue")):
            tip = R[:, :, axis]
            ax.plot(tip[:, 0], tip[:, 1], tip[:, 2], color=color, label=f"body axis {axis + 1}")
            ax.scatter(*tip[-1], color=color, s=12)
        ax.set_title(f"{k}: body axes on the sphere")
        ax.set_box_aspect((1, 1, 1))
        ax.legend(fontsize=7)
    fig.suptitle(f"{sol.problem}: {sol.status}, cost {sol.cost:.6g} (N={sol.N})")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    plt.close(fig)
    write_atomic(path, buf.getvalue())
    return Path(path)
