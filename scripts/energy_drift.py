"""Energy and Casimir errors over 10^5 steps: the variational integrator against RK4.

``og.simulate`` steps the free rigid body (I = diag(1, 2, 3), tumbling near its unstable
middle axis) and the free heavy top (rotor torques zero) with the order2 node equations
(Cayley, midpoint rule) and with RK4 on the continuous dynamics, both at h = 0.1 s. The
chart shows |E(t) - E(0)| and the Casimir error (|I Omega|^2 of the rigid body, Pi . Gamma
of the top), each curve the maximum over windows of WINDOW steps (the variational errors
oscillate through zero). For the rigid body it also shows the energy and |I xi|^2 of the
variational integrator's own interval velocities xi_k, which it conserves to rounding.

Writes results/energy_drift.json and results/figures/energy_drift.png; ``--out DIR`` writes
both to DIR; ``--quick`` takes 10^4 steps (CI).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import ocgroupoid as og  # noqa: E402
from ocgroupoid.bench.record import write_summary  # noqa: E402
from ocgroupoid.bench.script import arguments  # noqa: E402
from ocgroupoid.systems.heavy_top import GAMMA0, heavy_top  # noqa: E402
from ocgroupoid.systems.rigid_body import INERTIA, rigid_body  # noqa: E402

RESULTS = Path(__file__).resolve().parent.parent / "results"
H, STEPS, QUICK_STEPS = 0.1, 100_000, 10_000
WINDOW = 100  # steps per plotted point (the maximum of |error| over them)
RIGID_OMEGA0 = (0.1, 1.0, 0.1)  # rad/s, near the unstable middle axis: the body flips
TOP_OMEGA0 = (0.5, -0.3, 5.0)  # rad/s, a fast top, tilted 0.4 rad, rotors at rest
FLOOR = 1e-17  # |error| drawn no lower (exact zeros on a log scale)
COLOURS = {"variational": "tab:blue", "interval": "tab:green", "rk4": "tab:red"}


def envelope(t: np.ndarray, error: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Window ends and max |error| over each window of WINDOW values."""
    n = len(error) // WINDOW * WINDOW
    e = np.abs(error[:n]).reshape(-1, WINDOW).max(axis=1)
    return t[WINDOW - 1:n:WINDOW], np.maximum(e, FLOOR)


def curves(sim: og.Simulation, casimir: dict[str, np.ndarray]) -> dict[str, Any]:
    """The errors drawn: per quantity, label -> (times, errors)."""
    t, ti = sim.t, sim.t[:-1] + sim.h / 2
    out: dict[str, Any] = {
        "energy": {"variational (nodes)": (t, sim.variational.energy_error),
                   "RK4": (t, sim.rk4.energy_error)},
        "casimir": {"variational (nodes)": (t, casimir["variational"] - casimir["variational"][0]),
                    "RK4": (t, casimir["rk4"] - casimir["rk4"][0])}}
    if "interval" in casimir:
        out["energy"]["variational (intervals ξ_k)"] = (ti, sim.interval_energy
                                                        - sim.interval_energy[0])
        out["casimir"]["variational (intervals ξ_k)"] = (ti, casimir["interval"]
                                                         - casimir["interval"][0])
    return out


def run_rigid_body(steps: int) -> tuple[og.Simulation, dict[str, Any], float]:
    I = np.array(INERTIA)
    t0 = time.perf_counter()
    sim = og.simulate(rigid_body(Omega0=RIGID_OMEGA0), h=H, steps=steps)
    seconds = time.perf_counter() - t0
    casimir = {"variational": np.sum((I * sim.velocities) ** 2, axis=1),
               "rk4": np.sum((I * sim.rk4.velocities) ** 2, axis=1),
               "interval": np.sum((I * sim.xi) ** 2, axis=1)}
    return sim, casimir, seconds


def run_heavy_top(steps: int) -> tuple[og.Simulation, dict[str, Any], float]:
    t0 = time.perf_counter()
    sim = og.simulate(heavy_top(Omega0=TOP_OMEGA0), h=H, steps=steps)
    seconds = time.perf_counter() - t0
    casimir = {"variational": sim.variational.invariants["Pi.Gamma"],
               "rk4": sim.rk4.invariants["Pi.Gamma"]}
    return sim, casimir, seconds


