"""The benchmark pages' tables, rendered from the summaries in ``docs/benchmarks/data``
(written by :mod:`docsgen.extract`). Nothing is solved or downloaded here."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any, Callable

DATA = Path(__file__).resolve().parent.parent / "docs" / "benchmarks" / "data"
#: the landing accuracies of the best configurations' tables, as docsgen.extract keys them
LANDING_LEVELS = ("1e-04", "1e-06", "1e-08")
#: the outcome of a stability cell, as one mark
MARKS = {"converged": "✓", "unverified": "u", "off group": "g", "off target": "t",
         "other minimum": "m", "failed": "✗"}


def _csv(name: str) -> list[dict[str, str]]:
    with (DATA / name).open() as f:
        return list(csv.DictReader(f))


def _json(name: str) -> Any:
    return json.loads((DATA / name).read_text())


def table(header: list[str], rows: list[list[Any]]) -> str:
    """A Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def _ratio(h: dict[str, Any] | None, name: bool = True, level: bool = True) -> str:
    """``1e-4: 14.0x (order4)``; ``≥`` for a lower bound (ours more accurate on every grid,
    or the baseline on none); without the level where the column names it."""
    if not h:
        return "-"
    bound = "≥ " if h["lower_bound"] else ""
    return (f"{h['level']:.0e}: " if level else "") + f"{bound}{h['ratio']:.1f}x" + \
        (f" ({h['ours']})" if name else "")


def headlines() -> str:
    """Time of RK4 shooting over our fastest method at equal accuracy, per problem file."""
    d = _json("work_precision.json")
    rows = [[f"`{p}`", _ratio(e["schemes"]["cost_error"]), _ratio(e["schemes"]["replay_error"])]
            for p, e in d.items() if "schemes" in e]
    return table(["problem", "equal cost accuracy", "equal landing (replay) accuracy"], rows)


def best_headlines() -> str:
    """The same for the best configurations (backends, jit), against rk4_quat with and
    without compiled evaluation; landing against rk4_quat+jit at 1e-4, 1e-6 and 1e-8; the
    day each file's run was measured (files are run again one by one)."""
    d = _json("work_precision.json")
    rows = []
    for p, e in d.items():
        best = e.get("best")
        if not best:
            continue
        jit = best.get("vs_jit", {})
        landing = best.get("landing_vs_jit", {})
        rows.append([f"`{p}`", _ratio(best["cost_error"]),
                     _ratio(jit.get("cost_error"), name=False), _ratio(best["replay_error"]),
                     *(_ratio(landing.get(lv), name=False, level=False) for lv in LANDING_LEVELS),
                     str(best.get("created") or "")[:10]])
    return table(["problem", "cost: vs rk4_quat", "cost: vs rk4_quat+jit",
                  "landing: vs rk4_quat", *(f"landing {level.replace('e-0', 'e-')}: vs "
                                            "rk4_quat+jit" for level in LANDING_LEVELS),
                  "measured"], rows)


def best_coarse_headlines() -> str:
    """Landing of the best configurations against the shooting compiled and solved on N/4
    first (``rk4_quat+jit+coarse``), at 1e-4, 1e-6 and 1e-8, with our fastest named; the
    files whose best run had no such baseline are left out."""
    d = _json("work_precision.json")
    rows = [[f"`{p}`", *(_ratio(e["best"]["landing_vs_jit_coarse"].get(lv), level=False)
                         for lv in LANDING_LEVELS)]
            for p, e in d.items() if e.get("best", {}).get("landing_vs_jit_coarse")]
    return table(["problem", *(f"landing {level.replace('e-0', 'e-')}: vs rk4_quat+jit+coarse"
                               for level in LANDING_LEVELS)], rows)


def _iterations(row: dict[str, str]) -> str:
    """A row's iterations: every run's, and who ran when it was more than one backend
    (``163: ipopt polish after fatrop``); rows measured before runs were counted give the
    last run's."""
    every, who = row.get("iterations_all") or row["iterations"], row.get("backend", "")
    return f"{every}: {who}" if " after " in who else every


def work_precision_rows() -> str:
    """Every solve of the work-precision runs, one collapsible table per problem file."""
    out = []
    for path in sorted((DATA / "work_precision").glob("*.csv")):
        rows = _csv(f"work_precision/{path.name}")
        body = table(["run", "method", "N", "verified", "iterations", "solve s",
                      "cost error", "replay error"],
                     [[r["run"], f"`{r['method']}`", r["N"],
                       "yes" if r["success"] == "True" else "no", _iterations(r),
                       r["seconds"], r["cost_error"], r["replay_error"]] for r in rows])
        out.append(f'??? note "`{path.stem}`: {len(rows)} solves"\n\n'
                   + "\n".join("    " + line for line in body.splitlines()) + "\n")
    return "\n".join(out)


