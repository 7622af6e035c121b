"""docsgen.extract refreshes the benchmark tables a run measured and keeps the others."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

from docsgen import extract


def _summary(level_ratios: dict[float, float], cost: float) -> dict[str, Any]:
    """A work-precision summary with rk4_quat+jit comparisons at the given landing levels."""
    comparisons = [{"level": lv, "ours": "order4@fatrop+jit", "ratio": r, "lower_bound": False}
                   for lv, r in level_ratios.items()]
    head = {"level": 1e-6, "ours": "order4@fatrop+jit", "ratio": 9.0, "lower_bound": False}
    return {"headline": {"cost_error": {**head, "level": 1e-4}, "replay_error": head},
            "equal_accuracy_rk4_quat+jit": {"cost_error": comparisons,
                                            "replay_error": comparisons},
            "created": "today", "reference": {"cost": cost},
            "rows": [{"kind": "row", "method": "order4@fatrop+jit", "N": 8, "success": True,
                      "iterations": 4, "seconds": 0.001, "cost_error": 1e-3,
                      "replay_error": 1e-4}, {"kind": "reference"}]}


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open() as f:
        return list(csv.DictReader(f))


def test_a_best_run_replaces_its_rows_and_keeps_the_schemes_run(tmp_path: Path) -> None:
    results, data = tmp_path / "results", tmp_path / "data"
    (results / "work_precision").mkdir(parents=True)
    (data / "work_precision").mkdir(parents=True)
    old = {"so3": {"schemes": {"created": "before", "reference": 1.0},
                   "best": {"created": "before", "reference": 1.0}}}
    (data / "work_precision.json").write_text(json.dumps(old))
    with (data / "work_precision" / "so3.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, extract.WP_COLUMNS)
        w.writeheader()
        for run in ("schemes", "best"):
            w.writerow({"run": run, "method": "old", "N": 8})
    (results / "work_precision" / "so3_backends.json").write_text(
        json.dumps(_summary({1e-4: 2.0, 1e-6: 3.0, 1e-7: 4.0}, 0.5)))

    out = extract.work_precision(results, data)

    assert out["so3"]["schemes"] == old["so3"]["schemes"]  # not measured again: kept
    best = out["so3"]["best"]
    assert best["created"] == "today" and best["reference"] == 0.5
    landing = best["landing_vs_jit"]
    assert landing["1e-04"]["ratio"] == 2.0 and landing["1e-06"]["ratio"] == 3.0
    assert landing["1e-08"] is None  # the run did not reach it: no number made up
    assert "landing_vs_jit_coarse" not in best  # the run had no rk4_quat+jit+coarse
    rows = _rows(data / "work_precision" / "so3.csv")
    assert [(r["run"], r["method"]) for r in rows] == [("schemes", "old"),
                                                       ("best", "order4@fatrop+jit")]
    assert json.loads((data / "work_precision.json").read_text()) == out


def test_main_keeps_the_tables_whose_results_are_missing(tmp_path: Path, capsys: Any) -> None:
    results, data = tmp_path / "results", tmp_path / "data"
    results.mkdir()
    data.mkdir()
    (data / "sweep.json").write_text("{}")
    extract.main([str(results), str(data)])
    assert (data / "sweep.json").read_text() == "{}"
    assert "sweep: kept" in capsys.readouterr().out


def test_a_best_run_with_the_coarse_baseline_is_set_against_it_too(tmp_path: Path) -> None:
    results, data = tmp_path / "results", tmp_path / "data"
    (results / "work_precision").mkdir(parents=True)
    summary = _summary({1e-4: 2.0}, 0.5)
    summary["equal_accuracy_rk4_quat+jit+coarse"] = {"replay_error": [
        {"level": 1e-6, "ours": "order4@fatrop+jit+coarse", "ratio": 1.5,
         "lower_bound": False}]}
    (results / "work_precision" / "so3_backends.json").write_text(json.dumps(summary))
    best = extract.work_precision(results, data)["so3"]["best"]
    assert best["landing_vs_jit"]["1e-04"]["ratio"] == 2.0
    coarse = best["landing_vs_jit_coarse"]
    assert coarse["1e-06"] == {"level": 1e-6, "ours": "order4@fatrop+jit+coarse",
                               "ratio": 1.5, "lower_bound": False}
    assert coarse["1e-04"] is None and coarse["1e-08"] is None
