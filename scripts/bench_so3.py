"""so3_rest_to_rest: build time, IPOPT solve time and iterations versus N (16 ... 1024).

Writes results/bench_so3.json and results/bench_so3.png. Goals (ratios measured in this run):
build time grows at most 2x from N=16 to 1024 (one stage graph, mapped); solve time grows at
most ~20x from N=64 to 1024 (linear in N); median solve at N=64 aimed at <= 10 ms. The build
is split into its phases (stage graphs, derivative assembly, IPOPT setup), and the CasADi
calls every build of the NLP must make are timed alone at the smallest and largest N: the
floor under any build, whatever its bookkeeping.

Baselines the hand-written derivative assembly beats, on the same mapped stage graph, the
same IPOPT options and the same start: ``nlpsol`` deriving the derivatives itself with
CasADi's AD on the MX graph ("casadi_ad"), and the same with ``expand=True`` (the graph
expanded to SX first, "casadi_ad_expand"). Their build time includes our stage phase.
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import casadi as ca
import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import ocgroupoid as og  # noqa: E402
from ocgroupoid.bench.record import write_summary  # noqa: E402
from ocgroupoid.bench.script import arguments, steps  # noqa: E402
from ocgroupoid.bench.timing import median_seconds  # noqa: E402
from ocgroupoid.nlp.assembly import StageDerivatives, plain_nlp  # noqa: E402
from ocgroupoid.nlp.backends.ipopt import nlpsol_options  # noqa: E402
from ocgroupoid.nlp.transcription import Transcription  # noqa: E402
from ocgroupoid.solve import geodesic_guesses  # noqa: E402
from ocgroupoid.systems.rigid_body import rigid_body  # noqa: E402

RESULTS = Path(__file__).resolve().parent.parent / "results"


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


BASELINES = {"casadi_ad": {}, "casadi_ad_expand": {"expand": True}}


def baseline(tr: Transcription, extra: dict[str, object], x0: np.ndarray, p: np.ndarray,
             repeats: int) -> dict[str, float]:
    """Build (our stage phase + the plain NLP + nlpsol) and median solve of a baseline."""
    fns = {k: tr.solver.get_function(k) for k in ("nlp_grad_f", "nlp_jac_g", "nlp_hess_l")}
    opts = {k: v for k, v in nlpsol_options(None, fns).items() if k != "cache"}
    t0 = time.perf_counter()
    nlp = plain_nlp(tr.blocks, ca.MX.sym("x", tr.nx), ca.MX.sym("p", tr.np))
    solver = ca.nlpsol("baseline", "ipopt", nlp, {**opts, **extra})
    build = tr.build_phases["stages"] + time.perf_counter() - t0
    solve, r = median_seconds(lambda: solver(x0=x0, p=p, lbg=0, ubg=0), repeats)
    stats = solver.stats()
    return {"build_seconds": build, "solve_seconds": solve, "cost": float(r["f"]),
            "iterations": int(stats["iter_count"]), "status": str(stats["return_status"])}


def plot(path: Path, Ns: list[int], rows: list[dict]) -> None:
    """Three panels: our build and its phases; build against the baselines; IPOPT solve
    against the baselines."""
    by = {r["N"]: r for r in rows}
    fig, ax = plt.subplots(1, 3, figsize=(14, 4.2))
    ax[0].loglog(Ns, [r["build_seconds"] for r in rows], "o-", color="tab:blue", label="build")
    for k, style in (("stages", "v--"), ("assembly", "^--"), ("nlpsol", "d--")):
        ax[0].loglog(Ns, [r["build_phases_seconds"][k] for r in rows], style, ms=4, lw=0.8,
                     label=f"  {k}")
    floors = [r for r in rows if r["casadi_floor_seconds"]]
    ax[0].loglog([r["N"] for r in floors], [r["casadi_floor_seconds"]["total"] for r in floors],
                 "kx", ms=8, label="CasADi floor of any build")
    ax[0].set_title("our build and its phases")
    styles = {"ours": ("tab:blue", "o-"), "casadi_ad": ("tab:red", "s--"),
              "casadi_ad_expand": ("tab:purple", "^--")}
    for i, key in ((1, "build_seconds"), (2, "solve_seconds")):
        ax[i].loglog(Ns, [r[key] for r in rows], styles["ours"][1], color=styles["ours"][0],
                     label="ours (stage-wise derivatives)")
        for name in BASELINES:
            ax[i].loglog(Ns, [r["baselines"][name][key] for r in rows], styles[name][1],
                         color=styles[name][0], ms=4, label=name)
    ax[2].loglog(Ns, [by[Ns[len(Ns) // 2]]["solve_seconds"] * n / Ns[len(Ns) // 2] for n in Ns],
                 "k:", label="linear in N")
    ax[1].set_title("build: ours and CasADi's AD")
    iters = sorted({r["iterations"] for r in rows})
    ax[2].set_title(f"IPOPT solve (median; {'/'.join(map(str, iters))} iterations at every N)")
    for a in ax:
        a.set_xlabel("N")
        a.set_ylabel("seconds")
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=7)
    fig.suptitle("so3_rest_to_rest (Cayley, order2): time versus N")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], RESULTS)
    Ns = [16, 32, 64] if args.quick else [16, 32, 64, 128, 256, 512, 1024]
    repeats = 3 if args.quick else 15
    pb = rigid_body()
    rows = []
    with steps(len(Ns) * (2 + len(BASELINES))) as step:
        for N in Ns:
            step(f"N={N}: build")
            builds = [og.compile_problem(pb, N=N).transcription
                      for _ in range(1 if args.quick else 3)]
            build = statistics.median(b.build_seconds for b in builds)
            phases = {k: statistics.median(b.build_phases[k] for b in builds)
                      for k in builds[0].build_phases}
            tr = builds[-1]
            p = tr.pack()
            guess = geodesic_guesses(tr, p)[0]
            step(f"N={N}: solve x{repeats}")
            solve, raw = median_seconds(lambda: tr.solve(guess, p), repeats)  # noqa: B023 (called here)
            floor = casadi_floor(tr, 3) if N in (Ns[0], Ns[-1]) else None
            base = {}
            for name, extra in BASELINES.items():
                step(f"N={N}: baseline {name}")
                base[name] = baseline(tr, extra, tr.point(guess, p), p, repeats)
            rows.append({"N": N, "build_seconds": build, "build_phases_seconds": phases,
                         "casadi_floor_seconds": floor, "solve_seconds": solve,
                         "iterations": raw.iterations, "status": raw.status, "cost": raw.cost,
                         "baselines": base})
    by = {r["N"]: r for r in rows}
    ratios = {"build_1024_over_16": by[1024]["build_seconds"] / by[16]["build_seconds"]
              if 1024 in by else None,
              "solve_1024_over_64": by[1024]["solve_seconds"] / by[64]["solve_seconds"]
              if 1024 in by else None}
    last_N = Ns[-1]
    for name in BASELINES:  # how much the hand-written assembly saves, at the largest N
        b = by[last_N]["baselines"][name]
        ratios[f"{name}_build_over_ours_N{last_N}"] = b["build_seconds"] / \
            by[last_N]["build_seconds"]
        ratios[f"{name}_solve_over_ours_N{last_N}"] = b["solve_seconds"] / \
            by[last_N]["solve_seconds"]
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
            "median_solve_ms_N512": by[512]["solve_seconds"] * 1e3 if 512 in by else None}
    path = write_summary(args.out / "bench_so3.json", data)
    plot(args.out / "bench_so3.png", Ns, rows)
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
    for r in rows:
        print(f"N={r['N']:5d}  baselines: " + "; ".join(
            f"{k} build {b['build_seconds'] * 1e3:.1f} ms, solve {b['solve_seconds'] * 1e3:.2f} ms"
            f" ({b['iterations']} it, |dJ| {abs(b['cost'] - r['cost']):.1e})"
            for k, b in r["baselines"].items()))
    print(f"ratios: {ratios}; written {path}")


if __name__ == "__main__":
    main()
