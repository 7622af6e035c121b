"""Sweeps: points per second of 64 so3 slews (angle x inertia, N = 32), serial versus Dask.

The serial loop solves every point in this one process with one NLP reused (the sweep's
own worker task, in-process); Dask runs ``og.sweep`` on a LocalCluster with one worker
process per core (threads 1). Dask's rate is given with and without the cluster's start-up
(started once, ocgroupoid imported on every worker, then reused for a sweep). Each is run
twice and the faster run counts (the machine is shared); the serial loop runs before the
cluster starts, whose scheduler would share its process. Also measured: NLPs built versus
points solved, that both give the same costs, the machine's parallel capacity (a fixed loop
alone versus on every worker at once: shared cores do less than their count), and warm
starts from the grid neighbour tried first against the cold starts (the default tries them
only when a cold start fails): the largest cost difference where both succeed and the IPOPT
iterations of each.

Writes results/bench_sweep.json and results/bench_sweep.png.
"""

from __future__ import annotations

import importlib
import tempfile
import time
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import ocgroupoid as og  # noqa: E402
from ocgroupoid.bench.record import write_summary  # noqa: E402
from ocgroupoid.bench.script import arguments, steps  # noqa: E402
from ocgroupoid.sweep.cluster import connect, cores  # noqa: E402
from ocgroupoid.sweep.source import Source  # noqa: E402
from ocgroupoid.sweep.spec import axes, points  # noqa: E402
from ocgroupoid.sweep.structure import chunk_size, chunks, classify  # noqa: E402
from ocgroupoid.sweep.task import Task, solve_chunk  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SO3 = ROOT / "problems" / "so3_rest_to_rest.yaml"
INERTIAS = [[1, 2, 3], [2, 2, 3], [3, 2, 1], [1.5, 1, 2], [1, 1, 1], [2, 3, 4], [4, 1, 2],
            [1, 3, 1.5]]


def grid(quick: bool) -> tuple[dict[str, str], list[str]]:
    """The sweep: 8 angles x 8 inertias at N = 32 (quick: 2 x 4 at N = 16)."""
    if quick:
        return ({"final.R.axis_angle.angle": "1:2.5:2",
                 "parameters.inertia": str(INERTIAS[:4])}, ["horizon.N=16"])
    return ({"final.R.axis_angle.angle": "0.25:3:8", "parameters.inertia": str(INERTIAS)},
            ["horizon.N=32"])


def burn(n: int = 4_000_000) -> float:
    """Seconds of a fixed pure-Python loop: the unit of the machine's parallel capacity."""
    t0 = time.perf_counter()
    total = 0
    for i in range(n):
        total += i * i
    return time.perf_counter() - t0


def capacity(client: object, workers: int) -> float:
    """How many cores' worth of work the workers do at once: ``workers`` times the loop's
    time alone over its time on every worker at once (``workers`` on a machine whose cores
    are all its own; less when they are shared)."""
    alone = min(burn() for _ in range(2))
    together = max(client.run(burn).values())  # type: ignore[attr-defined]
    return workers * alone / together


