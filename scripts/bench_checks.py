"""A solve through the API against its solver: what the checks of the verdict cost, one run.

For each file in problems/ and N (``--N``, default 16, 64 and 256), one method (``--scheme``,
as for ``ocgroupoid bench work-precision``; default ``order4@fatrop+jit``): the problem
compiled once, then solved through the API as a user solves it
(:meth:`~ocgroupoid.solve.CompiledProblem.solve`, the first guess, no multi-start), five
times after one solve not timed. Per cell the medians of: the whole call; the solver's runs
(``Solution.solve_seconds``); the read-out and the checks of the verdict
(``diagnostics["seconds"]``: the discrete Euler-Lagrange residual, the rank test of the
equality rows, the replay through the continuous problem, the error estimate); the rest
(starts, packing the parameters, fatrop's guard or its helper's way there and back). Writes
``OUT/bench_checks.json`` and a chart of the shares, ``OUT/bench_checks.png`` (``--out``,
default ``results/``); ``--quick``: so3 at N = 16, one solve.

    python scripts/bench_checks.py [--scheme M] [--N 16,64,256] [--quick] [--out DIR]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from ocgroupoid import files
from ocgroupoid.bench.chart import save_png
from ocgroupoid.bench.methods import Method, parse_grids, parse_methods
from ocgroupoid.bench.record import write_summary
from ocgroupoid.bench.script import arguments, steps
from ocgroupoid.bench.timing import Setting
from ocgroupoid.errors import OcgError

ROOT = Path(__file__).resolve().parents[1]
METHOD = Method("order4", backend="fatrop", jit=True)
NS, REPEATS = (16, 64, 256), 5
QUICK_FILES, QUICK_NS = ("so3_rest_to_rest",), (16,)
PARTS = ("solver", "checks", "rest")


def own_arguments(ap: argparse.ArgumentParser) -> None:
    """``--scheme`` and ``--N``."""
    ap.add_argument("--scheme", default=METHOD.label,
                    help=f"the method (default {METHOD.label})")
    ap.add_argument("--N", help=f"intervals, comma-separated (default {','.join(map(str, NS))})")


def timed(path: Path, method: Method, N: int, repeats: int) -> dict[str, Any]:
    """One cell: the medians of the whole solve and of its parts (seconds), its status."""
    cfg = files.load(path, ["solver.multistart=false"])
    compiled = Setting.of(cfg.file).compile(files.build(cfg), method, N)
    compiled.solve()
    whole, solver, checks = [], [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        sol = compiled.solve()
        whole.append(time.perf_counter() - t0)
        solver.append(sol.solve_seconds)
        checks.append(sol.diagnostics["seconds"])
    w, s, c = (statistics.median(v) for v in (whole, solver, checks))
    return {"whole": w, "solver": s, "checks": c, "rest": max(0.0, w - s - c),
            "status": sol.status, "verified": sol.success}


def chart(rows: list[dict[str, Any]], path: Path) -> Path:
    """The share of the whole solve each part takes, per file and N (stacked bars)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in rows if "whole" in r]
    fig, ax = plt.subplots(figsize=(11, 4.5), layout="constrained")
    bottom = [0.0] * len(ok)
    for part, color in zip(PARTS, ("C0", "C1", "C7")):
        shares = [r[part] / r["whole"] for r in ok]
        ax.bar(range(len(ok)), shares, 0.8, bottom=bottom, label=part, color=color)
        bottom = [b + s for b, s in zip(bottom, shares)]
    ax.set_xticks(range(len(ok)), [f"{r['file']} {r['N']}" for r in ok], rotation=60,
                  ha="right", fontsize=7)
    ax.set_ylabel("share of the whole solve")
    ax.set_ylim(0, 1)
    ax.set_title("A solve through the API: the solver, the checks of the verdict, the rest",
                 fontsize=10)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.005, 1.0))
    return save_png(fig, path, 110)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results", more=own_arguments)
    paths = sorted((ROOT / "problems").glob("*.yaml"))
    if args.quick:
        paths = [p for p in paths if p.stem in QUICK_FILES]
    repeats = 1 if args.quick else REPEATS
    try:
        method = parse_methods(args.scheme, (METHOD,))
        Ns = QUICK_NS if args.quick else parse_grids(args.N, NS)
    except OcgError as e:
        Console(stderr=True).print(f"bench_checks: {e}", markup=False, highlight=False,
                                   soft_wrap=True)
        raise SystemExit(2) from None
    if len(method) != 1:
        Console(stderr=True).print("bench_checks: --scheme takes one method", markup=False)
        raise SystemExit(2)
    rows: list[dict[str, Any]] = []
    with steps(len(paths) * len(Ns)) as step:
        for path in paths:
            for N in Ns:
                step(f"{path.stem} N={N}")
                try:
                    cell = timed(path, method[0], N, repeats)
                except OcgError as e:
                    cell = {"status": "error", "message": str(e)}
                rows.append({"file": path.stem, "N": N, **cell})
    args.out.mkdir(parents=True, exist_ok=True)
    write_summary(args.out / "bench_checks.json",
                  {"method": method[0].label, "N": list(Ns), "repeats": repeats,
                   "start": "the file's first guess, no multi-start", "rows": rows})
    chart(rows, args.out / "bench_checks.png")
    table = Table("file", "N", "whole ms", "solver ms", "checks ms", "rest ms", "checks share",
                  "verified")
    for r in rows:
        if "whole" not in r:
            table.add_row(r["file"], str(r["N"]), r["status"], "", "", "", "", "")
            continue
        table.add_row(r["file"], str(r["N"]), *(f"{1e3 * r[k]:.1f}" for k in
                                                ("whole", "solver", "checks", "rest")),
                      f"{r['checks'] / r['whole']:.0%}", "yes" if r["verified"] else "no")
    Console().print(table)


if __name__ == "__main__":
    main()
