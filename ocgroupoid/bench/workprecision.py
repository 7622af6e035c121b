"""Work-precision: solve time against accuracy for every method on a geometric range of N.

For one problem file: the reference cost (:mod:`~ocgroupoid.bench.reference`), then for every
method and N a timed solve (:mod:`~ocgroupoid.bench.timing`) from the start that found the
reference's minimum, one row each:

* ``seconds``: the median wall time of the repeats' solves (:mod:`~ocgroupoid.bench.timing`:
  what the caller of the built NLP waits for), ``seconds_all`` every repeat's;
  ``iterations`` (the last run's), ``iterations_all`` (every run's: a fatrop run before
  IPOPT's polish as well) and ``backend`` (who ran: ``ipopt polish after fatrop``, ...);
* ``cost_error``: ``|J - J_ref| / |J_ref|``;
* ``replay_error``: the largest replay terminal error (the controls driven through the
  continuous dynamics, the miss of every prescribed final value, in its own units).

A row in another local minimum than the reference's (:mod:`~ocgroupoid.bench.minimum`: its
cost error beyond 1e-2, its path away from the reference's, its cost nearer another minimum
the multi-start met) is flagged ``minimum: other`` and left off the chart and the
comparisons. Every method is built on every N first; then their solves run in rounds, one
of each per round (:func:`~ocgroupoid.bench.timing.interleaved`), so that a slow phase of
the machine slows every row alike. A ``+coarse`` method has rows on the grids with a
coarse grid only (:func:`method_grids`). Rows go to ``<out>/work_precision/<name>.jsonl`` as they
are read out after the rounds (an interrupt keeps the reference and the rows read out); the
summary to ``<name>.json``, the chart to ``<out>/figures/work_precision_<name>.png``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from .. import files
from ..errors import ConfigError, OcgError
from ..model.problem import Problem
from ..solve import Solution
from .chart import work_precision_chart
from .equal_accuracy import compare, headline, lines
from .methods import COARSE_FACTOR, COARSE_MIN, Method, left_out
from .minimum import OTHER_COST, OTHER_PATH, path_deviation, which_minimum
from .record import Rows, write_summary
from .reference import STEPS, check_reference_N, reference
from .timing import Setting, Timed, Trial, interleaved

DEFAULT_NS = (8, 16, 32, 64, 128)
DEFAULT_REPEATS = 3
DEFAULT_REFERENCE_N = 256
#: the error levels the summary's headline ratios are read at (or the nearest decade)
HEADLINE = {"cost_error": 1e-4, "replay_error": 1e-6}

#: hears ``(description, finished, total)`` before every solve and once at the end
Progress = Callable[[str, int, int], None]


@dataclass(frozen=True)
class Outputs:
    """The files of one run."""

    rows: Path
    summary: Path
    chart: Path


def outputs(out: Path, name: str) -> Outputs:
    return Outputs(out / "work_precision" / f"{name}.jsonl",
                   out / "work_precision" / f"{name}.json",
                   out / "figures" / f"work_precision_{name}.png")


def row(method: Method, N: int, timed: Timed, ref: dict[str, Any], finest: Solution
        ) -> dict[str, Any]:
    """The record of a timed solve (module docstring) against the reference ``ref`` and its
    finest solution, whose path tells minima apart."""
    sol = timed.solution
    d = sol.diagnostics
    rep = d.get("replay", {})
    solved = sol.status == "Solve_Succeeded"
    J_ref = ref["cost"]
    cost_error = abs(sol.cost - J_ref) / abs(J_ref) if solved else None
    deviation = path_deviation(sol, finest) if solved else None
    minimum = which_minimum(sol.cost, J_ref, deviation, [m["cost"] for m in ref["minima"]],
                            ref["start_cost"]) if deviation is not None else None  # (solved)
    return {"kind": "row", "method": method.label, "scheme": method.scheme,
            "retraction": method.retraction, "N": N, "status": sol.status,
            "success": sol.success, "cost": sol.cost, "iterations": sol.iterations,
            "iterations_all": sum(r["iterations"] for r in d["runs"]), "backend": sol.backend,
            "seconds": timed.median, "seconds_all": timed.seconds,
            "build_seconds": timed.build_seconds, "start": timed.start,
            "cost_error": cost_error,
            "replay_error": rep.get("max_terminal_error") if solved else None,
            "replay_errors": rep.get("terminal_error", {}),
            "manifold_distance": max(d["manifold_distance"].values(), default=0.0),
            "path_deviation": deviation, "minimum": minimum,
            "hint": sol.hint}


def error_row(method: Method, N: int, error: OcgError) -> dict[str, Any]:
    """The record of a solve that raised before IPOPT returned (the message says why)."""
    return {"kind": "row", "method": method.label, "scheme": method.scheme,
            "retraction": method.retraction, "N": N, "status": "error", "success": False,
            "cost": None, "seconds": None, "cost_error": None, "replay_error": None,
            "minimum": None, "hint": str(error)}


def method_grids(method: Method, Ns: list[int]) -> list[int]:
    """The grids of ``Ns`` a method is timed on: all, and for a ``+coarse`` method those with
    a coarse grid (:meth:`Method.coarse_N`; on the others it would time the cold solve of the
    method without ``+coarse`` again). ConfigError when none has."""
    mine = [N for N in Ns if not method.coarse or method.coarse_N(N) is not None]
    if not mine:
        smallest = COARSE_MIN * COARSE_FACTOR
        raise ConfigError(f"--schemes {method.label}: no --N of at least {smallest} (it "
                          f"solves N/{COARSE_FACTOR} >= {COARSE_MIN} first); add a finer N "
                          "or drop +coarse")
    return mine


def check_methods(problem: Problem, methods: list[Method], setting: Setting, N: int) -> None:
    """Build every method once on N intervals: a method that does not apply to the problem
    is a ConfigError naming it, before anything is timed."""
    for m in methods:
        try:
            setting.compile(problem, m, N)
        except OcgError as e:
            raise type(e)(f"--schemes {m.label}: {e}") from None


def units(problem: Problem) -> str:
    """The units of the prescribed final values, e.g. ``R: rad, Omega: rad/s``."""
    lab = problem.labels()
    found = []
    for group in ("states", "velocities"):
        for name, info in lab.get(group, {}).items():
            final = lab.get("final", {}).get(name)
            if any(final) if isinstance(final, list) else final:
                unit = next(iter(dict.fromkeys(info.get("units") or [])), "")
                found.append(f"{name}: {unit or '1'}")
    return ", ".join(found)


def work_precision(path: Path, overrides: list[str], out: Path, methods: list[Method],
                   Ns: list[int], repeats: int = DEFAULT_REPEATS,
                   reference_N: int = DEFAULT_REFERENCE_N, name: str | None = None,
                   progress: Progress = lambda *_: None) -> tuple[dict[str, Any], Outputs]:
    """Run the benchmark of one problem file (module docstring); returns the summary and
    where it was written. Raises ConfigError on bad input before anything is solved,
    SolverError when the reference does not solve; KeyboardInterrupt keeps the rows."""
    check_reference_N(reference_N)
    if reference_N <= max(Ns):
        raise ConfigError(f"--reference-N {reference_N} must be finer than the finest --N "
                          f"({max(Ns)}): the reference is measured against")
    cfg = files.load(path, overrides)
    f = cfg.file
    problem = files.build(cfg)
    name = name or Path(path).stem
    setting = Setting.of(f)
    skipped = left_out(methods, problem)
    run = [m for m in methods if m.label not in skipped]
    grids = {m: method_grids(m, Ns) for m in run}
    check_methods(problem, run, setting, min(Ns))
    where = outputs(out, name)
    total = STEPS + 2 * sum(map(len, grids.values())) + 1
    done = [0]

    def step(what: str) -> None:
        progress(f"{name}: {what}", done[0], total)
        done[0] += 1

    rows: list[dict[str, Any]] = []
    with Rows(where.rows) as jsonl:
        ref, finest = reference(problem, setting, reference_N, bool(f.solver.multistart),
                                step)
        jsonl.append({"kind": "reference", **ref})
        trials: dict[tuple[str, int], Trial | OcgError] = {}
        for m in run:
            for N in grids[m]:
                step(f"build {m.label} N={N}")
                try:
                    trials[m.label, N] = Trial(problem, m, N, setting, ref["start"])
                except OcgError as e:
                    trials[m.label, N] = e
        step("solves in rounds")
        interleaved([t for t in trials.values() if isinstance(t, Trial)], repeats,
                    lambda k, n: progress(f"{name}: round {k + 1}, {n} solves", done[0],
                                          total))
        for m in run:
            for N in grids[m]:
                step(f"{m.label} N={N}")
                trial = trials[m.label, N]
                if isinstance(trial, OcgError):  # its build failed
                    r = error_row(m, N, trial)
                else:
                    try:
                        r = row(m, N, trial.timed(), ref, finest)
                    except OcgError as e:
                        r = error_row(m, N, e)
                jsonl.append(r)
                rows.append(r)
    progress(f"{name}: chart", total, total)
    by_method = lines(rows)
    summary: dict[str, Any] = {
        "problem": name, "file": str(path), "overrides": overrides,
        "settings": {"N": Ns, "repeats": repeats, "reference_N": reference_N,
                     "methods": [m.label for m in methods], "ipopt": setting.ipopt,
                     "fatrop": setting.fatrop,
                     "time": "median wall time of the repeats' solves from one cold start, "
                             "every method and N solved in turn in rounds: the start point, "
                             "the backend's arguments (and fatrop's helper round trip, where "
                             "it has one), the solve "
                             "(build, diagnostics and replay not included)"},
        "reference": ref, "skipped": skipped,
        "other_minimum": {"cost_error": OTHER_COST, "path_deviation": OTHER_PATH},
        "replay_units": units(problem), "rows": rows,
        "equal_accuracy": {key: compare(by_method, key) for key in HEADLINE}}
    for base in sorted(m for m in by_method if m.startswith("rk4_quat") and m != "rk4_quat"):
        summary[f"equal_accuracy_{base}"] = {key: compare(by_method, key, base)
                                             for key in HEADLINE}
    summary["headline"] = {key: headline(summary["equal_accuracy"][key], level)
                           for key, level in HEADLINE.items()}
    write_summary(where.summary, summary)
    work_precision_chart(summary, where.chart)
    return summary, where
