"""The closed loop's figure (``DIR/mpc.png``): trajectory against the open-loop plan, the
applied controls with their bounds, and the histogram of the step times.

Panels: the velocities of the plant (solid) and of the open-loop plan (dashed); the tracking
error on the groupoid (:func:`~ocgroupoid.mpc.state.distance`, log scale); the applied
control (solid) against the plan's (dashed), bounds as dotted lines; the warm steps' times.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # the result draws itself with this module (MpcResult.plot)
    from .report import MpcResult


def figure(result: MpcResult, path: Path) -> Path:
    """Draw ``result`` into the PNG ``path``; returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(12, 7.5))
    s = result.settings
    fig.suptitle(f"{result.problem}: {s['mode']} MPC, {s['horizon']} horizon, N={s['N']}, "
                 f"h={s['sample']:.3g} s, noise {s['noise']:g}, mismatch "
                 f"{s['mismatch'] or 'none'}", fontsize=11)
    plan, ny = result.plan, result.plan["velocities"].shape[1]
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    ax = axes[0, 0]
    for j in range(ny):
        c = colors[j % len(colors)]
        ax.plot(result.t, result.z[:, -ny + j], color=c, label=f"y[{j}] closed loop")
        ax.plot(plan["velocity_t"], plan["velocities"][:, j], "--", color=c, alpha=0.7)
    ax.set(title="velocities: closed loop (solid), open-loop plan (dashed)", xlabel="t [s]")
    ax.legend(fontsize=7, ncol=2)
    ax = axes[0, 1]
    names = list(result.steps[0].tracking_error)
    times = [st.t for st in result.steps]
    for name in names:
        e = np.array([st.tracking_error[name] for st in result.steps])
        ax.semilogy(times, np.maximum(e, 1e-16), "o-", ms=3, label=name)
    ax.set(title="distance from the open-loop plan (on the groupoid)", xlabel="t [s]")
    ax.legend(fontsize=8)
    ax = axes[1, 0]
    for j, name in enumerate(result.control_names):
        c = colors[j % len(colors)]
        ax.plot(result.control_t, result.control[:, j], color=c, label=name)
        ax.plot(plan["control_t"], plan["controls"][:, j], "--", color=c, alpha=0.6)
    for b in result.bounds:
        if b.get("quantity") == "controls":
            for side in ("lower", "upper"):
                if b.get(side) is not None:
                    ax.axhline(b[side], color="k", linestyle=":", linewidth=0.8)
    ax.set(title="applied control (solid), plan (dashed), bounds (dotted)", xlabel="t [s]")
    ax.legend(fontsize=7, ncol=2)
    ax = axes[1, 1]
    ms = np.array([st.step_seconds for st in result.steps[1:]]) * 1e3
    if ms.size:
        ax.hist(ms, bins=min(30, max(5, ms.size // 2)), color=colors[0])
        t = result.timing()["step"]
        ax.axvline(t["median"] * 1e3, color="k", label=f"median {t['median'] * 1e3:.2f} ms")
        ax.axvline(t["max"] * 1e3, color="r", label=f"max {t['max'] * 1e3:.2f} ms")
        ax.legend(fontsize=8)
    ax.set(title=f"step times (warm steps; {result.failed_steps} failed)", xlabel="ms")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
