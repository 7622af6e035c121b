"""Multi-start in parallel: wall time of every start on worker processes against in turn.

For problem files that multi-start (cart_pole with fatrop, heavy_top_rotors, quadrotor and
so3_rest_to_rest with IPOPT), with 4 and 8 perturbed starts on top of the geodesic and model
guesses, the same multi-start is solved one start after the other (``workers=1``) and on two
worker processes (``workers=2``, :mod:`ocgroupoid.solve.parallel`), alternately, in one run.
Printed and written (results/bench_multistart.json, .png) per case: the starts, the wall time of all
starts in turn and in parallel (the medians of the repeats), their ratio (the goal: <= 0.6 on
two cores), the same for the first parallel solve alone (its workers forked for it; the later
ones run on the kept workers), the per-start solver times summed, the best start's time, and
whether both found the same best start and cost. Other processes on the machine slow both
paths alike only if they load it evenly: read the ratio with the load average printed beside
it.
"""

from __future__ import annotations

import os
import statistics
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


def figure(rows: list[dict], path: Path) -> None:
    """Wall time in turn and in parallel, per case."""
    fig, ax = plt.subplots(figsize=(8, 4))
    labels = [f"{r['problem']}\n{r['starts']} starts" for r in rows]
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

    rows = []
    with steps(sum(repeats(name) for name in problems) * len(perturbed) * 2) as step:
        for name in problems:
            for k in perturbed:
                rows.append(case(name, k, repeats(name), N, step))
    args.out.mkdir(parents=True, exist_ok=True)
    write_summary(args.out / "bench_multistart.json", {
        "cores": os.cpu_count(), "workers": WORKERS,
        "repeats": {name: repeats(name) for name in problems}, "rows": rows,
        "goal": "parallel wall time <= 0.6 x in turn on two cores"})
    figure(rows, args.out / "bench_multistart.png")
    print(f"{'problem':18} {'N':>4} {'starts':>6} {'in turn s':>9} {'parallel s':>10} "
          f"{'ratio':>5} {'first':>5} {'same best':>9} {'load':>5}")
    for r in rows:
        print(f"{r['problem']:18} {r['N']:4d} {r['starts']:6d} "
              f"{r['sequential_wall_seconds']:9.2f} {r['parallel_wall_seconds']:10.2f} "
              f"{r['ratio']:5.2f} {r['ratio_first']:5.2f} {str(r['same_best']):>9} "
              f"{r['load_average']:5.1f}")


if __name__ == "__main__":
    main()
