"""Work-precision of every problem file: `ocgroupoid bench work-precision` with our schemes
order2 and order4 beside RK4 multiple shooting on unit quaternions (rk4_quat).

For each file in problems/, :func:`ocgroupoid.bench.workprecision.work_precision` (the
reference, the timed solves from one cold start and the equal-accuracy ratios: see there)
on N = 8 ... 512 with the reference from N = 1024, five repeats at least; it writes
OUT/work_precision/<file>_schemes.json (and .jsonl) and the chart
OUT/figures/work_precision_<file>_schemes.png. Then OUT/bench_schemes.json (per file the
reference and the time of rk4_quat over ours at equal accuracy) and OUT/bench_schemes.png
(every file's two panels). ``--quick``: so3_rest_to_rest and plate_ball_rotating, N = 8, 16,
32, the reference from N = 64, one repeat.
"""

from __future__ import annotations

from pathlib import Path

from rich.console import Console

from ocgroupoid.bench.chart import work_precision_grid
from ocgroupoid.bench.equal_accuracy import report
from ocgroupoid.bench.methods import Method
from ocgroupoid.bench.record import write_summary
from ocgroupoid.bench.script import arguments
from ocgroupoid.bench.workprecision import work_precision
from ocgroupoid.progress import progress_bar

ROOT = Path(__file__).resolve().parent.parent
METHODS = [Method("order2"), Method("order4"), Method("rk4_quat")]
QUICK_FILES = ("so3_rest_to_rest", "plate_ball_rotating")


def main() -> None:
    args = arguments(__doc__.splitlines()[0], ROOT / "results")
    Ns, reference_N, repeats = ([8, 16, 32], 64, 1) if args.quick else \
        ([8, 16, 32, 64, 128, 256, 512], 1024, 5)
    paths = sorted((ROOT / "problems").glob("*.yaml"))
    if args.quick:
        paths = [p for p in paths if p.stem in QUICK_FILES]
    summaries, files = [], {}
    with progress_bar(Console(stderr=True)) as bar:
        for path in paths:
            summary, where = work_precision(path, [], args.out, METHODS, Ns, repeats,
                                            reference_N, f"{path.stem}_schemes", bar)
            summaries.append(summary)
            files[path.stem] = {"reference": summary["reference"]["cost"],
                                "relative_uncertainty":
                                    summary["reference"]["relative_uncertainty"],
                                "headline": summary["headline"],
                                "equal_accuracy": summary["equal_accuracy"],
                                "summary": str(where.summary), "chart": str(where.chart)}
    json_path = write_summary(args.out / "bench_schemes.json", {
        "methods": [m.label for m in METHODS], "N": Ns, "reference_N": reference_N,
        "repeats": repeats, "files": files})
    work_precision_grid(summaries, args.out / "bench_schemes.png")
    for summary in summaries:
        print(report(summary))
    print(f"written {json_path}")


if __name__ == "__main__":
    main()
