"""Where the time of one iteration goes (issue 26), on every problem file and both backends.

Per problem file (its own scheme and N), backend (IPOPT; fatrop) and evaluation (CasADi's
virtual machine, ``vm``; compiled, ``jit``: the best configurations' evaluation), solves from
the first geodesic guess (the backend's CasADi solver called directly: no fallback), timed by
CasADi's own counters (``solver.stats()``, with ``record_time``): the wall time of the function
evaluations IPOPT or fatrop asked for (objective, constraints, gradient, constraint Jacobian,
Hessian of the Lagrangian: ``t_wall_nlp_*``), the rest of the solver's call (``t_wall_total``
less those: the KKT factorisations and solves — MUMPS for IPOPT, fatrop's stage-wise Riccati
and its set-up in every call — and the method's own linear algebra), and the Python around
the call (our wall time minus the solver's: CasADi's conversion of the numpy inputs and
outputs, which the backends' own calls avoid, :mod:`~ocgroupoid.nlp.buffered`, and what of
fatrop's set-up falls outside CasADi's timer). fatrop runs as the backend runs it (with
``jit`` or without), through its own C interface in this process
(:mod:`~ocgroupoid.nlp.backends.fatrop_ocp`), timed by its driver
(:class:`~ocgroupoid.nlp.backends.fatrop_ocp.SolveTimes`): the evaluations during fatrop's
call, fatrop's own (the call less those: its Riccati factorisations and solves, its line
search, the callbacks' copies of the stage blocks), and the Python around the call (the
scaled arguments and the way back). Each divided by the iterations, in milliseconds. The
median of :data:`REPEATS` solves per row.

Beside it, per solve: the same start solved as a caller solves it
(:meth:`~ocgroupoid.nlp.transcription.Transcription.solve`, the time the work-precision bench
charts), and what that costs beyond the direct call (``outside``, ms per solve): the guess's
start point, the backend's arguments and, for fatrop, its guard (in this process; or the way
to its helper process and back, :mod:`~ocgroupoid.nlp.isolated`, where it has one), less the
plain call's conversions, which the backends' buffered calls avoid; medians of :data:`PAIRS`
of each in turn, after one solve not timed (a helper process starts at the first).
Left empty where that solve is not the backend's own (a fallback).

Writes ``bench_iteration.json`` and ``bench_iteration.png`` (stacked bars per file, backend
and evaluation).
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path
from typing import Any, Callable

import casadi as ca
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
#: the caller's solves and direct calls timed in turn for ``outside`` (sub-millisecond)
PAIRS = 9
QUICK = ("so3_rest_to_rest",)


def one(path: Path, backend: str, jit: bool) -> dict[str, Any] | None:
    """Median per-iteration breakdown of :data:`REPEATS` solves of the file on ``backend``,
    its functions compiled if ``jit`` (None when the backend is not offered for the file's
    NLP)."""
    cfg = files.load(path, [f"solver.backend={backend}", f"solver.jit={str(jit).lower()}"])
    solver = compile_problem(files.build(cfg), files.method(cfg), files.options(cfg))
    tr = solver.transcription
    runner = next((b for b in tr.backends if b.name == backend), None)
    if runner is None:
        return None
    p = tr.pack()
    guess = tr.guesses(p)[0]
    x0 = tr.point(guess, p)
    if backend == "fatrop":
        arguments = runner.arguments(x0, p)
    else:
        lbg, ubg, lbx, ubx = runner.bounds(p)
        arguments = {"x0": x0, "p": p, "lbg": lbg, "ubg": ubg, "lbx": lbx, "ubx": ubx}
    direct = getattr(runner, "direct", None)
    if direct is not None:  # fatrop through its own C interface, in this process
        def breakdown() -> tuple[int, bool, float, dict[str, float]]:
            run = runner._solve_here((x0, p))
            times = direct.times
            return run.iterations, run.success, times.solve, times.evaluations

        call: Callable[[], object] = breakdown  # reading the times is free
    else:
        # the backend's solver with CasADi's timer of the whole call (record_time), which
        # the backend's own leaves out; called plainly (through buffers, as the backends
        # call theirs, CasADi's counters add up over the calls and the total reads 0)
        timed = ca.nlpsol("timed", backend, runner.nlp, {**runner.options, "record_time": True})

        def call() -> object:
            return timed(**arguments)

        def breakdown() -> tuple[int, bool, float, dict[str, float]]:
            timed(**arguments)
            stats = timed.stats()
            return (int(stats["iter_count"]), bool(stats["success"]),
                    float(stats["t_wall_total"]),
                    {key: float(stats.get(f"t_wall_{key}", 0.0)) for key in EVALUATIONS})
    rows = []
    walls, solves = [], []
    tr.solve(guess, p)  # not timed: a helper process starts at the first solve
    for _ in range(PAIRS):  # the caller's solve and the direct call in turn
        t0 = time.perf_counter()
        result = tr.solve(guess, p)
        solves.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        call()
        walls.append(time.perf_counter() - t0)
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        iterations, success, total, seconds = breakdown()
        wall = time.perf_counter() - t0
        its = max(iterations, 1)
        evals = {name: seconds[key] / its * 1e3 for key, name in EVALUATIONS.items()}
        rows.append({**evals, "solver": total / its * 1e3 - sum(evals.values()),
                     "python": (wall - total) / its * 1e3, "per_iteration": wall / its * 1e3,
                     "iterations": iterations, "success": success})
    best = {k: statistics.median(r[k] for r in rows) for k in rows[0]
            if k not in ("success", "iterations")}
    own = result.backend == backend
    solve_ms = statistics.median(solves) * 1e3
    return {"problem": path.stem, "backend": backend, "evaluation": "jit" if jit else "vm",
            "interface": "own" if direct is not None else "nlpsol", "N": solver.disc.N,
            "scheme": cfg.file.discretization.scheme, "iterations": rows[-1]["iterations"],
            "success": rows[-1]["success"], **best,
            "solve_ms": solve_ms if own else None,
            "outside_ms": solve_ms - statistics.median(walls) * 1e3 if own else None}


def chart(rows: list[dict[str, Any]], path: Path) -> None:
    """Stacked per-iteration bars (evaluations, the solver's own time, Python), one panel per
    evaluation (virtual machine, compiled)."""
    parts = list(EVALUATIONS.values()) + ["solver", "python"]
    panels = [e for e in ("vm", "jit") if any(r["evaluation"] == e for r in rows)]
    n = max(sum(r["evaluation"] == e for r in rows) for e in panels)
    fig, axes = plt.subplots(len(panels), 1, figsize=(max(7.0, 0.45 * n + 2.5),
                                                      3.8 * len(panels) + 0.6), squeeze=False)
    for ax, evaluation in zip(axes[:, 0], panels):
        shown = [r for r in rows if r["evaluation"] == evaluation]
        bottom = [0.0] * len(shown)
        for part in parts:
            v = [max(r[part], 0.0) for r in shown]
            ax.bar(range(len(shown)), v, bottom=bottom,
                   label="solver's own" if part == "solver" else part)
            bottom = [b + x for b, x in zip(bottom, v)]
        ax.set_xticks(range(len(shown)), [f"{r['problem']}\n{r['backend']}" for r in shown],
                      rotation=90, fontsize=7)
        ax.set_ylabel("ms per iteration")
        ax.set_title("evaluated by CasADi's virtual machine" if evaluation == "vm" else
                     "compiled evaluation (jit)", fontsize=9)
    axes[0, 0].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.suptitle("Where one iteration's time goes (each file at its own scheme and N)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results")
    paths = sorted(PROBLEMS.glob("*.yaml"))
    if args.quick:
        paths = [p for p in paths if p.stem in QUICK]
    rows: list[dict[str, Any]] = []
    with steps(4 * len(paths)) as step:
        for path in paths:
            for backend in ("ipopt", "fatrop"):
                for jit in (False, True):
                    step(f"{path.stem}: {backend}{' jit' if jit else ''}")
                    row = one(path, backend, jit)
                    if row is not None:
                        rows.append(row)
    args.out.mkdir(parents=True, exist_ok=True)
    write_summary(args.out / "bench_iteration.json", {"rows": rows})
    chart(rows, args.out / "bench_iteration.png")
    print(f"{'problem':24} {'backend':7} {'eval':4} {'N':>4} {'it':>4} {'ms/it':>7} "
          + " ".join(f"{n[:8]:>8}" for n in list(EVALUATIONS.values()) + ["solver", "python"])
          + f" {'solve ms':>9} {'outside':>8}")
    for r in rows:
        print(f"{r['problem']:24} {r['backend']:7} {r['evaluation']:4} {r['N']:>4} "
              f"{r['iterations']:>4} "
              f"{r['per_iteration']:7.3f} "
              + " ".join(f"{r[n]:8.3f}" for n in list(EVALUATIONS.values()) + ["solver",
                                                                                 "python"])
              + "".join(" " + ("-" if r[k] is None else f"{r[k]:{w}.3f}").rjust(w)
                        for k, w in (("solve_ms", 9), ("outside_ms", 8))))


if __name__ == "__main__":
    main()