def serial(spec: dict[str, str], sets: list[str], warm: str) -> tuple[list[dict], float]:
    """Every point in this process, one chunk in grid order (one NLP); records and seconds."""
    t0 = time.perf_counter()
    src = Source.of(SO3, sets)
    valid, _ = classify(src, points(axes(spec), [], None, 0, src.digest))
    records = [o.record for key, group in chunks(valid, len(valid))
               for o in solve_chunk(Task(src, key, tuple(group), len(spec), warm))]  # type: ignore[arg-type]
    return records, time.perf_counter() - t0


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results")
    spec, sets = grid(args.quick)
    n_workers = min(cores(), 2) if args.quick else cores()
    repeats = 1 if args.quick else 2
    with steps(2 * repeats + 2) as step:
        serial_times, dask_times, runs, built = [], [], [], []
        for r in range(repeats):  # no cluster running: its scheduler would share this process
            step(f"serial loop ({r + 1}/{repeats})")
            cold, seconds = serial(spec, sets, "fallback")
            serial_times.append(seconds)
            built.append(sum(c["nlp_built"] for c in cold))
        step("serial, warm starts first")
        warm, warm_seconds = serial(spec, sets, "first")
        step(f"Dask: starting {n_workers} workers")
        t0 = time.perf_counter()
        with connect(workers=n_workers) as client, tempfile.TemporaryDirectory() as tmp:
            client.run(importlib.import_module, "ocgroupoid.sweep.task")  # as a sweep would
            startup = time.perf_counter() - t0
            cores_worth = capacity(client, n_workers)
            for r in range(repeats):
                step(f"Dask sweep ({r + 1}/{repeats})")
                t1 = time.perf_counter()
                runs.append(og.sweep(SO3, spec, overrides=sets, client=client,
                                     out=Path(tmp) / f"s{r}"))
                dask_times.append(time.perf_counter() - t1)
    df = runs[0]  # the first: its workers built their NLPs (later runs reuse them)
    serial_seconds, dask_seconds = min(serial_times), min(dask_times)
    n = len(cold)
    by_id = {r["id"]: r for r in cold}
    both = [(r, by_id[r["id"]]) for r in warm if r["success"] and by_id[r["id"]]["success"]]
    data = {
        "what": f"{n} so3_rest_to_rest points ({' x '.join(spec)}; {', '.join(sets)}), "
                f"serial loop versus Dask on {n_workers} worker processes (threads 1)",
        "points": n, "cores": cores(), "workers": n_workers,
        "parallel_capacity": cores_worth,
        "repeats": repeats, "serial_seconds_each": serial_times,
        "dask_seconds_each": dask_times,
        "serial": {"seconds": serial_seconds, "points_per_second": n / serial_seconds,
                   "nlps_built": built[0],  # later loops reuse it
                   "solved": sum(r["success"] for r in cold)},
        "dask": {"seconds": dask_seconds, "startup_seconds": startup,
                 "points_per_second": n / dask_seconds,
                 "points_per_second_with_startup": n / (dask_seconds + startup),
                 "nlps_built": int(df["nlp_built"].sum()), "solved": int(df["success"].sum()),
                 "chunk_size": chunk_size(n, n_workers)},
        "speedup": serial_seconds / dask_seconds,
        "max_cost_difference_dask_vs_serial": max(
            (abs(c - by_id[i]["cost"]) for i, c, ok in zip(df["id"], df["cost"], df["success"])
             if ok and by_id[i]["success"]), default=None),
        "warm_first": {"seconds": warm_seconds, "warm_used": sum(r["warm"] for r in warm),
                       "max_cost_difference_vs_cold": max(
                           (abs(w["cost"] - c["cost"]) for w, c in both), default=None),
                       "iterations": sum(r["iterations"] for r in warm),
                       "iterations_cold": sum(r["iterations"] for r in cold)},
        "seconds_per_point_median": float(np.median([r["seconds"] for r in cold])),
        "solve_seconds_per_point_median": float(np.median([r["solve_seconds"] for r in cold])),
    }
    path = write_summary(args.out / "bench_sweep.json", data)
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    labels = ["serial\n(1 process)", f"Dask, {n_workers} workers\n(cluster running)",
              f"Dask, {n_workers} workers\n(with start-up)"]
    rates = [data["serial"]["points_per_second"], data["dask"]["points_per_second"],
             data["dask"]["points_per_second_with_startup"]]
    ax[0].bar(labels, rates, color=["C0", "C1", "C1"], alpha=0.85)
    for i, r in enumerate(rates):
        ax[0].text(i, r, f"{r:.1f}", ha="center", va="bottom")
    ax[0].set_ylabel("points per second")
    ax[0].set_title(f"{n} so3 points ({sets[0]}); the {n_workers} workers do "
                    f"{cores_worth:.2f} cores' work at once", fontsize=9)
    ax[1].bar(["serial", "Dask"], [n, n], color="0.8", label="points solved")
    ax[1].bar(["serial", "Dask"], [data["serial"]["nlps_built"], data["dask"]["nlps_built"]],
              color="C2", label="NLPs built")
    ax[1].set_title("build reuse")
    ax[1].legend()
    fig.tight_layout()
    fig.savefig(args.out / "bench_sweep.png", dpi=110)
    print(f"serial {rates[0]:.2f} points/s, Dask {rates[1]:.2f} points/s ({rates[2]:.2f} with "
          f"start-up {startup:.1f} s); NLPs built {data['serial']['nlps_built']} (serial), "
          f"{data['dask']['nlps_built']} (Dask) for {n} points; written {path}")


if __name__ == "__main__":
    main()
