"""The table ``ocgroupoid solve`` prints after a solve, and the line of each grid of
``horizon.N: auto``."""

from __future__ import annotations

from typing import Any

from rich.table import Table


def summary(sol: Any) -> Table:
    """The table printed after a solve."""
    d = sol.diagnostics
    disc = sol.discretization
    t = Table(title=f"{sol.problem}  (N={sol.N}, T={sol.T:g}, {disc.get('scheme', 'order2')}, "
                    f"{disc.get('retraction')}, rule {disc.get('rule')})", show_header=False)
    t.add_column(style="bold")
    t.add_column()
    t.add_row("status", f"[{'green' if sol.success else 'red'}]{sol.status}[/]"
              + ("" if sol.success or sol.status != "Solve_Succeeded" else " (not verified)"))
    t.add_row("cost", f"{sol.cost:.12g}")
    before = d.get("runs", [])[:-1]
    t.add_row("iterations", str(sol.iterations) + (" (after " + ", ".join(
        f"{r['backend']} {r['iterations']}: {r['status']}" for r in reversed(before)) + ")"
        if before else ""))
    if "T_range" in disc:
        lo, hi = disc["T_range"]
        t.add_row("final time (free)", f"{sol.T:.10g} in [{lo:g}, {hi:g}]"
                  + (f", {disc['steps']} steps" if disc.get("steps") == "adaptive" else ""))
    t.add_row("build time", f"{sol.build_seconds * 1e3:.1f} ms")
    t.add_row("solver time, this solution", f"{sol.solve_seconds * 1e3:.1f} ms ({sol.backend})")
    runs = [f"{sol.starts} starts" if sol.starts > 1 else "",
            "grids" if d.get("continuation") or "error_estimate" in d else "",
            "a rescue through " + " and ".join(
                filter(None, [d["rescue"].get("scheme"), f"N={d['rescue']['grid']}"
                              if "grid" in d["rescue"] else ""])) if "rescue" in d else "",
            "phases" if d.get("adaptive", {}).get("used") else ""]
    if sol.ipopt_seconds_total > sol.solve_seconds * (1 + 1e-9) or sol.starts > 1:
        t.add_row("solver time, every run", f"{sol.ipopt_seconds_total * 1e3:.1f} ms ("
                  + (", ".join(filter(None, runs)) or "retries") + ")")
    if "multistart" in d:
        m = d["multistart"]
        t.add_row("multi-start", f"{m['finished']} starts on {m['workers']} worker"
                  f"{'s' if m['workers'] > 1 else ''}: {m['wall_seconds']:.2f} s wall, "
                  f"{m['sequential_seconds']:.2f} s summed over the starts, best start "
                  f"{m['best_start_seconds']:.2f} s" + (f"; {len(m['failed'])} failed in "
                                                          "their worker" if m.get("failed")
                                                          else "")
                  + (f"; {len(m['budget_spent'])} stopped by "
                     f"{'its' if len(m['budget_spent']) == 1 else 'their'} budget"
                     if m.get("budget_spent") else ""))
    t.add_row("EL residual (max over nodes)", f"{d['euler_lagrange_residual_max']:.2e}"
              if "euler_lagrange_residual_max" in d else "none: the scheme is not variational")
    t.add_row("distance from manifold",
              ", ".join(f"{k} {v:.1e}" for k, v in d["manifold_distance"].items()))
    if d["final_residual"]:
        t.add_row("final residual", ", ".join(f"{k} {v:.1e}" for k, v in
                                              d["final_residual"].items()))
    if "bound_violation_max" in d:
        active = d["bounds_active"]
        t.add_row("bounds", f"max violation {d['bound_violation_max']:.1e}; active: " + (
            ", ".join(f"{k} ({', '.join(f'{s} at {n}' for s, n in v.items())} of "
                      f"{d['bound_points']} points)" for k, v in active.items()) or "none"))
    if d.get("conserved_drift"):
        t.add_row("conserved drift (max - min)", ", ".join(
            f"{k} {v:.2e}" for k, v in d["conserved_drift"].items()))
    rep = d.get("replay", {})
    if rep.get("available"):
        t.add_row("replay terminal error", ", ".join(f"{k} {v:.2e}" for k, v in
                                                     rep["terminal_error"].items()))
    elif rep.get("reason"):
        t.add_row("replay", rep["reason"])
    if "error_estimate" in d:
        e = d["error_estimate"]
        t.add_row("error estimate (cost)", f"{e['cost_relative']:.1e} relative ({e['cost']:.2e}"
                  f"), Richardson from N={e['N'][0]} and {e['N'][1]}, order {e['order']:.2g}")
    if "accuracy" in d:
        acc = d["accuracy"]
        t.add_row("N: auto", f"{acc['message']} ({acc['ipopt_seconds']:.2f} s in IPOPT)")
        if len(acc["schemes"]) > 1:
            t.add_row("schemes tried", ", ".join(
                f"{k} {'met' if v['met'] else v['stopped']} ({v['ipopt_seconds']:.2f} s IPOPT)"
                for k, v in acc["schemes"].items()))
    if d.get("rescue", {}).get("rescued"):  # a failed rescue is told by the hint
        t.add_row("rescued", f"{d['rescue']['message']} ({d['rescue']['seconds']:.2f} s)")
    if len(sol.minima) > 1:
        grid = d.get("minima_grid")
        where = f" (of the starts, on the first grid: {grid['scheme']}, N={grid['N']})" \
            if grid else " (of the starts, before the adaptive steps)" if \
            d.get("adaptive", {}).get("used") else ""
        t.add_row("local minima" + where, ", ".join(f"{m['cost']:.6g} ({m['label']})"
                                                    for m in sol.minima))
    if sol.hint:
        t.add_row("hint", sol.hint)
    return t


def grid_line(level: Any) -> str:
    """One grid of ``N: auto``: cost, error estimate, replay error, verdict and time."""
    est = "-" if level.estimate is None else f"{level.estimate:.1e} (order {level.order:.2g})"
    replay = "-" if level.replay_error is None else f"{level.replay_error:.1e}"
    verdict = "verified" if level.verified else level.status if \
        level.status != "Solve_Succeeded" else "not verified"
    return (f"{level.scheme} N={level.N}: cost {level.cost:.10g}, estimated error {est}, "
            f"replay error {replay}, {verdict}, {level.seconds:.2f} s"
            + (" — target met" if level.met else ""))
