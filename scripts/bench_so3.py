"""so3_rest_to_rest: build time, IPOPT solve time and iterations versus N (16 ... 1024).

Writes results/bench_so3.json and results/bench_so3.png. Goals (ratios measured in this run):
build time grows at most 2x from N=16 to 1024 (one stage graph, mapped); solve time grows at
most ~20x from N=64 to 1024 (linear in N); median solve at N=64 aimed at <= 10 ms. The build
is split into its phases (stage graphs, derivative assembly, IPOPT setup), and the CasADi
calls every build of the NLP must make are timed alone at the smallest and largest N: the
floor under any build, whatever its bookkeeping.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import casadi as ca  # noqa: E402
import matplotlib  # noqa: E402
import numpy as np  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from _bench import arguments, median_time, progress, save  # noqa: E402

import ocgroupoid as og  # noqa: E402
from ocgroupoid.models.rigid_body import rigid_body  # noqa: E402
from ocgroupoid.assembly import StageDerivatives  # noqa: E402
from ocgroupoid.solve import geodesic_guesses  # noqa: E402
from ocgroupoid.transcribe import Transcription, nlpsol_options  # noqa: E402


def casadi_floor(tr: Transcription, repeats: int) -> dict[str, float]:
    """Median seconds of the CasADi calls any build of this NLP makes, with every index
    precomputed: ``nlpsol`` on the assembled functions, one ``Function.map`` per stage
    function, the Jacobian and Hessian ``Sparsity`` and one index node over all derivative
    entries. What a build spends beyond the N = 16 value of this floor is ours."""
    fns = {k: tr.solver.get_function(k) for k in ("nlp_grad_f", "nlp_jac_g", "nlp_hess_l")}
    sparsities = [fns["nlp_jac_g"].sparsity_out(1), fns["nlp_hess_l"].sparsity_out(0)]
    ccs = [(sp.size1(), sp.size2(), *sp.get_ccs()) for sp in sparsities]
    derivatives = [(b.ncols, f) for b in tr.blocks for d in [StageDerivatives(b)]
                   for f in (d.grad, d.jac, d.hess)]
    stage_funs = [(b.ncols, b.fun) for b in tr.blocks] + derivatives
    entries = sum(n * f.nnz_out(0) for n, f in derivatives)
    index = np.random.default_rng(0).integers(0, entries, entries)
    src = ca.MX.sym("src", entries)
    opts = nlpsol_options(None, fns)
    times: dict[str, list[float]] = {"nlpsol": [], "map": [], "sparsity": [], "index": []}
    for _ in range(repeats):
        fresh = [(n, ca.Function(f.name(), f.sx_in(), f.call(f.sx_in()))) for n, f in stage_funs]
        t0 = time.perf_counter()
        ca.nlpsol("floor", "ipopt", tr.nlp, opts)
        t1 = time.perf_counter()
        for n, f in fresh:
            f.map(n)
        t2 = time.perf_counter()
        for nrow, ncol, colind, row in ccs:
            ca.Sparsity(nrow, ncol, colind, row)
        t3 = time.perf_counter()
        src[index.tolist()]
        t4 = time.perf_counter()
        for k, dt in zip(times, (t1 - t0, t2 - t1, t3 - t2, t4 - t3)):
            times[k].append(dt)
    out = {k: statistics.median(v) for k, v in times.items()}
    return {**out, "total": sum(out.values()), "derivative_entries": entries}


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
            builds = [og.compile(pb, N=N).transcription for _ in range(1 if args.quick else 3)]
            build = statistics.median(b.build_seconds for b in builds)
            phases = {k: statistics.median(b.build_phases[k] for b in builds)
                      for k in builds[0].build_phases}
            tr = builds[-1]
            p = tr.pack()
            guess = geodesic_guesses(tr, p)[0]
            bar.update(task, description=f"N={N}: solve x{repeats}")
            solve, raw = median_time(lambda: tr.solve(guess, p), repeats)
            floor = casadi_floor(tr, 3) if N in (Ns[0], Ns[-1]) else None
            rows.append({"N": N, "build_seconds": build, "build_phases_seconds": phases,
                         "casadi_floor_seconds": floor, "solve_seconds": solve,
                         "iterations": raw.iterations, "status": raw.status, "cost": raw.cost})
            bar.advance(task)
    by = {r["N"]: r for r in rows}
    ratios = {"build_1024_over_16": by[1024]["build_seconds"] / by[16]["build_seconds"]
              if 1024 in by else None,
              "solve_1024_over_64": by[1024]["solve_seconds"] / by[64]["solve_seconds"]
              if 1024 in by else None}
    if 1024 in by:  # where the growth is: stage graphs are built once, whatever N
        ratios.update({f"build_{k}_1024_over_16": by[1024]["build_phases_seconds"][k]
                       / by[16]["build_phases_seconds"][k] for k in tr.build_phases})
    first, last = rows[0], rows[-1]
    # the best ratio any build could reach: N=16's build plus only CasADi's own growth
    floor_growth = last["casadi_floor_seconds"]["total"] - first["casadi_floor_seconds"]["total"]
    ratios[f"floor_build_{last['N']}_over_{first['N']}"] = \
        (first["build_seconds"] + floor_growth) / first["build_seconds"]
    data = {"problem": "so3_rest_to_rest", "retraction": "cayley", "repeats": repeats,
            "rows": rows, "ratios": ratios, "median_solve_ms_N64": by[64]["solve_seconds"] * 1e3,
            "median_solve_ms_N512": by[512]["solve_seconds"] * 1e3 if 512 in by else None,
            "created": time.strftime("%Y-%m-%d %H:%M:%S")}
    path = save(args.out, "bench_so3", data)
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
    ax[0].loglog(Ns, [r["build_seconds"] for r in rows], "o-", label="build (compile)")
    for k, style in (("stages", "v--"), ("assembly", "^--"), ("nlpsol", "d--")):
        ax[0].loglog(Ns, [r["build_phases_seconds"][k] for r in rows], style, ms=4, lw=0.8,
                     label=f"  build: {k}")
    floors = [r for r in rows if r["casadi_floor_seconds"]]
    ax[0].loglog([r["N"] for r in floors], [r["casadi_floor_seconds"]["total"] for r in floors],
                 "kx", ms=8, label="CasADi floor of any build")
    ax[0].loglog(Ns, [r["solve_seconds"] for r in rows], "s-", label="IPOPT solve (median)")
    ax[0].loglog(Ns, [by[64]["solve_seconds"] * n / 64 for n in Ns], "k:", label="linear in N")
    ax[0].set_xlabel("N")
    ax[0].set_ylabel("seconds")
    ax[0].legend(fontsize=7)
    ax[0].grid(alpha=0.3, which="both")
    ax[1].semilogx(Ns, [r["iterations"] for r in rows], "o-")
    ax[1].set_xlabel("N")
    ax[1].set_ylabel("IPOPT iterations")
    ax[1].set_ylim(0, max(r["iterations"] for r in rows) + 2)
    ax[1].grid(alpha=0.3)
    fig.suptitle("so3_rest_to_rest: time and iterations versus N")
    fig.tight_layout()
    fig.savefig(args.out / "bench_so3.png", dpi=110)
    for r in rows:
        ph = "/".join(f"{v * 1e3:.1f}" for v in r["build_phases_seconds"].values())
        print(f"N={r['N']:5d}  build {r['build_seconds'] * 1e3:7.1f} ms (stages/assembly/nlpsol "
              f"{ph})  solve {r['solve_seconds'] * 1e3:8.2f} ms  iterations {r['iterations']:2d}"
              f"  {r['status']}")
    for r in (first, last):
        fl = r["casadi_floor_seconds"]
        print(f"N={r['N']:5d}  CasADi floor {fl['total'] * 1e3:6.1f} ms: " + ", ".join(
            f"{k} {fl[k] * 1e3:.2f}" for k in ("nlpsol", "map", "sparsity", "index"))
            + f" ms ({fl['derivative_entries']} derivative entries)")
    print(f"ratios: {ratios}; written {path}")


if __name__ == "__main__":
    main()
