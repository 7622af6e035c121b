"""Which scheme a problem file gets by default: order2 against order4, one run.

For every problem file that does not name its scheme, both schemes solve it at the file's N
and order2 also at 2N and 4N (one start each, the file's other settings). Printed per run:
the replay's landing error relative to the distance the plan covers (the quantity
"verified" bounds, ``verify/verdict.py``), the solver time of the start, and whether the
solution is verified. Writes ``OUT/bench_default_scheme.json`` and a chart of landing error
against solver time, ``OUT/bench_default_scheme.png`` (``--out``, default ``results/``);
``--quick``: the canonical slew at N = 16.

    python scripts/bench_default_scheme.py [--quick] [--out DIR]
"""

from __future__ import annotations

from pathlib import Path

from rich.console import Console
from rich.table import Table

from ocgroupoid import files
from ocgroupoid.bench.chart import save_png
from ocgroupoid.bench.record import write_summary
from ocgroupoid.bench.script import arguments
from ocgroupoid.solve import compile_problem

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"


def landing(sol) -> float:
    """The replay's terminal error over the distance covered, the largest over states."""
    verdict = sol.diagnostics["verdict"]
    share = verdict["replay_tolerance"]
    errors = sol.diagnostics["replay"]["terminal_error"]
    return max(err / (verdict["tolerances"]["landing"][key] / share)
               for key, err in errors.items())


def run(path: Path, scheme: str, N: int) -> dict:
    """Solve ``path`` with ``scheme`` on N intervals from one start."""
    cfg = files.load(path, [f"discretization.scheme={scheme}", f"horizon.N={N}"])
    f, d = cfg.file, cfg.file.discretization
    solver = compile_problem(files.build(cfg), N, d.retraction, d.rule, f.solver.ipopt,
                             scheme, d.steps, f.solver.jit, f.solver.backend,
                             f.solver.max_seconds, bound_points=d.bound_points)
    sol = solver.solve(multistart=False)
    return {"file": path.name, "scheme": scheme, "N": N, "landing": landing(sol),
            "solver_seconds": sol.solve_seconds, "verified": bool(sol.success),
            "cost": sol.cost}


def unnamed(paths: list[Path]) -> list[Path]:
    """The files that leave the scheme to the default."""
    return [p for p in paths
            if "scheme" not in files.load(p).raw.get("discretization", {})]


def chart(rows: list[dict], path: Path) -> Path:
    """Landing error against solver time, one line per file and scheme (order2 over N)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(10, 5.5), layout="constrained")
    for i, name in enumerate(dict.fromkeys(r["file"] for r in rows)):
        colour = f"C{i % 10}"
        for scheme, marker in (("order4", "s"), ("order2", "o")):
            mine = [r for r in rows if r["file"] == name and r["scheme"] == scheme]
            ax.loglog([r["solver_seconds"] for r in mine], [r["landing"] for r in mine],
                      marker=marker, color=colour, ls="-" if scheme == "order2" else "none",
                      label=f"{name.removesuffix('.yaml')} {scheme}")
    ax.set_xlabel("solver time of one start [s]")
    ax.set_ylabel("landing error / distance covered")
    ax.set_title("order4 at the file's N (squares), order2 at N, 2N, 4N (circles)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2, loc="center left", bbox_to_anchor=(1.0, 0.5))
    return save_png(fig, path, 110)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], RESULTS)
    paths = [ROOT / "problems" / "so3_rest_to_rest.yaml"] if args.quick else \
        sorted((ROOT / "problems").glob("*.yaml"))
    console = Console()
    rows = []
    for path in unnamed(paths):
        N = 16 if args.quick else files.load(path).file.horizon.N
        for scheme, n in (("order4", N), ("order2", N), ("order2", 2 * N), ("order2", 4 * N)):
            console.print(f"{path.name}: {scheme} N={n} ...", highlight=False)
            rows.append(run(path, scheme, n))
    table = Table(title="default scheme: landing error (relative) and solver time, one start")
    for col in ("file", "scheme", "N", "landing", "solver s", "verified"):
        table.add_column(col)
    for r in rows:
        table.add_row(r["file"], r["scheme"], str(r["N"]), f"{r['landing']:.2e}",
                      f"{r['solver_seconds']:.3f}", str(r["verified"]))
    console.print(table)
    write_summary(args.out / "bench_default_scheme.json", {"rows": rows})
    chart(rows, args.out / "bench_default_scheme.png")


if __name__ == "__main__":
    main()
