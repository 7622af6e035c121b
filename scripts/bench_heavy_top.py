"""heavy_top: times, iterations and accuracy vs N for both rules of the top equations.

The seed's midpoint rule and the Lie-Poisson rule (exact discrete Casimir), multi-start at
N = 32 ... 256 and continued from the N = 256 solution to 512 and 1024. Writes
results/bench_heavy_top.json and results/bench_heavy_top.png: build and IPOPT times, iterations,
replay terminal errors and cost differences with their observed orders, the drift of the
Casimir Pi . Gamma at the nodes and of the discrete Casimir, and the local minima met.
"""

from __future__ import annotations

import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import NullLocator  # noqa: E402

import ocgroupoid as og  # noqa: E402
from ocgroupoid.bench.record import write_summary  # noqa: E402
from ocgroupoid.bench.reference import extrapolated  # noqa: E402
from ocgroupoid.bench.script import arguments, rounded, steps  # noqa: E402
from ocgroupoid.bench.timing import median_seconds  # noqa: E402
from ocgroupoid.solve import interpolate  # noqa: E402
from ocgroupoid.systems.heavy_top import discrete_casimir, heavy_top  # noqa: E402
from ocgroupoid.verify.richardson import observed_orders  # noqa: E402

RESULTS = Path(__file__).resolve().parent.parent / "results"
RULES = ("midpoint", "lie_poisson")


def row(solver: og.CompiledProblem, sol: og.Solution, seconds: float, repeats: int) -> dict:
    """Figures of one solve; the IPOPT time is the median of re-solves from the same start."""
    tr = solver.transcription
    best = sol.discretization.get("start")  # the label of the start that won
    guess = next((g for g in solver.guesses(tr, sol.p, True) if g.label == best), None)
    ipopt_seconds = median_seconds(lambda: tr.solve(guess, sol.p), repeats)[0] if guess else \
        sol.solve_seconds
    d = sol.diagnostics
    rep = d["replay"]["terminal_error"]
    C = discrete_casimir(tr, sol.x, sol.p) if sol.discretization["rule"] == "lie_poisson" \
        else None
    return {"N": sol.N, "status": sol.status, "cost": sol.cost, "iterations": sol.iterations,
            "build_seconds": sol.build_seconds, "solve_seconds": sol.solve_seconds,
            "ipopt_seconds_median": ipopt_seconds, "total_seconds": seconds,
            "replay_error_Gamma": rep["Gamma"],
            "replay_error_velocity": float(np.hypot(rep["Omega"], rep["dtheta"])),
            "euler_lagrange_residual_max": d["euler_lagrange_residual_max"],
            "manifold_distance": d["manifold_distance"]["Gamma"],
            "casimir_drift_nodes": d["conserved_drift"]["Pi.Gamma"],
            "discrete_casimir_drift": float(np.ptp(C)) if C is not None else None,
            "start": sol.discretization.get("start"),
            "minima": [(m["cost"], m["label"]) for m in sol.minima]}


