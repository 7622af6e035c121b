"""A coarse grid first: every problem file solved on N from its first guess, and on N/4 first.

For each file in problems/ and N = 32, 64, 128: ``order4@fatrop+jit`` from the file's first
geodesic guess (cold), and the same with ``+coarse`` (solved on N/4 from that guess, then on
N from that solution, interpolated: ``solver.continuation: [N/4]``), built first and then
solved in rounds, five solves each (:func:`~ocgroupoid.bench.timing.interleaved`); the
medians, the iterations of every run and the cost. The ratio is the cold time over the
coarse-first time (> 1: the coarse grid pays), measured in the same run, where both solved;
``same_minimum`` says whether they landed at the same cost (within 1e-6). Writes
``OUT/bench_continuation.json`` and the ratios as a chart, ``OUT/bench_continuation.png``
(``--out``, default ``results/``); ``--quick``: the rotating plate-ball at N = 32, one solve.

    python scripts/bench_continuation.py [--quick] [--out DIR]
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from ocgroupoid import files
from ocgroupoid.bench.chart import ratio_bars
from ocgroupoid.bench.methods import Method
from ocgroupoid.bench.record import write_summary
from ocgroupoid.bench.script import arguments, cell, record, steps
from ocgroupoid.bench.timing import Setting, Trial, interleaved
from ocgroupoid.errors import OcgError

ROOT = Path(__file__).resolve().parents[1]
COLD = Method("order4", backend="fatrop", jit=True)
COARSE = Method("order4", backend="fatrop", jit=True, coarse=True)
NS, REPEATS = (32, 64, 128), 5
QUICK_FILES, QUICK_NS = ("plate_ball_rotating",), (32,)


def chart(rows: list[dict[str, Any]], path: Path) -> Path:
    """The cold time over the coarse-first time, per file, one bar per N."""
    return ratio_bars(rows, path, "cold time / time with N/4 first",
                      "order4, fatrop, jit, from the first guess: > 1 where a coarse grid "
                      "first pays")


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results")
    paths = sorted((ROOT / "problems").glob("*.yaml"))
    Ns, repeats = (QUICK_NS, 1) if args.quick else (NS, REPEATS)
    if args.quick:
        paths = [p for p in paths if p.stem in QUICK_FILES]
    trials: dict[tuple[str, int, str], Trial | OcgError] = {}
    with steps(len(paths) * len(Ns) * 2 + 1) as step:
        for path in paths:
            cfg = files.load(path)
            problem, setting = files.build(cfg), Setting.of(cfg.file)
            for N in Ns:
                for method in (COLD, COARSE):
                    step(f"build {path.stem} {method.label} N={N}")
                    try:
                        trials[path.stem, N, method.label] = Trial(problem, method, N, setting)
                    except OcgError as e:
                        trials[path.stem, N, method.label] = e
        step("solves in rounds")
        interleaved([t for t in trials.values() if isinstance(t, Trial)], repeats)
    rows = []
    for path in paths:
        for N in Ns:
            cold, coarse = (record(trials[path.stem, N, m.label]) for m in (COLD, COARSE))
            both = cold["status"] == coarse["status"] == "Solve_Succeeded"
            rows.append({"file": path.stem, "N": N, "cold": cold, "coarse": coarse,
                         "ratio": cold["seconds"] / coarse["seconds"] if both else None,
                         "same_minimum": both and abs(cold["cost"] - coarse["cost"]) <=
                         1e-6 * abs(cold["cost"])})
    args.out.mkdir(parents=True, exist_ok=True)
    write_summary(args.out / "bench_continuation.json",
                  {"method": COLD.label, "coarse": COARSE.label, "N": list(Ns),
                   "repeats": repeats, "start": "the file's first geodesic guess",
                   "rows": rows})
    chart(rows, args.out / "bench_continuation.png")
    table = Table("file", "N", "cold: iterations, ms", "N/4 first: iterations, ms", "ratio",
                  "same minimum")
    for r in rows:
        table.add_row(r["file"], str(r["N"]), cell(r["cold"]), cell(r["coarse"]),
                      "-" if r["ratio"] is None else f"{r['ratio']:.2f}x",
                      "yes" if r["same_minimum"] else "no")
    Console().print(table)


if __name__ == "__main__":
    main()
