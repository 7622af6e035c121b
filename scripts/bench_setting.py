"""One setting changed: every problem file solved as it is and with ``--set``, in rounds.

For each file in problems/, method (``--schemes``, as for ``ocgroupoid bench
work-precision``; default ``order4+jit`` and ``rk4_quat+jit``: both run IPOPT, whose
options are the usual subject) and N (``--N``, default 64 and 256): the file as it is
and the file with the ``--set`` overrides (as ``ocgroupoid solve --set``; default
``solver.ipopt.mumps_mem_percent=1000``, IPOPT's own workspace for MUMPS against ours,
:data:`~ocgroupoid.nlp.backends.ipopt.DEFAULT_IPOPT`), built first and then solved from the
file's first guess in rounds, five solves each (:func:`~ocgroupoid.bench.timing.interleaved`).
The ratio is the changed time over the time as it is (> 1: the file as it is is faster),
measured in the same run; ``same`` says whether both solved to the same cost (within 1e-8)
in as many iterations. Writes ``OUT/bench_setting.json`` and the ratios as a chart,
``OUT/bench_setting.png`` (``--out``, default ``results/``); ``--quick``: so3 at N = 16, one
solve.

    python scripts/bench_setting.py [--set KEY=VALUE ...] [--schemes M,...] [--N 64,256]
                                    [--quick] [--out DIR]
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from ocgroupoid import files
from ocgroupoid.bench.chart import save_png
from ocgroupoid.bench.methods import Method, parse_grids, parse_methods
from ocgroupoid.bench.record import write_summary
from ocgroupoid.bench.script import arguments, cell, record, steps
from ocgroupoid.bench.timing import Setting, Trial, interleaved
from ocgroupoid.errors import OcgError

ROOT = Path(__file__).resolve().parents[1]
METHODS = (Method("order4", jit=True), Method("rk4_quat", jit=True))
METHOD_LABELS = ",".join(m.label for m in METHODS)
DEFAULT_SET = ["solver.ipopt.mumps_mem_percent=1000"]
NS, REPEATS = (64, 256), 5
QUICK_FILES, QUICK_NS = ("so3_rest_to_rest",), (16,)


def own_arguments(ap: argparse.ArgumentParser) -> None:
    """``--set`` (repeatable), ``--schemes`` and ``--N``."""
    ap.add_argument("--set", action="append", dest="overrides", metavar="KEY=VALUE",
                    help=f"a setting changed, as for ocgroupoid solve (default {DEFAULT_SET[0]})")
    ap.add_argument("--schemes", default=METHOD_LABELS,
                    help=f"methods, comma-separated (default {METHOD_LABELS})")
    ap.add_argument("--N", help="intervals, comma-separated (default "
                    f"{','.join(map(str, NS))})")


def compared(base: dict[str, Any], changed: dict[str, Any]) -> dict[str, Any]:
    """The changed time over the time as it is, and whether both reached the same point."""
    both = base["status"] == changed["status"] == "Solve_Succeeded"
    return {"ratio": changed["seconds"] / base["seconds"] if both else None,
            "same": both and base["iterations"] == changed["iterations"]
            and abs(base["cost"] - changed["cost"]) <= 1e-8 * max(1.0, abs(base["cost"]))}


def chart(rows: list[dict[str, Any]], overrides: list[str], path: Path) -> Path:
    """The changed time over the time as it is, per file, one bar per method and N."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(r["file"] for r in rows))
    series = list(dict.fromkeys((r["method"], r["N"]) for r in rows))
    fig, ax = plt.subplots(figsize=(10, 4.5), layout="constrained")
    width = 0.8 / len(series)
    for j, (method, N) in enumerate(series):
        xs, ys = [], []
        for i, name in enumerate(names):
            r = next((r for r in rows if (r["file"], r["method"], r["N"]) == (name, method, N)),
                     None)
            if r and r["ratio"]:
                xs.append(i + (j - (len(series) - 1) / 2) * width)
                ys.append(r["ratio"])
        ax.bar(xs, ys, width, label=f"{method}, N = {N}", color=f"C{j}")
    ax.axhline(1.0, color="k", lw=0.8)
    ratios = [r["ratio"] for r in rows if r["ratio"]]
    ax.set_ylim(min([0.8, *ratios]) * 0.95, max([1.2, *ratios]) * 1.05)
    ax.set_xticks(range(len(names)), names, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel("time with the change / time as it is")
    ax.set_title(f"{', '.join(overrides)}: > 1 where the file as it is solves faster",
                 fontsize=10)
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    return save_png(fig, path, 110)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results", more=own_arguments)
    overrides = args.overrides or DEFAULT_SET
    paths = sorted((ROOT / "problems").glob("*.yaml"))
    if args.quick:
        paths = [p for p in paths if p.stem in QUICK_FILES]
    repeats = 1 if args.quick else REPEATS
    try:  # every input checked before anything is built
        methods = parse_methods(args.schemes, METHODS)
        Ns = QUICK_NS if args.quick else parse_grids(args.N, NS)
        configs = {(path, changed): files.load(path, overrides if changed else [])
                   for path in paths for changed in (False, True)}
    except OcgError as e:
        Console(stderr=True).print(f"bench_setting: {e}", markup=False, highlight=False,
                                   soft_wrap=True)
        raise SystemExit(2) from None
    trials: dict[tuple[str, str, int, bool], Trial | OcgError] = {}
    with steps(len(paths) * len(methods) * len(Ns) * 2 + 1) as step:
        for path in paths:
            for changed in (False, True):
                cfg = configs[path, changed]
                problem, setting = files.build(cfg), Setting.of(cfg.file)
                for method in methods:
                    for N in Ns:
                        step(f"build {path.stem} {method.label} N={N}"
                             + (" changed" if changed else ""))
                        key = (path.stem, method.label, N, changed)
                        try:
                            trials[key] = Trial(problem, method, N, setting)
                        except OcgError as e:
                            trials[key] = e
        step("solves in rounds")
        interleaved([t for t in trials.values() if isinstance(t, Trial)], repeats)
    rows = []
    for path in paths:
        for method in methods:
            for N in Ns:
                base, changed = (record(trials[path.stem, method.label, N, c])
                                 for c in (False, True))
                rows.append({"file": path.stem, "method": method.label, "N": N,
                             "as_it_is": base, "changed": changed, **compared(base, changed)})
    args.out.mkdir(parents=True, exist_ok=True)
    write_summary(args.out / "bench_setting.json",
                  {"overrides": overrides, "methods": [m.label for m in methods],
                   "N": list(Ns), "repeats": repeats, "start": "the file's first guess",
                   "rows": rows})
    chart(rows, overrides, args.out / "bench_setting.png")
    table = Table("file", "method", "N", "as it is: its, ms", "changed: its, ms", "ratio",
                  "same")
    for r in rows:
        table.add_row(r["file"], r["method"], str(r["N"]), cell(r["as_it_is"]), cell(r["changed"]),
                      "-" if r["ratio"] is None else f"{r['ratio']:.2f}x",
                      "yes" if r["same"] else "no")
    Console().print(table)


if __name__ == "__main__":
    main()
