"""Extract the small tables the benchmark pages show from the benchmark results.

The benchmark scripts and ``ocgroupoid bench`` write their full results to ``results/``
(megabytes, not kept in git). This module keeps what the pages need, a few kilobytes per
table, in ``docs/benchmarks/data/``; the docs build reads only those. Run it after a
benchmark::

    python -m docsgen.extract [RESULTS] [DATA]
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path
from typing import Any, Iterable

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "results"
DATA = ROOT / "docs" / "benchmarks" / "data"
#: the columns kept of a work-precision row
WP_COLUMNS = ("run", "method", "N", "success", "iterations", "iterations_all", "backend",
              "seconds", "cost_error", "replay_error")
#: the landing accuracies at which the best configurations are set against rk4_quat+jit
LANDING_LEVELS = (1e-4, 1e-6, 1e-8)
#: the baselines the best configurations' landing is set against there, and their keys: the
#: shooting compiled, and compiled and solved on N/4 first (``+coarse``)
LANDING_BASELINES = {"landing_vs_jit": "rk4_quat+jit",
                     "landing_vs_jit_coarse": "rk4_quat+jit+coarse"}
#: each table's input in the results folder: an extract runs when its input is there
INPUTS = {"work_precision": "work_precision", "stability": "stability/so3.json",
          "so3_build": "bench_so3.json", "backends": "bench_backends.json",
          "codegen": "bench_codegen.json", "drift": "energy_drift.json",
          "sweep": "bench_sweep.json", "rockit": "bench_rockit.json"}


def _read(path: Path) -> Any:
    return json.loads(path.read_text())


def _write_csv(path: Path, columns: Iterable[str], rows: Iterable[dict[str, Any]]) -> None:
    columns = list(columns)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, columns, extrasaction="ignore", lineterminator="\n")
        w.writeheader()
        for row in rows:
            w.writerow({k: _short(row.get(k)) for k in columns})


def _short(v: Any) -> Any:
    """Floats to 4 significant digits (what a page shows); other values as they are."""
    return f"{v:.4g}" if isinstance(v, float) else ("" if v is None else v)


def _headline(entry: dict[str, Any] | None) -> dict[str, Any] | None:
    if not entry:
        return None
    return {k: entry[k] for k in ("level", "ours", "ratio", "lower_bound")}


def _at_level(comparisons: list[dict[str, Any]], level: float) -> dict[str, Any] | None:
    return next((c for c in comparisons if c["level"] == level), None)


def _rows(path: Path) -> list[dict[str, str]]:
    if not path.exists():
        return []
    with path.open() as f:
        return list(csv.DictReader(f))


def work_precision(results: Path, data: Path) -> dict[str, Any]:
    """Per problem file: the headline ratios of both runs, the landing ratios against
    ``rk4_quat+jit`` at :data:`LANDING_LEVELS`, and one CSV of their rows. A run found in
    ``results`` replaces that run's entry and rows; the runs it did not repeat are kept."""
    summary_path = data / "work_precision.json"
    out: dict[str, Any] = _read(summary_path) if summary_path.exists() else {}
    found = sorted({p.stem.removesuffix("_backends")
                    for p in (results / "work_precision").glob("*.json")})
    for problem in found:
        runs = {run: _read(path) for run, path in (
            ("schemes", results / "work_precision" / f"{problem}.json"),
            ("best", results / "work_precision" / f"{problem}_backends.json")) if path.exists()}
        entry: dict[str, Any] = out.get(problem, {})
        csv_path = data / "work_precision" / f"{problem}.csv"
        rows: list[dict[str, Any]] = [r for r in _rows(csv_path) if r["run"] not in runs]
        for run, summary in runs.items():
            head = summary.get("headline", {})
            entry[run] = {kind: _headline(head.get(kind)) for kind in ("cost_error",
                                                                      "replay_error")}
            jit = summary.get("equal_accuracy_rk4_quat+jit")
            if jit:
                entry[run]["vs_jit"] = {
                    kind: _headline(_at_level(jit.get(kind, []), head[kind]["level"]))
                    for kind in ("cost_error", "replay_error") if head.get(kind)}
            for key, baseline in LANDING_BASELINES.items():
                if against := summary.get(f"equal_accuracy_{baseline}"):
                    entry[run][key] = {
                        f"{level:.0e}": _headline(_at_level(against.get("replay_error", []),
                                                            level))
                        for level in LANDING_LEVELS}
            entry[run]["created"] = summary.get("created")
            entry[run]["reference"] = summary["reference"]["cost"]
            rows += [{"run": run, **r} for r in summary["rows"] if r.get("kind") == "row"]
        out[problem] = dict(sorted(entry.items(), key=lambda kv: kv[0] != "schemes"))
        _write_csv(csv_path, WP_COLUMNS, rows)
    summary_path.write_text(json.dumps(dict(sorted(out.items())), indent=1) + "\n")
    return out


