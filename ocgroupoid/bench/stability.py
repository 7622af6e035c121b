"""Stability map: where each method fails, over manoeuvres and grids.

For one problem file with an SO(3) state (``R`` by default): rest-to-rest slews about a
fixed axis (the body y axis by default: the pitch of ZYX Euler angles passes 90 degrees
from an angle of pi/2) of every angle, on every N, by every method; each solve from the
first geodesic guess (``multistart`` to use the problem file's multi-start instead), judged
by :mod:`~ocgroupoid.bench.outcome`: converged, unverified, off group, off target, other
minimum or failed, with the message a user gets.

The final condition is written ``final.R = {axis_angle: {axis, angle}}``. An angle beyond
pi is the rotation by 2 pi - angle about the opposite axis: the slew turns the short way, the
other way round (the net turn recorded shows it; the reference does the same).

Per angle the reference is order4 (cayley) on :data:`REFERENCE_N` intervals from every
start of the multi-start: its cost and its net turn. Cells go to
``<out>/stability/<name>.jsonl`` as they finish; the summary to ``<name>.json``, the map to
``<out>/figures/stability_<name>.png``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .. import files
from ..errors import ConfigError, OcgError, SolverError
from ..lie import SO3
from ..model.problem import Problem
from .methods import Method
from .outcome import OUTCOMES, error_cell, judge, net_turn
from .record import Rows, write_summary
from .stability_chart import stability_chart
from .timing import Setting
from .workprecision import Outputs, Progress

DEFAULT_ANGLES = (0.5, 1.0, 1.5, 2.0, 2.6, 3.0, 3.5)
DEFAULT_NS = (2, 4, 8, 16, 32, 64)
DEFAULT_AXIS = (0.0, 1.0, 0.0)
REFERENCE_N = 128


def outputs(out: Path, name: str) -> Outputs:
    return Outputs(out / "stability" / f"{name}.jsonl", out / "stability" / f"{name}.json",
                   out / "figures" / f"stability_{name}.png")


def manoeuvre(state: str, axis: np.ndarray, angle: float) -> str:
    """The ``--set`` override of the final attitude: ``angle`` rad about ``axis``."""
    return (f"final.{state}={{axis_angle: {{axis: [{', '.join(f'{a:g}' for a in axis)}], "
            f"angle: {angle!r}}}}}")


def reference(problem: Problem, setting: Setting, state: str, axis: np.ndarray
              ) -> dict[str, Any]:
    """order4 (cayley) on REFERENCE_N intervals, every start of the multi-start."""
    solver = setting.compile(problem, Method("order4"), REFERENCE_N)
    sol = solver.solve(multistart=True)
    if sol.status != "Solve_Succeeded":
        raise SolverError(f"the reference (order4, N={REFERENCE_N}) did not solve: "
                       f"{sol.status}. {sol.hint}")
    return {"cost": sol.cost, "net_turn": net_turn(np.asarray(sol.states[state]), axis),
            "method": f"order4 (cayley), N={REFERENCE_N}, multi-start",
            "success": sol.success, "start": sol.discretization["start"]}


def check_state(cfg: files.Config, state: str) -> None:
    """The manoeuvre's state must be an SO(3) factor of the problem."""
    problem = files.build(cfg)
    found = {f.state: f for f in problem.groupoid.factors}
    if state not in found or getattr(found[state], "group", None) is not SO3 or \
            found[state].state_size != 4:
        raise ConfigError(f"--state {state}: the problem has no SO(3) state of that name "
                       f"(states: {', '.join(found)}); a stability map slews an attitude")


def stability(path: Path, overrides: list[str], out: Path, methods: list[Method],
              Ns: list[int], angles: list[float], axis: tuple[float, ...] = DEFAULT_AXIS,
              state: str = "R", multistart: bool = False, name: str | None = None,
              progress: Progress = lambda *_: None) -> tuple[dict[str, Any], Outputs]:
    """Run the stability map of one problem file (module docstring); returns the summary and
    where it was written. Raises ConfigError on bad input before anything is solved;
    KeyboardInterrupt keeps the finished cells."""
    axis_v = np.asarray(axis, dtype=float)
    if axis_v.shape != (3,) or not np.linalg.norm(axis_v) > 0:
        raise ConfigError(f"--axis: give three numbers, not all zero, got {list(axis)}")
    check_state(files.load(path, overrides), state)
    name = name or Path(path).stem
    where = outputs(out, name)
    total = len(angles) * (1 + len(methods) * len(Ns))
    done = 0
    cells: list[dict[str, Any]] = []
    references: dict[str, Any] = {}
    with Rows(where.rows) as jsonl:
        for angle in angles:
            cfg = files.load(path, [*overrides, manoeuvre(state, axis_v, angle)])
            f = cfg.file
            problem = files.build(cfg)
            setting = Setting.of(f)
            progress(f"{name}: {angle:g} rad, reference", done, total)
            ref = reference(problem, setting, state, axis_v)
            references[f"{angle:g}"] = ref
            jsonl.append({"kind": "reference", "angle": angle, **ref})
            done += 1
            for m in methods:
                for N in Ns:
                    progress(f"{name}: {angle:g} rad, {m.label} N={N}", done, total)
                    try:
                        solver = setting.compile(problem, m, N)
                        sol = solver.solve(multistart=multistart and bool(f.solver.multistart))
                        cell = judge(m, N, angle, state, axis_v, solver.transcription, sol, ref)
                    except (OcgError, RuntimeError) as e:  # RuntimeError: CasADi's
                        cell = error_cell(m, N, angle, e)
                    cell["message_missing"] = cell["outcome"] != "converged" and \
                        not cell["message"].strip()
                    jsonl.append(cell)
                    cells.append(cell)
                    done += 1
    progress(f"{name}: map", total, total)
    summary = {"problem": name, "file": str(path), "overrides": overrides,
               "settings": {"angles": angles, "N": Ns, "axis": list(axis), "state": state,
                            "methods": [m.label for m in methods], "multistart": multistart,
                            "start": "the file's multi-start" if multistart else
                            "the first geodesic guess"},
               "outcomes": list(OUTCOMES), "references": references, "cells": cells,
               "messages": messages(cells)}
    write_summary(where.summary, summary)
    stability_chart(summary, where.chart)
    return summary, where


def messages(cells: list[dict[str, Any]]) -> dict[str, dict[str, list[str]]]:
    """Per method and outcome other than converged, the distinct messages with the cells
    (angle/N) that gave them."""
    out: dict[str, dict[str, list[str]]] = {}
    for c in cells:
        if c["outcome"] == "converged":
            continue
        text = c["message"] or "(no message)"
        where = f"{c['angle']:g} rad N={c['N']}"
        out.setdefault(c["method"], {}).setdefault(f"{c['outcome']}: {text}", []).append(where)
    return out