def stability() -> str:
    """The so3 stability map: one table per method, slew angle against N."""
    cells = _csv("stability_so3.csv")
    Ns = sorted({int(c["N"]) for c in cells})
    out = ["Marks: " + ", ".join(f"{m} {k}" for k, m in MARKS.items()) + ".", ""]
    for method in dict.fromkeys(c["method"] for c in cells):
        mine = {(c["angle"], int(c["N"])): c["outcome"] for c in cells if c["method"] == method}
        angles = sorted({a for a, _ in mine}, key=float)
        out += [f"**`{method}`**", "", table(["angle (rad)", *(f"N={n}" for n in Ns)], [
            [a, *(MARKS.get(mine.get((a, n), ""), "·") for n in Ns)] for a in angles]), ""]
    return "\n".join(out)


def so3_build() -> str:
    """Build and solve times of the so3 slew, ours against CasADi's own derivatives."""
    rows = [[r["N"], f"{float(r['build_ms']):.1f} ms ({float(r['stages_ms']):.1f} / "
             f"{float(r['assembly_ms']):.1f} / {float(r['nlpsol_ms']):.1f})",
             f"{float(r['solve_ms']):.1f} ms",
             f"{float(r['casadi_ad_build_ms']):.0f} / {float(r['casadi_ad_solve_ms']):.1f} ms",
             f"{float(r['casadi_ad_expand_build_ms']):.0f} / "
             f"{float(r['casadi_ad_expand_solve_ms']):.1f} ms"] for r in _csv("so3_build.csv")]
    return table(["N", "build (stage graphs / assembly / IPOPT setup)", "IPOPT solve (median)",
                  "casadi_ad build / solve", "casadi_ad_expand build / solve"], rows)


def backends() -> str:
    """Speed-up of the best configuration over IPOPT with the virtual machine."""
    rows = [[f"`{r['problem']}`", r["scheme"], r["N"], r["best"].replace("_", " "),
             f"{float(r['speedup']):.1f}x", f"{float(r['best_solve_ms']):.1f} ms"]
            for r in _csv("backends.csv")]
    return table(["problem", "scheme", "N", "best", "speed-up", "its solve"], rows)


def codegen() -> str:
    """The exported C solve against the Python solve."""
    rows = [[f"`{r['problem']}`", r["N"], f"{float(r['c_ms']):.1f} ms",
             f"{float(r['python_ms']):.1f} ms", f"{float(r['ratio']):.2f}"]
            for r in _csv("codegen.csv")]
    return table(["problem", "N", "C", "Python", "C / Python"], rows)


def drift() -> str:
    """Energy and Casimir errors over 10^5 steps."""
    rows = [[r["system"], r["quantity"], r["max_first_half"], r["max_second_half"]]
            for r in _csv("energy_drift.csv")]
    return table(["system", "quantity", "largest error, first half",
                  "largest error, second half"], rows)


def sweep() -> str:
    """A sweep of so3 points, serial against Dask."""
    d = _json("sweep.json")
    return d["what"] + "\n\n" + table(["run", "points/s", "NLPs built", "solved"], [
        ["serial loop", f"{d['serial']['points_per_second']:.1f}", d["serial"]["nlps_built"],
         d["serial"]["solved"]],
        [f"Dask, {d['cores']} cores", f"{d['dask']['points_per_second']:.1f} "
         f"({d['dask']['points_per_second_with_startup']:.1f} with start-up)",
         d["dask"]["nlps_built"], d["dask"]["solved"]]]) + \
        f"\n\nLargest cost difference between the two: {d['max_cost_difference']:g}."


def rockit() -> str:
    """so3: rockit's time over ours at equal landing accuracy, then both lines."""
    d = _json("rockit.json")

    def ratio(v: float | None) -> str:
        return "-" if v is None else f"{v:.1f}x"

    head = table(["landing error", "ours", "rockit", "rockit / ours",
                  "rockit's IPOPT time alone / ours"],
                 [[f"{r['level']:.0e}", f"{1e3 * r['ours_seconds']:.2f} ms",
                   f"{1e3 * r['rockit_seconds']:.2f} ms", ratio(r["ratio"]),
                   ratio(r["ratio_ipopt_only"])] for r in d["equal_landing"]
                  if r["ours_seconds"] and r["rockit_seconds"]])
    lines = table(["N", *(f"{name}: {what}" for name in ("ours", "rockit")
                          for what in ("time", "iterations", "landing error"))],
                  [[a["N"], f"{1e3 * a['seconds']:.2f} ms", a["iterations"],
                    f"{a['landing_error']:.1e}", f"{1e3 * b['seconds']:.2f} ms",
                    b["iterations"], f"{b['landing_error']:.1e}"]
                   for a, b in zip(d["lines"]["ours"], d["lines"]["rockit"])])
    return (f"Measured {d['created']} (load average {d['load_average_1min']} on 2 cores), "
            f"ours `{d['ours_method']}`:\n\n{head}\n\n{lines}")


#: the markers a page may hold, ``<!-- generated: NAME -->``, and what fills them
RENDERERS: dict[str, Callable[[], str]] = {
    "bench-headlines": headlines, "bench-best-headlines": best_headlines,
    "bench-best-coarse-headlines": best_coarse_headlines,
    "bench-work-precision-rows": work_precision_rows, "bench-stability": stability,
    "bench-so3-build": so3_build, "bench-backends": backends, "bench-codegen": codegen,
    "bench-drift": drift, "bench-sweep": sweep, "bench-rockit": rockit}
