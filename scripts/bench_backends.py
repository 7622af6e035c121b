"""The NLP backends, every problem file, N = 16 to 1024, both schemes: IPOPT or fatrop (the
stage form), each with the virtual machine or compiled evaluation (``solver.jit``). Per
configuration: the median wall time of one solve, the iterations, the cost, the time to
generate and compile the library; per problem, N and scheme: the speed-up of the best
configuration over IPOPT with the virtual machine (the default before issue 18) and the
break-even of compiling (solves after which it has paid for itself). One start (the
geodesic) per solve, the problem file's other settings.

Writes ``bench_backends.json`` (a row per finished configuration, as it goes) and
``bench_backends.png`` (time per solve against N, one panel per problem file).
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from ocgroupoid import files
from ocgroupoid.bench.record import write_summary
from ocgroupoid.bench.script import arguments, steps
from ocgroupoid.bench.timing import median_seconds
from ocgroupoid.solve import compile_problem

ROOT = Path(__file__).resolve().parent.parent
PROBLEMS = ROOT / "problems"


CONFIGS = (("ipopt", False), ("ipopt", True), ("fatrop", False), ("fatrop", True))


def label(backend: str, jit: bool) -> str:
    return f"{backend}_{'jit' if jit else 'vm'}"


def measure(path: Path, N: int, scheme: str, repeats: int) -> dict[str, Any]:
    """One problem, N and scheme: every configuration from the same start."""
    cfg = files.load(path, [f"horizon.N={N}", f"discretization.scheme={scheme}"])
    d, f = cfg.file.discretization, cfg.file
    problem = files.build(cfg)
    row: dict[str, Any] = {"problem": path.stem, "N": N, "scheme": scheme}
    for backend, jit in CONFIGS:
        key = label(backend, jit)
        try:
            t0 = time.perf_counter()
            solver = compile_problem(problem, N, d.retraction, d.rule, f.solver.ipopt, d.scheme,
                                     d.steps, jit, backend)
        except Exception as e:  # e.g. a problem fatrop does not accept: recorded
            row[f"{key}_error"] = f"{type(e).__name__}: {e}"
            continue
        tr = solver.transcription
        row[f"{key}_build_seconds"] = time.perf_counter() - t0
        if jit:
            row[f"{key}_jit_seconds"] = tr.build_phases["jit" if backend == "ipopt" else
                                                        "fatrop"]
        p = tr.pack()
        guess = tr.guesses(p)[0]
        seconds, r = median_seconds(lambda: tr.solve(guess, p), repeats)  # noqa: B023 (called here)
        row[f"{key}_solve_seconds"] = seconds
        row[f"{key}_iterations"] = r.iterations
        row[f"{key}_cost"] = r.cost
        row[f"{key}_status"] = r.status
        row[f"{key}_solver"] = r.backend  # "ipopt after fatrop": fatrop failed, IPOPT solved
    old = row["ipopt_vm_solve_seconds"]
    ok = [label(*c) for c in CONFIGS if row.get(f"{label(*c)}_status") == "Solve_Succeeded"
          and abs(row[f"{label(*c)}_cost"] - row["ipopt_vm_cost"])
          <= 1e-8 * abs(row["ipopt_vm_cost"])]
    best = min(ok, key=lambda k: row[f"{k}_solve_seconds"])
    row["best"], row["speedup"] = best, old / row[f"{best}_solve_seconds"]
    for backend in ("ipopt", "fatrop"):
        vm, jit = (row.get(f"{backend}_{m}_solve_seconds") for m in ("vm", "jit"))
        if vm is not None and jit is not None:
            gain = vm - jit
            row[f"{backend}_break_even_solves"] = row[f"{backend}_jit_jit_seconds"] / gain \
                if gain > 0 else None
    return row


def chart(rows: list[dict[str, Any]], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = sorted({r["problem"] for r in rows})
    cols = 3
    fig, axes = plt.subplots(-(-len(names) // cols), cols, figsize=(13, 3.6 * -(-len(names)
                                                                            // cols)),
                             squeeze=False)
    for ax, name in zip(axes.ravel(), names):
        for scheme, style in (("order2", "-"), ("order4", ":")):
            sel = sorted((r for r in rows if r["problem"] == name and r["scheme"] == scheme),
                         key=lambda r: r["N"])
            for (backend, jit), (colour, mark) in zip(CONFIGS, (("C0", "o"), ("C1", "s"),
                                                               ("C2", "^"), ("C3", "D"))):
                key = label(backend, jit)
                pts = [(r["N"], 1e3 * r[f"{key}_solve_seconds"]) for r in sel
                       if r.get(f"{key}_status") == "Solve_Succeeded"]
                if pts:
                    ax.loglog(*zip(*pts), mark + style, color=colour, ms=4,
                              label=f"{scheme} {backend} {'jit' if jit else 'vm'}")
        ax.set_title(name, fontsize=10)
        ax.set_xlabel("N (intervals)")
        ax.set_ylabel("time per solve [ms]")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=6, ncol=2)
    for ax in axes.ravel()[len(names):]:
        ax.set_visible(False)
    fig.suptitle("solver.backend and solver.jit: wall time per solve (median), one start; "
                 "converged solves only (solid order2, dotted order4)\na fatrop time includes "
                 "IPOPT's re-solve where fatrop failed (cart_pole)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out / "bench_backends.png", dpi=100)
    plt.close(fig)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results")
    quick = args.quick
    # a private cache, so that every compile is measured (a shared one may hold them)
    os.environ["OCGROUPOID_JIT_CACHE"] = tempfile.mkdtemp(prefix="ocg-jit-bench-")
    paths = [PROBLEMS / "so3_rest_to_rest.yaml"] if quick else sorted(PROBLEMS.glob("*.yaml"))
    Ns = [16, 32] if quick else [16, 64, 256, 1024]
    schemes = ["order2"] if quick else ["order2", "order4"]
    repeats = 1 if quick else 5
    args.out.mkdir(parents=True, exist_ok=True)
    rows: list[dict[str, Any]] = []
    configs = [(p, N, s) for p in paths for s in schemes for N in Ns]
    summary_path = args.out / "bench_backends.json"
    with steps(len(configs)) as step:
        for path, N, scheme in configs:
            step(f"{path.stem} {scheme} N={N}")
            try:
                rows.append(measure(path, N, scheme, repeats))
            except Exception as e:  # a configuration that does not build is recorded
                rows.append({"problem": path.stem, "N": N, "scheme": scheme,
                             "error": f"{type(e).__name__}: {e}"})
            write_summary(summary_path, {"rows": rows, "repeats": repeats})
    done = [r for r in rows if "error" not in r]
    summary = {f"{r['problem']}/{r['scheme']}/N={r['N']}":
               {"best": r["best"], "speedup": r["speedup"],
                **{k: r.get(k) for k in ("ipopt_break_even_solves",
                                         "fatrop_break_even_solves")}} for r in done}
    write_summary(summary_path, {
        "rows": rows, "repeats": repeats, "summary": summary,
        "median_speedup": float(np.median([r["speedup"] for r in done])),
        "fatrop_vm_over_ipopt_vm": {f"{r['problem']}/{r['scheme']}/N={r['N']}":
                                    r["ipopt_vm_solve_seconds"] / r["fatrop_vm_solve_seconds"]
                                    for r in done if r.get("fatrop_vm_status")
                                    == "Solve_Succeeded"}})
    chart(done, args.out)
    for r in done:
        times = "  ".join(f"{label(*c)} {1e3 * r[label(*c) + '_solve_seconds']:7.1f} ms"
                          f" ({r[label(*c) + '_iterations']} it)" for c in CONFIGS
                          if label(*c) + "_solve_seconds" in r)
        print(f"{r['problem']:20s} {r['scheme']} N={r['N']:5d}  {times}  best {r['best']} "
              f"x{r['speedup']:.2f}")


if __name__ == "__main__":
    main()