def record(sim: og.Simulation, casimir: dict[str, np.ndarray], seconds: float,
           setup: dict[str, Any], unit: int) -> dict[str, Any]:
    """JSON of one system: setup, wall times, per curve the final and max |error| and the
    max over each half of the run (a drift shows as a larger second half), and the largest
    distance of the first ``unit`` state components (a unit quaternion or vector) from 1."""
    rows: dict[str, Any] = {}
    for quantity, lines in curves(sim, casimir).items():
        for label, (_, e) in lines.items():
            a, n = np.abs(e), len(e) // 2
            rows[f"{quantity}: {label}"] = {
                "final": float(a[-1]), "max": float(a.max()), "max_first_half": float(a[:n].max()),
                "max_second_half": float(a[n:].max())}
    return {"setup": setup, "wall_seconds": seconds, "initial_energy": float(
        sim.variational.energy[0]), "initial_casimir": float(casimir["variational"][0]),
        "summary": sim.summary(), "errors": rows,
        "unit_norm_error": {tr.integrator: float(np.max(np.abs(
            np.linalg.norm(tr.states[:, :unit], axis=1) - 1))) for tr in (sim.variational,
                                                                          sim.rk4)}}


def draw(path: Path, systems: list[tuple[str, og.Simulation, dict[str, Any], str]],
         steps: int) -> None:
    fig, axes = plt.subplots(2, 2, figsize=(12, 7.5), sharex=True, constrained_layout=True)
    for col, (title, sim, casimir, casimir_label) in enumerate(systems):
        for row, (quantity, lines) in enumerate(curves(sim, casimir).items()):
            ax = axes[row, col]
            for label, (t, e) in lines.items():
                key = "rk4" if label == "RK4" else "interval" if "intervals" in label else \
                    "variational"
                ax.semilogy(*envelope(t, e), color=COLOURS[key], lw=1.4, label=label)
            ax.set_title(title if row == 0 else "")
            ax.set_ylabel("|E(t) − E(0)|  [J]" if quantity == "energy" else casimir_label)
            ax.grid(True, which="major", alpha=0.3)
            ax.legend(loc="center right" if col == 0 else "lower right", fontsize=9)
        axes[1, col].set_xlabel("time t  [s]")
    fig.suptitle(f"Energy and Casimir errors, h = {H} s, {steps:,} steps (T = {H * steps:g} s): "
                 "variational integrator (Cayley, midpoint rule) vs RK4\n"
                 f"each point: max |error| over {WINDOW} steps ({WINDOW * H:g} s)", fontsize=12)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], None, "folder for JSON and PNG (default: "
                     "results/ and results/figures/)", f"{QUICK_STEPS} steps (CI)")
    out = args.out or RESULTS
    figures = args.out or RESULTS / "figures"
    figures.mkdir(parents=True, exist_ok=True)
    steps = QUICK_STEPS if args.quick else STEPS
    rigid, rigid_c, rigid_s = run_rigid_body(steps)
    top, top_c, top_s = run_heavy_top(steps)
    data = {
        "h": H, "steps": steps, "T": H * steps, "window": WINDOW,
        "rigid_body": record(rigid, rigid_c, rigid_s, {
            "inertia": list(INERTIA), "Omega0": list(RIGID_OMEGA0), "R0": "identity",
            "controls": "zero", "casimir": "|I Omega|^2"}, unit=4),
        "heavy_top": record(top, top_c, top_s, {
            "model": "heavy_top defaults (Ibar, J, mgl)", "Gamma0": list(GAMMA0),
            "Omega0": list(TOP_OMEGA0), "theta0": [0, 0], "dtheta0": [0, 0],
            "controls": "zero rotor torques", "casimir": "Pi . Gamma"}, unit=3)}
    path = write_summary(out / "energy_drift.json", data)
    draw(figures / "energy_drift.png", [
        ("free rigid body, I = diag(1, 2, 3), Ω(0) = (0.1, 1, 0.1) rad/s", rigid, rigid_c,
         "| |IΩ|² − |IΩ(0)|² |  [kg² m⁴ s⁻²]"),
        ("free heavy top (rotor torques 0), Ω(0) = (0.5, −0.3, 5) rad/s", top, top_c,
         "|Π·Γ − Π·Γ(0)|  [kg m² s⁻¹]")], steps)
    for name, system in (("rigid body", data["rigid_body"]), ("heavy top", data["heavy_top"])):
        s = system["summary"]
        print(f"{name}: energy error at the end: variational "
              f"{s['variational']['energy_error_final']:.2e} (max "
              f"{s['variational']['energy_error_max']:.2e}), RK4 "
              f"{s['rk4']['energy_error_final']:.2e}; wall {system['wall_seconds']:.2f} s "
              f"(variational {s['variational']['seconds']:.2f} s, RK4 {s['rk4']['seconds']:.2f} s)")
    print(f"wrote {path} and {figures / 'energy_drift.png'}")


if __name__ == "__main__":
    main()
