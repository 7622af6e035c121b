"""Exported C solver versus the Python API: IPOPT solve time of the same instance, as a ratio.

For each case the problem is exported (ocgroupoid.export_c) and built with -O2; a small C
program linked with the export's libocg.a solves the instance repeatedly (after one warm-up
solve, each from the geodesic guess) and reports the time of each IPOPT call; the Python
side times the same call (Transcription.solve from the same guess, RawResult.solve_seconds),
after the same warm-up. Both medians are measured in this one run; the ratio C/Python is the
figure (below 1: C is faster). The machine is shared: expect noise of tens of percent.

Writes results/bench_codegen.json and results/bench_codegen.png.
"""

from __future__ import annotations

import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ocgroupoid import files  # noqa: E402
from ocgroupoid.bench.record import write_summary  # noqa: E402
from ocgroupoid.bench.script import arguments, steps  # noqa: E402
from ocgroupoid.export.codegen import export_c, make  # noqa: E402
from ocgroupoid.solve import geodesic_guesses  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
HARNESS = r"""
#include <stdio.h>
#include <stdlib.h>
#include "ocg_model.h"
#include "ocg_solver.h"

/* bench R: one warm-up solve, then R solves from the geodesic guess; one line each. */
int main(int argc, char **argv) {
  int repeats = argc > 1 ? atoi(argv[1]) : 10, i, code = 0;
  double p[OCG_NP];
  ocg_result *r = ocg_result_new();
  if (!r || ocg_pack(ocg_default_values, OCG_NV, p, OCG_NP, NULL) != OCG_OK) return 2;
  for (i = 0; i <= repeats && code >= 0; ++i) {
    code = ocg_solve(p, OCG_NP, NULL, 0, r);
    if (i > 0)
      printf("%.9f %d %.17g %s\n", ocg_solve_seconds(r), ocg_iterations(r), ocg_cost(r),
             ocg_status_name(r));
  }
  ocg_result_free(r);
  return code < 0 ? 2 : 0;
}
"""


def cases(quick: bool) -> list[tuple[Path, int]]:
    """(problem file, N): every problem file at its own N, and so3_rest_to_rest refined."""
    so3 = ROOT / "problems" / "so3_rest_to_rest.yaml"
    if quick:
        return [(so3, 32)]
    paths = sorted((ROOT / "problems").glob("*.yaml"))
    return [(f, files.load(f).file.horizon.N) for f in paths] + [(so3, 256), (so3, 1024)]


def measure(path: Path, N: int, repeats: int, folder: Path) -> dict:
    cfg = files.load(path)
    f = cfg.file
    t0 = time.perf_counter()
    exp = export_c(files.build(cfg), folder, N, f.discretization.retraction,
                   f.discretization.rule, f.solver.ipopt)
    export_seconds = time.perf_counter() - t0
    (folder / "bench.c").write_text(HARNESS)
    t0 = time.perf_counter()
    exe = make(folder, target="bench")
    build_seconds = time.perf_counter() - t0
    lines = subprocess.run([str(exe), str(repeats)], capture_output=True, text=True,
                           check=True, timeout=600).stdout.split("\n")
    c_rows = [line.split() for line in lines if line.strip()]
    tr = exp.solver.transcription
    p = tr.pack()
    guess = geodesic_guesses(tr, p)[0]
    tr.solve(guess, p)  # warm-up, as in C
    py_rows = [tr.solve(guess, p) for _ in range(repeats)]
    c_time = statistics.median(float(r[0]) for r in c_rows)
    py_time = statistics.median(r.solve_seconds for r in py_rows)
    return {"problem": cfg.name, "N": N, "nx": tr.nx, "repeats": repeats,
            "c_solve_seconds": c_time, "python_solve_seconds": py_time,
            "ratio_c_over_python": c_time / py_time,
            # the two may take different iteration counts (rounding on symmetric problems)
            "ratio_per_iteration": (c_time / max(int(c_rows[-1][1]), 1))
            / (py_time / max(py_rows[-1].iterations, 1)),
            "c_iterations": int(c_rows[-1][1]), "python_iterations": py_rows[-1].iterations,
            "c_status": c_rows[-1][3], "python_status": py_rows[-1].status,
            "cost_difference": abs(float(c_rows[-1][2]) - py_rows[-1].cost),
            "export_seconds": export_seconds, "build_seconds": build_seconds}


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results")
    repeats = 5 if args.quick else 15
    todo = cases(args.quick)
    rows = []
    with steps(len(todo)) as step, tempfile.TemporaryDirectory() as tmp:
        for i, (path, N) in enumerate(todo):
            step(f"export, build, solve: {path.stem} N={N}")
            rows.append(measure(path, N, repeats, Path(tmp) / f"case{i}"))
    data = {"what": "median IPOPT solve time, exported C versus Python, same instance and "
                    "start", "rows": rows,
            "ratios": {f"{r['problem']}_N{r['N']}": r["ratio_c_over_python"] for r in rows}}
    path = write_summary(args.out / "bench_codegen.json", data)
    labels = [f"{r['problem']}\nN={r['N']}" for r in rows]
    x = range(len(rows))
    fig, ax = plt.subplots(1, 2, figsize=(max(8, 2.2 * len(rows) + 3), 4))
    ax[0].bar([i - 0.2 for i in x], [r["python_solve_seconds"] * 1e3 for r in rows], 0.4,
              label="Python (CasADi + IPOPT)")
    ax[0].bar([i + 0.2 for i in x], [r["c_solve_seconds"] * 1e3 for r in rows], 0.4,
              label="exported C")
    ax[0].set_yscale("log")
    ax[0].set_ylabel("median solve time (ms)")
    ax[0].legend()
    ax[1].bar(list(x), [r["ratio_c_over_python"] for r in rows], color="C2")
    ax[1].axhline(1.0, color="k", lw=0.8)
    ax[1].set_ylabel("C / Python")
    for a in ax:
        a.set_xticks(list(x), labels, fontsize=8)
        a.grid(alpha=0.3, axis="y")
    fig.suptitle("exported C solver versus Python: same NLP, same start")
    fig.tight_layout()
    fig.savefig(args.out / "bench_codegen.png", dpi=110)
    for r in rows:
        print(f"{r['problem']:22s} N={r['N']:5d}  Python {r['python_solve_seconds'] * 1e3:8.2f} "
              f"ms  C {r['c_solve_seconds'] * 1e3:8.2f} ms  ratio {r['ratio_c_over_python']:.2f}"
              f"  iterations {r['python_iterations']}/{r['c_iterations']}  "
              f"{r['c_status']}  |dJ| {r['cost_difference']:.1e}")
    print(f"written {path}")


if __name__ == "__main__":
    main()
