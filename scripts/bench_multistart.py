"""Multi-start in parallel: wall time of every start on worker processes against in turn.

For problem files that multi-start (cart_pole with fatrop, heavy_top_rotors, quadrotor and
so3_rest_to_rest with IPOPT), with 4 and 8 perturbed starts on top of the geodesic and model
guesses, the same multi-start is solved one start after the other (``workers=1``) and on two
worker processes (``workers=2``, :mod:`ocgroupoid.solve.parallel`), alternately, in one run.
Printed and written (results/bench_multistart.json, .png) per case: the starts, the wall time of all
starts in turn and in parallel (the medians of the repeats), their ratio (the goal: <= 0.6 on
two cores), the same for the first parallel solve alone (its workers forked for it; the later
ones run on the kept workers), the per-start solver times summed, the best start's time, and
whether both found the same best start and cost. The cases of short starts (so3's, the
cart-pole's) are also solved as the command line solves them, once in a fresh process
(``workers=1`` and ``workers=2`` in alternate processes): their ratio ``ratio_cold`` is the
medians' over those processes, where the parallel path pays its fork and a fresh worker's
first start every time. Other processes on the machine slow both paths alike only if they
load it evenly: read the ratio with the load average printed beside it.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import ocgroupoid as og  # noqa: E402
from ocgroupoid.bench.record import write_summary  # noqa: E402
from ocgroupoid.bench.script import arguments, steps  # noqa: E402
from ocgroupoid.files.load import load  # noqa: E402
from ocgroupoid.files.solving import build_all  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "results"
PROBLEMS = ("cart_pole", "heavy_top_rotors", "quadrotor", "so3_rest_to_rest")
PERTURBED = (4, 8)
WORKERS = 2
#: the repeats of a case: more for short starts (so3's about 30 ms, the cart-pole's about
#: 0.1 s), whose wall time varies by tens of percent from one solve to the next
REPEATS = {"so3_rest_to_rest": 15, "cart_pole": 9}
#: the cases also solved once per fresh process, as the command line does: pairs of processes
COLD = {"so3_rest_to_rest": 8, "cart_pole": 5}
#: one multi-start in a fresh process (argv: file, perturbed starts, workers, N or 0): its report
ONCE = """import json, sys
import ocgroupoid as og
from ocgroupoid.files.load import load
from ocgroupoid.files.solving import build_all
path, k, w, N = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
problem, method, options = build_all(load(path, [f"horizon.N={N}"] if N else []))
sol = og.compile_problem(problem, method, options, workers=w).solve(multistart=k)
print(json.dumps(sol.diagnostics["multistart"]))
"""


def case(name: str, perturbed: int, repeats: int, N: int | None, step) -> dict:
    """One problem file and number of perturbed starts: in turn and on WORKERS processes."""
    overrides = [f"horizon.N={N}"] if N else []
    problem, method, options = build_all(load(ROOT / "problems" / f"{name}.yaml", overrides))
    solvers = {w: og.compile_problem(problem, method, options, workers=w) for w in (1, WORKERS)}
    runs: dict[int, list[dict]] = {1: [], WORKERS: []}
    sols = {}
    for r in range(repeats):
        for w in ((1, WORKERS) if r % 2 == 0 else (WORKERS, 1)):  # alternate: drift hits both
            step(f"{name}, {perturbed} perturbed starts, workers={w}, run {r + 1}/{repeats}")
            sols[w] = solvers[w].solve(multistart=perturbed)
            runs[w].append(sols[w].diagnostics["multistart"])

    def median(w: int, key: str) -> float:
        return statistics.median(m[key] for m in runs[w])

    seq, par = median(1, "wall_seconds"), median(WORKERS, "wall_seconds")
    first = runs[WORKERS][0]["wall_seconds"]  # on workers forked for it
    return {"problem": name, "N": sols[1].N, "perturbed": perturbed,
            "starts": runs[1][0]["starts"], "workers": runs[WORKERS][0]["workers"],
            "sequential_wall_seconds": seq, "parallel_wall_seconds": par, "ratio": par / seq,
            "parallel_first_wall_seconds": first, "ratio_first": first / seq,
            "summed_start_seconds_sequential": median(1, "sequential_seconds"),
            "summed_start_seconds_parallel": median(WORKERS, "sequential_seconds"),
            "best_start_seconds": median(1, "best_start_seconds"),
            "same_best": sols[1].discretization.get("start") ==
            sols[WORKERS].discretization.get("start")
            and abs(sols[1].cost - sols[WORKERS].cost) <= 1e-8 * max(1.0, abs(sols[1].cost)),
            "cost": sols[1].cost, "load_average": os.getloadavg()[0]}


def cold(name: str, perturbed: int, pairs: int, N: int | None, step) -> dict:
    """The multi-start solved once in a fresh process, ``pairs`` processes in turn and as
    many on WORKERS workers, alternately: the medians of their wall times and the ratio."""
    walls: dict[int, list[float]] = {1: [], WORKERS: []}
    for r in range(pairs):
        for w in ((1, WORKERS) if r % 2 == 0 else (WORKERS, 1)):
            step(f"{name}, {perturbed} perturbed starts, workers={w}, fresh process "
                 f"{r + 1}/{pairs}")
            out = subprocess.run([sys.executable, "-c", ONCE, str(ROOT / "problems" /
                                  f"{name}.yaml"), str(perturbed), str(w), str(N or 0)],
                                 capture_output=True, text=True)
            if out.returncode != 0:
                raise SystemExit(f"{name}: the multi-start in a fresh process (workers={w}) "
                                 f"failed with exit code {out.returncode}:\n"
                                 f"{out.stderr.strip()[-2000:]}")
            walls[w].append(json.loads(out.stdout.splitlines()[-1])["wall_seconds"])
    seq, par = statistics.median(walls[1]), statistics.median(walls[WORKERS])
    return {"cold_processes": pairs, "cold_sequential_wall_seconds": seq,
            "cold_parallel_wall_seconds": par, "ratio_cold": par / seq}


def figure(rows: list[dict], path: Path) -> None:
    """Wall time in turn and in parallel, per case."""
    fig, ax = plt.subplots(figsize=(max(8.0, 1.2 * len(rows)), 4))
    labels = [f"{r['problem'].replace('_', ' ')}\n{r['starts']} starts" for r in rows]
    xs = range(len(rows))
    ax.bar([x - 0.2 for x in xs], [r["sequential_wall_seconds"] for r in rows], 0.4,
           label="in turn (workers=1)")
    ax.bar([x + 0.2 for x in xs], [r["parallel_wall_seconds"] for r in rows], 0.4,
           label=f"parallel (workers={WORKERS})")
    for x, r in zip(xs, rows):
        ax.annotate(f"{r['ratio']:.2f}x", (x + 0.2, r["parallel_wall_seconds"]),
                    ha="center", va="bottom", fontsize=8)
    ax.set_xticks(list(xs), labels, fontsize=7)
    ax.set_ylabel("wall time of all starts (s)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], RESULTS)
    problems, perturbed = (PROBLEMS[-1:], PERTURBED[:1]) if args.quick else (PROBLEMS, PERTURBED)
    N = 16 if args.quick else None

    def repeats(name: str) -> int:
        return 1 if args.quick else REPEATS.get(name, 5)

    def pairs(name: str) -> int:
        return min(1, COLD.get(name, 0)) if args.quick else COLD.get(name, 0)

    rows = []
    with steps(sum(repeats(name) + pairs(name) for name in problems) * len(perturbed) * 2
               ) as step:
        for name in problems:
            for k in perturbed:
                row = case(name, k, repeats(name), N, step)
                if pairs(name):
                    row.update(cold(name, k, pairs(name), N, step))
                rows.append(row)
    args.out.mkdir(parents=True, exist_ok=True)
    write_summary(args.out / "bench_multistart.json", {
        "cores": os.cpu_count(), "workers": WORKERS,
        "repeats": {name: repeats(name) for name in problems}, "rows": rows,
        "goal": "parallel wall time <= 0.6 x in turn on two cores"})
    figure(rows, args.out / "bench_multistart.png")
    print(f"{'problem':18} {'N':>4} {'starts':>6} {'in turn s':>9} {'parallel s':>10} "
          f"{'ratio':>5} {'first':>5} {'cold':>5} {'same best':>9} {'load':>5}")
    for r in rows:
        cold_ratio = f"{r['ratio_cold']:5.2f}" if "ratio_cold" in r else f"{'-':>5}"
        print(f"{r['problem']:18} {r['N']:4d} {r['starts']:6d} "
              f"{r['sequential_wall_seconds']:9.2f} {r['parallel_wall_seconds']:10.2f} "
              f"{r['ratio']:5.2f} {r['ratio_first']:5.2f} {cold_ratio} "
              f"{str(r['same_best']):>9} {r['load_average']:5.1f}")


if __name__ == "__main__":
    main()