def main() -> None:
    args = arguments(__doc__.splitlines()[0], RESULTS)
    Ns = [32, 64] if args.quick else [32, 64, 128, 256]
    fine = [128] if args.quick else [512, 1024]
    repeats = 1 if args.quick else 5
    pb = heavy_top()
    table: dict[str, dict] = {}
    with steps(len(RULES) * (len(Ns) + len(fine))) as step:
        for rule in RULES:
            rows, prev = [], None
            for N in [*Ns, *fine]:
                step(f"{rule} N={N}")
                t0 = time.perf_counter()
                solver = og.compile_problem(pb, N=N, rule=rule)
                if N in Ns:
                    sol = solver.solve(multistart=True)
                else:
                    sol = solver.solve(guess=interpolate(prev[0].transcription, prev[1].x,
                                                         prev[1].p, N))
                seconds = time.perf_counter() - t0
                rows.append(row(solver, sol, seconds, repeats if N in Ns else 1))
                prev = (solver, sol)
            costs = [r["cost"] for r in rows]
            table[rule] = {
                "rows": rows,
                "replay_order_Gamma": observed_orders([r["replay_error_Gamma"] for r in rows]),
                "replay_order_velocity": observed_orders([r["replay_error_velocity"]
                                                          for r in rows]),
                "cost_order": observed_orders(np.abs(np.diff(costs)).tolist()),
                "casimir_order": observed_orders([r["casimir_drift_nodes"] for r in rows]),
                "cost_richardson": extrapolated(costs[-2], costs[-1], 2)}
    allN = [*Ns, *fine]
    data = {"problem": "heavy_top_rotors", "T": 3.0, "Ns_multistart": Ns, "Ns_continued": fine,
            "rules": list(RULES), "results": table,
            "note": "2 cores shared with other jobs: times are indicative"}
    path = write_summary(args.out / "bench_heavy_top.json", data)

    fig, ax = plt.subplots(1, 4, figsize=(17, 4))
    style = {"midpoint": "o-", "lie_poisson": "s--"}
    for rule, res in table.items():
        rows = res["rows"]
        ax[0].loglog(allN, [r["build_seconds"] * 1e3 for r in rows], style[rule],
                     label=f"build, {rule}")
        ax[0].loglog(allN, [r["ipopt_seconds_median"] * 1e3 for r in rows], style[rule],
                     label=f"IPOPT, {rule}")
        ax[1].semilogx(allN, [r["iterations"] for r in rows], style[rule], label=rule)
        ax[2].loglog(allN, [r["replay_error_Gamma"] for r in rows], style[rule],
                     label=f"Gamma, {rule}")
        ax[2].loglog(allN, [r["replay_error_velocity"] for r in rows], style[rule],
                     label=f"(Omega1,2, dtheta), {rule}")
        ax[3].loglog(allN, [r["casimir_drift_nodes"] for r in rows], style[rule],
                     label=f"Pi.Gamma at nodes, {rule}")
    lp = [max(r["discrete_casimir_drift"], 1e-16) for r in table["lie_poisson"]["rows"]]
    ax[3].loglog(allN, lp, "k^-", label="discrete Casimir, lie_poisson")
    ref = table["midpoint"]["rows"][0]["replay_error_velocity"]
    ax[2].loglog(allN, [ref * (allN[0] / n) ** 2 for n in allN], "k:", label="h^2")
    titles = ("build and IPOPT time [ms]", "IPOPT iterations", "replay terminal error",
              "Casimir drift (max - min)")
    for a, title in zip(ax, titles):
        a.set_xlabel("N")
        a.set_xticks(allN, [str(n) for n in allN])
        a.xaxis.set_minor_locator(NullLocator())
        a.set_title(title)
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=7)
    fig.suptitle(f"heavy_top_rotors: multi-start N = {Ns}, continued to {fine}")
    fig.tight_layout()
    fig.savefig(args.out / "bench_heavy_top.png", dpi=110)

    for rule, res in table.items():
        print(f"{rule}: replay orders Gamma {rounded(res['replay_order_Gamma'])}, "
              f"velocity {rounded(res['replay_order_velocity'])}, cost orders "
              f"{rounded(res['cost_order'])}, extrapolated cost "
              f"{res['cost_richardson']:.7f}")
        for r in res["rows"]:
            dc = r["discrete_casimir_drift"]
            print(f"   N={r['N']:5d} {r['status']} cost {r['cost']:.10f} it {r['iterations']:3d} "
                  f"build {r['build_seconds'] * 1e3:6.1f} ms IPOPT "
                  f"{r['ipopt_seconds_median'] * 1e3:7.1f} ms total {r['total_seconds']:5.2f} s "
                  f"replay {r['replay_error_Gamma']:.2e}/{r['replay_error_velocity']:.2e} "
                  f"EL {r['euler_lagrange_residual_max']:.1e} Casimir "
                  f"{r['casimir_drift_nodes']:.2e}" + (f" discrete {dc:.1e}" if dc is not None
                                                       else "")
                  + f" minima {[round(c, 4) for c, _ in r['minima']]}")
    print(f"written {path}")


if __name__ == "__main__":
    main()
