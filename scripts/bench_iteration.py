"""Where the time of one iteration goes (issue 26), on every problem file and both backends.

Per problem file (its own scheme and N) and backend (IPOPT; fatrop), one solve from the first
geodesic guess (the backend's CasADi solver called directly: no fallback), timed by CasADi's
own counters (``solver.stats()``): the wall time of the
function evaluations IPOPT or fatrop asked for (objective, constraints, gradient, constraint
Jacobian, Hessian of the Lagrangian: ``t_wall_nlp_*``), the rest of the solver's time (the KKT
factorisations and solves — MUMPS for IPOPT, fatrop's stage-wise Riccati — and the method's
own linear algebra), and the Python around the call (our wall time minus the solver's). Each
divided by the iterations, in milliseconds. The median of :data:`REPEATS` solves per row.

Writes ``bench_iteration.json`` and ``bench_iteration.png`` (stacked bars per file and backend).
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ocgroupoid import files  # noqa: E402
from ocgroupoid.bench.record import write_summary  # noqa: E402
from ocgroupoid.bench.script import arguments, steps  # noqa: E402
from ocgroupoid.solve import compile_problem  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
PROBLEMS = ROOT / "problems"
#: CasADi's counters of the evaluations, by what they evaluate
EVALUATIONS = {"nlp_f": "objective", "nlp_g": "constraints", "nlp_grad_f": "gradient",
               "nlp_jac_g": "Jacobian", "nlp_hess_l": "Hessian"}
REPEATS = 3
QUICK = ("so3_rest_to_rest",)


def one(path: Path, backend: str) -> dict[str, Any] | None:
    """Median per-iteration breakdown of :data:`REPEATS` solves of the file on ``backend``
    (None when the backend is not offered for the file's NLP)."""
    cfg = files.load(path, [f"solver.backend={backend}"])
    solver = compile_problem(files.build(cfg), files.method(cfg), files.options(cfg))
    tr = solver.transcription
    runner = next((b for b in tr.backends if b.name == backend), None)
    if runner is None:
        return None
    p = tr.pack()
    x0 = tr.point(tr.guesses(p)[0], p)
    if backend == "fatrop":
        arguments = runner.arguments(x0, p)
    else:
        lbg, ubg, lbx, ubx = runner.bounds(p)
        arguments = {"x0": x0, "p": p, "lbg": lbg, "ubg": ubg, "lbx": lbx, "ubx": ubx}
    rows = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        runner.solver(**arguments)
        wall = time.perf_counter() - t0
        stats = runner.solver.stats()
        its = max(int(stats["iter_count"]), 1)
        evals = {name: float(stats.get(f"t_wall_{key}", 0.0)) / its * 1e3
                 for key, name in EVALUATIONS.items()}
        total = float(stats.get("t_wall_total", wall))
        rows.append({**evals, "solver": total / its * 1e3 - sum(evals.values()),
                     "python": (wall - total) / its * 1e3, "per_iteration": wall / its * 1e3,
                     "iterations": int(stats["iter_count"]), "success": bool(stats["success"])})
    best = {k: statistics.median(r[k] for r in rows) for k in rows[0]
            if k not in ("success", "iterations")}
    return {"problem": path.stem, "backend": backend, "N": solver.disc.N,
            "scheme": cfg.file.discretization.scheme, "iterations": rows[-1]["iterations"],
            "success": rows[-1]["success"], **best}


def chart(rows: list[dict[str, Any]], path: Path) -> None:
    """Stacked per-iteration bars: evaluations, the solver's own time, Python."""
    parts = list(EVALUATIONS.values()) + ["solver", "python"]
    labels = [f"{r['problem']}\n{r['backend']}" for r in rows]
    fig, ax = plt.subplots(figsize=(max(7.0, 0.55 * len(rows) + 1.5), 4.5))
    bottom = [0.0] * len(rows)
    for part in parts:
        v = [max(r[part], 0.0) for r in rows]
        ax.bar(range(len(rows)), v, bottom=bottom, label=part)
        bottom = [b + x for b, x in zip(bottom, v)]
    ax.set_xticks(range(len(rows)), labels, rotation=90, fontsize=7)
    ax.set_ylabel("ms per iteration")
    ax.set_title("Where one iteration's time goes (each file at its own scheme and N)")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results")
    paths = sorted(PROBLEMS.glob("*.yaml"))
    if args.quick:
        paths = [p for p in paths if p.stem in QUICK]
    rows: list[dict[str, Any]] = []
    with steps(2 * len(paths)) as step:
        for path in paths:
            for backend in ("ipopt", "fatrop"):
                step(f"{path.stem}: {backend}")
                row = one(path, backend)
                if row is not None:
                    rows.append(row)
    args.out.mkdir(parents=True, exist_ok=True)
    write_summary(args.out / "bench_iteration.json", {"rows": rows})
    chart(rows, args.out / "bench_iteration.png")
    print(f"{'problem':24} {'backend':7} {'N':>4} {'it':>4} {'ms/it':>7} "
          + " ".join(f"{n[:8]:>8}" for n in list(EVALUATIONS.values()) + ["solver", "python"]))
    for r in rows:
        print(f"{r['problem']:24} {r['backend']:7} {r['N']:>4} {r['iterations']:>4} "
              f"{r['per_iteration']:7.3f} "
              + " ".join(f"{r[n]:8.3f}" for n in list(EVALUATIONS.values()) + ["solver",
                                                                                 "python"]))


if __name__ == "__main__":
    main()
