"""Virtual machine against compiled evaluation (``solver.jit``), every problem file, N = 16 to
1024, both schemes: the median IPOPT time of one solve, the iterations, the time to generate
and compile the library, and the break-even (solves after which compiling has paid for
itself). One start (the geodesic) per solve, the problem file's other settings.

The stage-structured solver (fatrop) is not measured: it needs a stage-form transcription,
which the package does not have yet (issue 18).

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
from _bench import arguments, median_time, progress, save

from ocgroupoid import files
from ocgroupoid.solve import compile as compile_problem

PROBLEMS = Path(__file__).resolve().parent.parent / "problems"


def measure(path: Path, N: int, scheme: str, repeats: int) -> dict[str, Any]:
    """One configuration: VM and JIT solves from the same start, and the JIT build."""
    cfg = files.load(path, [f"horizon.N={N}", f"discretization.scheme={scheme}"])
    d, f = cfg.file.discretization, cfg.file
    problem = files.build(cfg)
    row: dict[str, Any] = {"problem": path.stem, "N": N, "scheme": scheme}
    for backend, jit in (("vm", False), ("jit", True)):
        t0 = time.perf_counter()
        solver = compile_problem(problem, N, d.retraction, d.rule, f.solver.ipopt, d.scheme,
                                 d.steps, jit)
        tr = solver.transcription
        row[f"{backend}_build_seconds"] = time.perf_counter() - t0
        if jit:
            row["jit_seconds"] = tr.build_phases["jit"]
        p = tr.pack()
        guess = tr.guesses(p)[0]
        seconds, r = median_time(lambda: tr.solve(guess, p), repeats)
        row[f"{backend}_solve_seconds"] = seconds
        row[f"{backend}_iterations"] = r.iterations
        row[f"{backend}_cost"] = r.cost
        row[f"{backend}_status"] = r.status
    gain = row["vm_solve_seconds"] - row["jit_solve_seconds"]
    row["speedup"] = row["vm_solve_seconds"] / row["jit_solve_seconds"]
    row["break_even_solves"] = row["jit_seconds"] / gain if gain > 0 else None
    row["cost_difference"] = abs(row["vm_cost"] - row["jit_cost"])
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
        for scheme, colour in (("order2", "C0"), ("order4", "C1")):
            sel = sorted((r for r in rows if r["problem"] == name and r["scheme"] == scheme),
                         key=lambda r: r["N"])
            if not sel:
                continue
            Ns = [r["N"] for r in sel]
            ax.loglog(Ns, [1e3 * r["vm_solve_seconds"] for r in sel], "o-", color=colour,
                      label=f"{scheme}, virtual machine")
            ax.loglog(Ns, [1e3 * r["jit_solve_seconds"] for r in sel], "s--", color=colour,
                      label=f"{scheme}, compiled (jit)")
        ax.set_title(name, fontsize=10)
        ax.set_xlabel("N (intervals)")
        ax.set_ylabel("IPOPT time per solve [ms]")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    for ax in axes.ravel()[len(names):]:
        ax.set_visible(False)
    fig.suptitle("solver.jit: IPOPT wall time per solve (median), one start; the library "
                 "is compiled once per structure")
    fig.tight_layout()
    fig.savefig(out / "bench_backends.png", dpi=100)
    plt.close(fig)


def main() -> None:
    args = arguments(__doc__.splitlines()[0])
    quick = args.quick
    if quick:  # CI: a private cache, so that the compile is measured too
        os.environ["OCGROUPOID_JIT_CACHE"] = tempfile.mkdtemp(prefix="ocg-jit-bench-")
    paths = [PROBLEMS / "so3_rest_to_rest.yaml"] if quick else sorted(PROBLEMS.glob("*.yaml"))
    Ns = [16, 32] if quick else [16, 64, 256, 1024]
    schemes = ["order2"] if quick else ["order2", "order4"]
    repeats = 1 if quick else 5
    args.out.mkdir(parents=True, exist_ok=True)
    rows: list[dict[str, Any]] = []
    configs = [(p, N, s) for p in paths for s in schemes for N in Ns]
    with progress() as bar:
        task = bar.add_task("VM vs JIT", total=len(configs))
        for path, N, scheme in configs:
            bar.update(task, description=f"{path.stem} {scheme} N={N}")
            try:
                rows.append(measure(path, N, scheme, repeats))
            except Exception as e:  # a configuration that does not build is recorded
                rows.append({"problem": path.stem, "N": N, "scheme": scheme,
                             "error": f"{type(e).__name__}: {e}"})
            save(args.out, "bench_backends", {"rows": rows, "repeats": repeats})
            bar.advance(task)
    done = [r for r in rows if "error" not in r]
    summary = {f"{r['problem']}/{r['scheme']}/N={r['N']}":
               {"speedup": r["speedup"], "break_even_solves": r["break_even_solves"]}
               for r in done}
    save(args.out, "bench_backends", {"rows": rows, "repeats": repeats, "summary": summary,
                                      "median_speedup": float(np.median([r["speedup"]
                                                                         for r in done]))})
    chart(done, args.out)
    for r in done:
        be = r["break_even_solves"]
        even = "-" if be is None else f"{be:.0f}"
        print(f"{r['problem']:22s} {r['scheme']} N={r['N']:5d}  "
              f"VM {1e3 * r['vm_solve_seconds']:8.1f} ms  JIT {1e3 * r['jit_solve_seconds']:8.1f}"
              f" ms  x{r['speedup']:.2f}  compile {r['jit_seconds']:.2f} s  break-even {even}"
              " solves")


if __name__ == "__main__":
    main()
