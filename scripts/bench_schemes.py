"""Work-precision of the schemes: IPOPT time against cost error and against replay error,
order2 and order4, N = 8 ... 512, for every problem file; RK4 multiple shooting on unit
quaternions (scripts/_shooting.py, as a rockit user writes it) beside them where it applies.

Every time is IPOPT's, median over repeated solves from a cold start that carries the same
information for every method: for single-minimum problems our geodesic guess (the shooting:
the slerp with its constant rate and zero controls); for problems with several minima the
guess of the start that wins the file's multi-start (on grids up to 64 it is re-chosen at each
N; finer grids use the winning label), whose path the shooting gets as its initial path.
The cost reference is order4 at N = 1024 (64 with --quick) reached from the best minimum,
Richardson-extrapolated with N/2 (error estimate stored). Ratios at equal accuracy: for each
accuracy the shooting reaches at some N, the time order4 needs for it (log-log
interpolation between its grids; when order4's coarsest grid is already more accurate, its
time there, and the ratio is a lower bound) against the shooting's time. Writes
results/bench_schemes.json and results/bench_schemes.png.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import matplotlib  # noqa: E402
import numpy as np  # noqa: E402

matplotlib.use("Agg")
import _shooting  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
from _bench import arguments, progress, save  # noqa: E402

import ocgroupoid as og  # noqa: E402
from ocgroupoid import files  # noqa: E402
from ocgroupoid.solve import interpolate  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SCHEMES = ("order2", "order4")
SHOOTING = {"so3_rest_to_rest": "rigid_body", "custom_rigid_body": "rigid_body",
            "plate_ball": "plate_ball", "plate_ball_rotating": "plate_ball"}


def refine(pb: og.Problem, scheme: str, Ns: list[int], multistart: bool, repeats: int,
           rule: str) -> list[dict]:
    """One row per N: cost, replay error, iterations, median IPOPT seconds from the start's
    cold guess, and that guess (interval velocities) for the shooting."""
    rows, label = [], None
    for N in Ns:
        solver = og.compile(pb, N=N, scheme=scheme, rule=rule if scheme == "order2" else
                            "midpoint")
        tr = solver.transcription
        p = tr.pack()
        if multistart and N <= 64:
            label = solver.solve(multistart=True, replay=False).discretization["start"]
        guesses = solver.guesses(tr, p, multistart)
        guess = next(g for g in guesses if g.label == label) if label else guesses[0]
        sol = solver.solve(guess=guess)
        times = [tr.solve(guess, p).solve_seconds for _ in range(repeats)]
        rep = sol.diagnostics.get("replay", {})
        rows.append({"N": N, "cost": sol.cost, "status": sol.status, "iterations": sol.iterations,
                     "start": guess.label, "ipopt_seconds": statistics.median(times),
                     "replay_error": rep.get("max_terminal_error"),
                     "euler_lagrange_residual": sol.diagnostics["euler_lagrange_residual_max"],
                     "build_seconds": tr.build_seconds, "guess": guess.xi})
    return rows


def reference(pb: og.Problem, N: int, multistart: bool) -> dict:
    """order4 at N and N/2, continued from the best minimum of N/16, Richardson (order 4)."""
    solver = og.compile(pb, N=N // 16, scheme="order4")
    sol = solver.solve(multistart=multistart, replay=False)
    costs = []
    for n in (N // 4, N // 2, N):
        guess = interpolate(solver.transcription, sol.x, sol.p, n)
        solver = og.compile(pb, N=n, scheme="order4")
        sol = solver.solve(guess=guess, replay=False)
        costs.append(sol.cost)
    coarse, fine = costs[-2], costs[-1]
    return {"cost": fine + (fine - coarse) / 15, "estimate": abs(fine - coarse) / 15,
            "method": f"order4 at N={N} and N={N // 2}, Richardson (order 4)"}


def shooting(name: str, cfg: files.Config, Ns: list[int], repeats: int,
             starts: dict[int, np.ndarray]) -> list[dict]:
    """The baseline at every N; ``starts`` holds our winning guesses (for the path)."""
    rows = []
    T = cfg.file.horizon.T
    for N in Ns:
        if SHOOTING[name] == "rigid_body":
            prm = cfg.parameters
            b = _shooting.rigid_body(N, prm.inertia, cfg.file.horizon.T, cfg.final.R)
            z0 = np.array([1.0, 0, 0, 0, 0, 0, 0])
        else:
            prm = cfg.parameters
            path = np.vstack([cfg.initial.xy, cfg.initial.xy + np.cumsum(
                starts[N][:, :2] * T / N, axis=0)])  # the positions of our winning guess
            b = _shooting.plate_ball(N, prm.r, prm.Omega_p, prm.c, T, cfg.final.xy,
                                     cfg.final.R, path)
            z0 = np.array([0, 0, 1.0, 0, 0, 0])
        runs = [b.solve() for _ in range(repeats)]
        r = runs[-1]
        rows.append({"N": N, "cost": r["cost"], "status": r["status"],
                     "iterations": r["iterations"],
                     "ipopt_seconds": statistics.median(x["seconds"] for x in runs),
                     "replay_error": b.replay(r["controls"], z0) if r["success"] else None})
    return rows


def time_at(rows: list[dict], key: str, target: float) -> tuple[float | None, bool]:
    """Seconds the rows' method needs for error ``target`` (log-log interpolation between
    its grids), and whether that is an upper bound: its coarsest grid is already more
    accurate than the target (its time there)."""
    pts = sorted((r[key], r["ipopt_seconds"]) for r in rows if r.get(key))
    if not pts or target < pts[0][0]:
        return None, False
    if target > pts[-1][0]:
        return pts[-1][1], True
    e, t = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
    return float(np.exp(np.interp(np.log(target), e, t))), False


def main() -> None:
    args = arguments(__doc__.splitlines()[0])
    Ns = [8, 16, 32] if args.quick else [8, 16, 32, 64, 128, 256, 512]
    N_ref, repeats = (64, 1) if args.quick else (1024, 5)
    problems = sorted((ROOT / "problems").glob("*.yaml"))
    if args.quick:
        problems = [p for p in problems if p.stem in ("so3_rest_to_rest", "plate_ball_rotating")]
    out: dict = {"Ns": Ns, "problems": {}}
    with progress() as bar:
        task = bar.add_task("schemes", total=len(problems) * (len(SCHEMES) + 2))
        for path in problems:
            name = path.stem
            cfg = files.load(path)
            pb = files.build(cfg)
            multistart = bool(cfg.file.solver.multistart)
            rule = cfg.file.discretization.rule
            bar.update(task, description=f"{name}: reference")
            res: dict = {"reference": reference(pb, N_ref, multistart)}
            bar.advance(task)
            for scheme in SCHEMES:
                bar.update(task, description=f"{name}: {scheme}")
                res[scheme] = refine(pb, scheme, Ns, multistart, repeats, rule)
                bar.advance(task)
            if name in SHOOTING:
                bar.update(task, description=f"{name}: RK4 shooting")
                starts = {r["N"]: r["guess"] for r in res["order4"]}
                res["rk4_shooting"] = shooting(name, cfg, Ns, repeats, starts)
            bar.advance(task)
            J = res["reference"]["cost"]
            for method in [*SCHEMES, "rk4_shooting"]:
                for r in res.get(method, []):
                    r["cost_error"] = abs(r["cost"] - J) / abs(J)
            if "rk4_shooting" in res:
                res["ratios"] = {key: [
                    {"N": r["N"], "accuracy": r[key], "rk4_shooting_seconds": r["ipopt_seconds"],
                     "order4_seconds": t, "speedup": r["ipopt_seconds"] / t if t else None,
                     "lower_bound": bound}
                    for r in res["rk4_shooting"] if r.get(key)
                    for t, bound in [time_at(res["order4"], key, r[key])]]
                    for key in ("cost_error", "replay_error")}
            for rows in (res["order2"], res["order4"]):
                for r in rows:
                    del r["guess"]
            out["problems"][name] = res
    out["created"] = time.strftime("%Y-%m-%d %H:%M:%S")
    json_path = save(args.out, "bench_schemes", out)
    plot(out, args.out / "bench_schemes.png")
    for name, res in out["problems"].items():
        print(f"{name}: reference J = {res['reference']['cost']:.12g} "
              f"(+-{res['reference']['estimate']:.1e})")
        for method in [*SCHEMES, "rk4_shooting"]:
            for r in res.get(method, []):
                rep = r.get("replay_error")
                print(f"  {method:13s} N={r['N']:4d} {r['ipopt_seconds'] * 1e3:8.1f} ms "
                      f"it {r['iterations']:3d} cost err {r['cost_error']:.2e} replay "
                      f"{rep if rep is None else format(rep, '.2e')}")
        for key, rows in res.get("ratios", {}).items():
            print(f"  speed-up of order4 over RK4 shooting at equal {key}: " + ", ".join(
                (f"N={r['N']}: {'>=' if r['lower_bound'] else ''}{r['speedup']:.1f}x"
                 if r["speedup"] else f"N={r['N']}: -") for r in rows))
    print(f"written {json_path}")


def plot(out: dict, path: Path) -> None:
    names = list(out["problems"])
    fig, axes = plt.subplots(len(names), 2, figsize=(11, 3.4 * len(names)), squeeze=False)
    styles = {"order2": ("tab:blue", "o-"), "order4": ("tab:green", "s-"),
              "rk4_shooting": ("tab:red", "^--")}
    labels = {"order2": "ours, order2", "order4": "ours, order4",
              "rk4_shooting": "RK4 shooting (quaternions)"}
    for ax_row, name in zip(axes, names):
        res = out["problems"][name]
        for ax, key, what in zip(ax_row, ("cost_error", "replay_error"),
                                 ("relative cost error", "replay terminal error")):
            for method, (color, style) in styles.items():
                rows = [r for r in res.get(method, []) if r.get(key)]
                if rows:
                    ax.loglog([r[key] for r in rows], [r["ipopt_seconds"] for r in rows],
                              style, color=color, ms=4, label=labels[method])
                    for r in rows[:: max(1, len(rows) // 3)]:
                        ax.annotate(f"N={r['N']}", (r[key], r["ipopt_seconds"]), fontsize=6,
                                    color=color, xytext=(3, 3), textcoords="offset points")
            ax.set_xlabel(what)
            ax.set_ylabel("IPOPT seconds (median)")
            ax.set_title(f"{name}: time against {what}", fontsize=9)
            ax.invert_xaxis()
            ax.grid(alpha=0.3, which="both")
            ax.legend(fontsize=7)
    fig.suptitle("Work-precision: further right is more accurate, lower is faster")
    fig.tight_layout(rect=(0, 0, 1, 0.985))
    fig.savefig(path, dpi=100)


if __name__ == "__main__":
    main()
