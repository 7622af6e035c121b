"""The finer grid of a continuation with and without the coarse grid's multipliers (IPOPT).

For every problem file, with IPOPT (``solver.backend: ipopt``, the file's scheme, no jit) and
N = 128 and 512: the grid N/2 solved once from the first guess, then the grid N from that
solution twice, alternately: from its velocities interpolated alone (IPOPT's cold start, as
continuation did before) and with its multipliers carried over
(:func:`ocgroupoid.solve.multipliers.onto`: IPOPT's primal-dual warm start, what continuation
and accuracy on demand now run). Printed and written (``OUT/bench_carried.json``): the
iterations and the solver time of the grid N (the median of the repeats: 3 at N = 128, 1 at
512), the ratio cold / warm of the times, and whether both landed at the same cost (within
1e-8), and the ratios as a chart (``OUT/bench_carried.png``). ``--quick``: the quadrotor
with minimum time at N = 32, once.

    python scripts/bench_carried.py [--quick] [--out DIR]
"""

from __future__ import annotations

import statistics
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.bench.chart import ratio_bars
from ocgroupoid.bench.record import write_summary
from ocgroupoid.bench.script import arguments, steps
from ocgroupoid.solve.multipliers import onto

ROOT = Path(__file__).resolve().parents[1]
NS = {128: 3, 512: 1}  # N: repeats
QUICK = ("quadrotor_min_time", {32: 1})


def compiled(path: Path, N: int) -> og.CompiledProblem:
    """The file on N intervals with IPOPT."""
    cfg = files.load(path, [f"horizon.N={N}", "solver.backend=ipopt", "solver.jit=false"])
    return og.compile_problem(files.build(cfg), files.method(cfg), files.options(cfg))


def row(path: Path, N: int, repeats: int, step: Any) -> dict[str, Any]:
    """One file and grid: the coarse grid solved, the fine one from it, cold and warm."""
    step(f"{path.stem} N={N // 2}, then N={N}")
    coarse, fine = compiled(path, N // 2), compiled(path, N)
    first = coarse.solve(multistart=False)
    if first.status != "Solve_Succeeded":
        return {"file": path.stem, "N": N, "coarse_status": first.status}
    tc, tf = coarse.transcription, fine.transcription
    warm = onto(tc, first, tf, tf.pack())
    starts = {"cold": warm.primal or warm, "warm": warm}  # velocities alone; with multipliers
    runs: dict[str, list[og.Solution]] = {"cold": [], "warm": []}
    for r in range(repeats):
        for kind in (("cold", "warm") if r % 2 == 0 else ("warm", "cold")):
            step(f"{path.stem} N={N}, {kind}, {r + 1}/{repeats}")
            runs[kind].append(fine.solve(multistart=False, guess=starts[kind]))
    out: dict[str, Any] = {"file": path.stem, "N": N, "coarse_iterations": first.iterations,
                           "carried": starts["warm"].lam_g is not None}
    for kind, sols in runs.items():
        out[kind] = {"status": sols[-1].status, "iterations": sols[-1].iterations,
                     "seconds": statistics.median(s.solve_seconds for s in sols),
                     "cost": sols[-1].cost}
    ok = out["cold"]["status"] == out["warm"]["status"] == "Solve_Succeeded"
    out["ratio"] = out["cold"]["seconds"] / out["warm"]["seconds"] if ok else None
    out["same_minimum"] = ok and abs(out["cold"]["cost"] - out["warm"]["cost"]) <= \
        1e-8 * abs(out["cold"]["cost"])
    return out


def chart(rows: list[dict[str, Any]], path: Path) -> Path:
    """The cold time over the warm time of the grid N, per file, one bar per N."""
    return ratio_bars(rows, path, "time without / with the multipliers",
                      "IPOPT from the coarse grid's solution: > 1 where carrying its "
                      "multipliers pays", "N = {N} (from N = {half})")


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results")
    paths = sorted((ROOT / "problems").glob("*.yaml"))
    Ns = NS
    if args.quick:
        paths, Ns = [p for p in paths if p.stem == QUICK[0]], QUICK[1]
    rows = []
    with steps(len(paths) * sum(1 + 2 * k for k in Ns.values())) as step:
        for path in paths:
            for N, repeats in Ns.items():
                rows.append(row(path, N, repeats, step))
    args.out.mkdir(parents=True, exist_ok=True)
    write_summary(args.out / "bench_carried.json", {"N": Ns, "backend": "ipopt",
                                                     "rows": rows})
    chart(rows, args.out / "bench_carried.png")
    table = Table("file", "N", "cold: iterations, s", "warm: iterations, s", "cold / warm",
                  "same minimum")
    for r in rows:
        if "cold" not in r:
            table.add_row(r["file"], str(r["N"]), f"coarse grid: {r['coarse_status']}", "",
                          "", "")
            continue
        cells = [f"{r[k]['iterations']}, {r[k]['seconds']:.3f}" +
                 ("" if r[k]["status"] == "Solve_Succeeded" else f" ({r[k]['status']})")
                 for k in ("cold", "warm")]
        table.add_row(r["file"], str(r["N"]), *cells,
                      "-" if r["ratio"] is None else f"{r['ratio']:.2f}x",
                      "yes" if r["same_minimum"] else "no")
    Console().print(table)


if __name__ == "__main__":
    main()
