"""so3_rest_to_rest: build time, IPOPT solve time and iterations versus N (16 ... 1024).

Writes results/bench_so3.json and results/bench_so3.png. Goals (ratios measured in this run):
build time grows at most 2x from N=16 to 1024 (one stage graph, mapped); solve time grows at
most ~20x from N=64 to 1024 (linear in N); median solve at N=64 aimed at <= 10 ms.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from _bench import arguments, median_time, progress, save  # noqa: E402

import ocgroupoid as og  # noqa: E402
from ocgroupoid.models.rigid_body import rigid_body  # noqa: E402
from ocgroupoid.solve import geodesic_guesses  # noqa: E402


def main() -> None:
    args = arguments(__doc__.splitlines()[0])
    Ns = [16, 32, 64] if args.quick else [16, 32, 64, 128, 256, 512, 1024]
    repeats = 3 if args.quick else 15
    pb = rigid_body()
    rows = []
    with progress() as bar:
        task = bar.add_task("so3_rest_to_rest", total=len(Ns))
        for N in Ns:
            bar.update(task, description=f"N={N}: build")
            build, solver = median_time(lambda: og.compile(pb, N=N), 3 if not args.quick else 1)
            tr = solver.transcription
            p = tr.pack()
            guess = geodesic_guesses(tr, p)[0]
            bar.update(task, description=f"N={N}: solve x{repeats}")
            solve, raw = median_time(lambda: tr.solve(guess, p), repeats)
            rows.append({"N": N, "build_seconds": build, "solve_seconds": solve,
                         "iterations": raw.iterations, "status": raw.status, "cost": raw.cost})
            bar.advance(task)
    by = {r["N"]: r for r in rows}
    ratios = {"build_1024_over_16": by[1024]["build_seconds"] / by[16]["build_seconds"]
              if 1024 in by else None,
              "solve_1024_over_64": by[1024]["solve_seconds"] / by[64]["solve_seconds"]
              if 1024 in by else None}
    data = {"problem": "so3_rest_to_rest", "retraction": "cayley", "repeats": repeats,
            "rows": rows, "ratios": ratios, "median_solve_ms_N64": by[64]["solve_seconds"] * 1e3,
            "median_solve_ms_N512": by[512]["solve_seconds"] * 1e3 if 512 in by else None,
            "created": time.strftime("%Y-%m-%d %H:%M:%S")}
    path = save(args.out, "bench_so3", data)
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
    ax[0].loglog(Ns, [r["build_seconds"] for r in rows], "o-", label="build (compile)")
    ax[0].loglog(Ns, [r["solve_seconds"] for r in rows], "s-", label="IPOPT solve (median)")
    ax[0].loglog(Ns, [by[64]["solve_seconds"] * n / 64 for n in Ns], "k:", label="linear in N")
    ax[0].set_xlabel("N")
    ax[0].set_ylabel("seconds")
    ax[0].legend()
    ax[0].grid(alpha=0.3, which="both")
    ax[1].semilogx(Ns, [r["iterations"] for r in rows], "o-")
    ax[1].set_xlabel("N")
    ax[1].set_ylabel("IPOPT iterations")
    ax[1].grid(alpha=0.3)
    fig.suptitle("so3_rest_to_rest: time and iterations versus N")
    fig.tight_layout()
    fig.savefig(args.out / "bench_so3.png", dpi=110)
    for r in rows:
        print(f"N={r['N']:5d}  build {r['build_seconds'] * 1e3:7.1f} ms  solve "
              f"{r['solve_seconds'] * 1e3:8.2f} ms  iterations {r['iterations']:2d}  {r['status']}")
    print(f"ratios: {ratios}; written {path}")


if __name__ == "__main__":
    main()
