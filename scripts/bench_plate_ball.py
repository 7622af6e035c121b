"""plate_ball: accuracy of the discretisation rules (rule x N -> replay error, cost, time).

Both instances (Omega_p = 0 and 1) under the Cayley and exp retractions and the seed's
first-order read-out (seed 001, eq. 8), multi-start at every N. Writes
results/bench_plate_ball.json and results/bench_plate_ball.png: replay terminal errors and
cost differences with their observed orders, IPOPT iterations and times, the local minima
met, and the paths of the two mirror-image minima of the fixed plate.
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
from ocgroupoid.nlp import RawResult  # noqa: E402
from ocgroupoid.solve import distinct_minima, make_solution  # noqa: E402
from ocgroupoid.systems.plate_ball import plate_ball  # noqa: E402
from ocgroupoid.verify.richardson import observed_orders  # noqa: E402

RESULTS = Path(__file__).resolve().parent.parent / "results"
OMEGAS = (0.0, 1.0)


def run(pb: og.Problem, N: int, rule: str) -> tuple[og.Solution, list[RawResult], float]:
    """Multi-start as ``CompiledProblem.solve(multistart=True)`` does, keeping every start's
    result."""
    solver = og.compile_problem(pb, N=N, retraction=rule)
    tr = solver.transcription
    p = tr.pack()
    t0 = time.perf_counter()
    results = [tr.solve(g, p) for g in solver.guesses(tr, p, True)]
    seconds = time.perf_counter() - t0
    best = min(results, key=lambda r: (not r.success, r.cost))
    return make_solution(tr, best, distinct_minima(results)), results, seconds


def row(sol: og.Solution, results: list[RawResult], seconds: float) -> dict:
    d = sol.diagnostics
    return {"N": sol.N, "cost": sol.cost, "status": sol.status,
            "replay_error": d["replay"]["max_terminal_error"],
            "replay_error_xy": d["replay"]["terminal_error"]["xy"],
            "replay_error_R": d["replay"]["terminal_error"]["R"],
            "euler_lagrange_residual_max": d["euler_lagrange_residual_max"],
            "final_residual_max": max(d["final_residual"].values()),
            "iterations": sol.iterations, "start": sol.discretization["start"],
            "solve_seconds": sol.solve_seconds, "multistart_seconds": seconds,
            "build_seconds": sol.build_seconds,
            "minima": [(m["cost"], m["label"]) for m in sol.minima],
            "starts": [{"label": r.label, "status": r.status, "cost": r.cost,
                        "iterations": r.iterations, "seconds": r.solve_seconds}
                       for r in results]}


def main() -> None:
    args = arguments(__doc__.splitlines()[0], RESULTS)
    Ns = [32, 64, 128] if args.quick else [32, 64, 128, 256, 512]
    rules = ["cayley", "first_order"] if args.quick else ["cayley", "exp", "first_order"]
    table: dict[str, dict[str, dict]] = {}
    with steps(len(OMEGAS) * len(rules) * len(Ns)) as step:
        for Om in OMEGAS:
            pb = plate_ball(Omega_p=Om)
            inst = table.setdefault(f"Omega_p={Om:g}", {})
            for rule in rules:
                rows = []
                for N in Ns:
                    step(f"Omega_p={Om:g} {rule} N={N}")
                    sol, results, seconds = run(pb, N, rule)
                    rows.append(row(sol, results, seconds))
                    if Om == 0.0 and rule == "cayley" and N == Ns[-1]:
                        tr = og.compile_problem(pb, N=N).transcription
                        pair = [tr.unpack(r.x, r.p)["s"][:, :2] for m in sol.minima[:2]
                                for r in results if r.label == m["label"]]
                costs = [r["cost"] for r in rows]
                inst[rule] = {"rows": rows,
                              "replay_order": observed_orders([r["replay_error"]
                                                               for r in rows]),
                              "cost_order": observed_orders(np.abs(np.diff(costs)).tolist()),
                              "cost_richardson": extrapolated(costs[-2], costs[-1], 2)}
    data = {"problem": "plate_ball", "T": 1.0, "Ns": Ns, "rules": rules, "instances": table,
            "note": "2 cores shared with other jobs: times are indicative"}
    path = write_summary(args.out / "bench_plate_ball.json", data)

    fig, ax = plt.subplots(1, 4, figsize=(17, 4))
    styles = {"cayley": "o-", "exp": "^-", "first_order": "s--"}
    for (inst, res), color in zip(table.items(), ("C0", "C3")):
        for rule, r in res.items():
            lbl = f"{rule}, {inst}"
            ax[0].loglog(Ns, [x["replay_error"] for x in r["rows"]], styles[rule], color=color,
                         label=lbl)
            ax[1].loglog(Ns[:-1], np.abs(np.diff([x["cost"] for x in r["rows"]])), styles[rule],
                         color=color, label=lbl)
            ax[2].semilogx(Ns, [np.median([s["iterations"] for s in x["starts"]])
                                for x in r["rows"]], styles[rule], color=color, label=lbl)
    ref = table["Omega_p=0"]["cayley"]["rows"][0]["replay_error"]
    ax[0].loglog(Ns, [ref * (Ns[0] / n) ** 2 for n in Ns], "k:", label="h^2")
    for a, title in zip(ax[:3], ("replay terminal error", "|J_N - J_2N|",
                                 "IPOPT iterations (median of starts)")):
        a.set_xlabel("N")
        a.set_xticks(Ns, [str(n) for n in Ns])
        a.xaxis.set_minor_locator(NullLocator())
        a.set_title(title)
        a.grid(alpha=0.3, which="both")
    ax[0].legend(fontsize=7)
    for xy, style in zip(pair, ("-", "--")):
        ax[3].plot(xy[:, 0], xy[:, 1], style)
    ax[3].plot([0, 1], [0, 0.5], "k:", lw=0.8)
    ax[3].set_aspect("equal")
    ax[3].set_title(f"mirror minima, Omega_p=0, N={Ns[-1]}")
    fig.suptitle("plate_ball: discretisation rules, replay error and cost convergence")
    fig.tight_layout()
    fig.savefig(args.out / "bench_plate_ball.png", dpi=110)

    for inst, res in table.items():
        for rule, r in res.items():
            print(f"{inst} {rule}: replay orders {rounded(r['replay_order'])}, "
                  f"cost orders {rounded(r['cost_order'])}, "
                  f"extrapolated cost {r['cost_richardson']:.7f}")
            for x in r["rows"]:
                print(f"   N={x['N']:4d} cost {x['cost']:.9f} replay {x['replay_error']:.3e} "
                      f"EL {x['euler_lagrange_residual_max']:.1e} it {x['iterations']:3d} "
                      f"solve {x['solve_seconds'] * 1e3:7.1f} ms multistart "
                      f"{x['multistart_seconds']:.2f} s, iterations of the starts "
                      f"{[s['iterations'] for s in x['starts']]}, minima "
                      f"{[round(c, 5) for c, _ in x['minima']]}")
    print(f"written {path}")


if __name__ == "__main__":
    main()