def stability(results: Path, data: Path) -> None:
    """The so3 stability map: one row per method, angle and N with its outcome."""
    summary = _read(results / "stability" / "so3.json")
    _write_csv(data / "stability_so3.csv", ("method", "angle", "N", "outcome"),
               summary["cells"])


def so3_build(results: Path, data: Path) -> None:
    """Build and solve times of so3_rest_to_rest against CasADi's own derivatives."""
    rows = []
    for r in _read(results / "bench_so3.json")["rows"]:
        base = r["baselines"]
        rows.append({"N": r["N"], "build_ms": 1e3 * r["build_seconds"],
                     **{f"{k}_ms": 1e3 * v for k, v in r["build_phases_seconds"].items()},
                     "solve_ms": 1e3 * r["solve_seconds"], "iterations": r["iterations"],
                     **{f"{name}_{k}_ms": 1e3 * base[name][f"{k}_seconds"]
                        for name in base for k in ("build", "solve")}})
    _write_csv(data / "so3_build.csv", rows[0].keys(), rows)


def backends(results: Path, data: Path) -> None:
    """The best of IPOPT, fatrop, virtual machine and jit, per problem, scheme and N."""
    summary = _read(results / "bench_backends.json")
    by_key = {f"{r['problem']}/{r['scheme']}/N={r['N']}": r for r in summary["rows"]}
    rows = [{"problem": by_key[k]["problem"], "scheme": by_key[k]["scheme"],
             "N": by_key[k]["N"], "best": v["best"], "speedup": v["speedup"],
             "best_solve_ms": 1e3 * by_key[k][f"{v['best']}_solve_seconds"]}
            for k, v in summary["summary"].items()]
    _write_csv(data / "backends.csv", rows[0].keys(), rows)


def codegen(results: Path, data: Path) -> None:
    """Exported C against Python, same instance and start."""
    rows = [{"problem": r["problem"], "N": r["N"], "c_ms": 1e3 * r["c_solve_seconds"],
             "python_ms": 1e3 * r["python_solve_seconds"],
             "ratio": r["ratio_c_over_python"]}
            for r in _read(results / "bench_codegen.json")["rows"]]
    _write_csv(data / "codegen.csv", rows[0].keys(), rows)


def drift(results: Path, data: Path) -> None:
    """Energy and Casimir errors of the variational integrator and RK4 over 10^5 steps."""
    d = _read(results / "energy_drift.json")
    rows = [{"system": system, "quantity": q, **errors}
            for system in ("rigid_body", "heavy_top")
            for q, errors in d[system]["errors"].items()]
    _write_csv(data / "energy_drift.csv", ("system", "quantity", "max_first_half",
                                           "max_second_half", "final"), rows)


def sweep(results: Path, data: Path) -> None:
    """A sweep of 64 so3 points: serial loop against Dask."""
    d = _read(results / "bench_sweep.json")
    keep = {"what": d["what"], "points": d["points"], "cores": d["cores"],
            "serial": d["serial"], "dask": d["dask"], "speedup": d["speedup"],
            "max_cost_difference": d["max_cost_difference_dask_vs_serial"]}
    (data / "sweep.json").write_text(json.dumps(keep, indent=1) + "\n")


def rockit(results: Path, data: Path) -> None:
    """so3 against rockit's RK4 multiple shooting: both lines and the ratios at equal
    landing accuracy."""
    d = _read(results / "bench_rockit.json")
    keep = {"ours_method": d["ours_method"], "created": d.get("created"),
            "load_average_1min": d.get("machine", {}).get("load_average_1min"),
            "equal_landing": d["equal_landing"],
            "lines": {name: [{k: r[k] for k in ("N", "seconds", "iterations",
                                                "landing_error")} for r in rows]
                      for name, rows in d["lines"].items()}}
    (data / "rockit.json").write_text(json.dumps(keep, indent=1) + "\n")


def main(argv: list[str]) -> None:
    """Refresh the tables of ``DATA`` whose results are in ``RESULTS`` (defaults: results/,
    docs/benchmarks/data/); the others are kept as they are."""
    results = Path(argv[0]) if argv else RESULTS
    data = Path(argv[1]) if len(argv) > 1 else DATA
    data.mkdir(parents=True, exist_ok=True)
    for extract in (work_precision, stability, so3_build, backends, codegen, drift, sweep,
                    rockit):
        source = results / INPUTS[extract.__name__]
        if source.exists():
            extract(results, data)
            print(f"{extract.__name__}: refreshed from {source}")
        else:
            print(f"{extract.__name__}: kept ({source} not found)")


if __name__ == "__main__":
    main(sys.argv[1:])
