"""The figure of every problem file: solve each file in problems/ as `ocgroupoid solve` does
(its own N, scheme and solver options) and draw it with `og.plot`.

Writes results/figures/<name>.png (shown in the README) and results/figures/figures.json
(status, cost, N, T and the seconds of each solve). ``--quick`` solves at N = 64 (CI).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.bench.record import write_summary
from ocgroupoid.bench.script import arguments, steps

ROOT = Path(__file__).resolve().parent.parent
PROBLEMS = ROOT / "problems"
QUICK_N = 64  # the coarsest grid on which every problem file is verified (heavy top: 1%)


def solve_file(path: Path, quick: bool) -> og.Solution:
    """A problem file solved with its own settings (N = QUICK_N when ``quick``)."""
    cfg = files.load(path, [f"horizon.N={QUICK_N}"] if quick else [])
    f, d = cfg.file, cfg.file.discretization
    solver = og.compile_problem(files.build(cfg), f.horizon.N, d.retraction, d.rule, f.solver.ipopt,
                        d.scheme, d.steps)
    return solver.solve(multistart=f.solver.multistart,
                        continuation=f.solver.continuation or None)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results" / "figures",
                     "folder for the PNGs", f"N = {QUICK_N} (CI)")
    args.out.mkdir(parents=True, exist_ok=True)
    paths = sorted(PROBLEMS.glob("*.yaml"))
    rows: dict[str, Any] = {}
    with steps(len(paths)) as step:
        for path in paths:
            step(f"solving and plotting {path.stem}")
            t0 = time.perf_counter()
            sol = solve_file(path, args.quick)
            og.plot(sol, args.out / f"{path.stem}.png")
            rows[path.stem] = {"status": sol.status, "success": sol.success, "cost": sol.cost,
                               "N": sol.N, "T": sol.T, "seconds": time.perf_counter() - t0}
    write_summary(args.out / "figures.json", {"quick": args.quick, "problems": rows})
    failed = [name for name, r in rows.items() if not r["success"]]
    if failed:
        sys.exit(f"not solved: {', '.join(failed)}")


if __name__ == "__main__":
    main()
