"""The worker's task: solve a chunk of points of one structure, reusing one compiled NLP.

A worker process keeps the last few compiled Solvers by structure key, so a chunk builds
the NLP only if this process has not built it already; every point is solved through
``CompiledProblem.solve(params, initial, final, T)`` with its own values, which never rebuilds.

Warm starts (``warm``): the points of a chunk are solved in sweep order, and a point whose
grid neighbour (one step back or forward along one axis, same random sample) was solved
successfully in this chunk may start from that solution: its point and multipliers (IPOPT's
primal-dual warm start, :attr:`~ocgroupoid.nlp.backends.ipopt.IpoptBackend.warm_solver`).
``"fallback"`` (the default) starts cold (the geodesic guess, or the file's multi-start and
continuation) and tries the neighbour only when the cold start fails, so a point that solves
cold gives exactly the result of solving it alone, whatever the chunking. ``"first"`` tries
the neighbour first and falls back to the cold start (not with multi-start, which would lose
its other starts); ``"off"`` never uses neighbours.
"""

from __future__ import annotations

import time
from collections import OrderedDict
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Literal

from ..errors import BoundaryError, ConfigError
from ..model.problem import Problem
from ..nlp import Guess
from ..solve import CompiledProblem, Solution, compile_problem, interpolate
from . import record
from .source import Source
from .spec import Point

if TYPE_CHECKING:
    from ..files import Config

Warm = Literal["fallback", "first", "off"]
WARM_MODES: tuple[str, ...] = ("fallback", "first", "off")
#: compiled NLPs a worker process keeps (a sweep over N holds one per N)
CACHE_SIZE = 4
_solvers: OrderedDict[str, CompiledProblem] = OrderedDict()


@dataclass(frozen=True)
class Task:
    """A chunk: points of one structure, in sweep order, and how to warm-start them
    (``grid_axes``: how many leading entries of a point's index are grid indices)."""

    source: Source
    structure: str
    points: tuple[Point, ...]
    grid_axes: int
    warm: Warm = "fallback"


@dataclass(frozen=True)
class Outcome:
    """What a worker sends back for one point: its record and its solution JSON, if any."""

    record: dict[str, Any]
    solution: str | None


def arguments(pb: Problem) -> dict[str, Any]:
    """The :meth:`CompiledProblem.solve` arguments that make an NLP of the same structure solve
    ``pb``: its parameters, prescribed boundary values and T (free quantities left out)."""
    def given(*parts: dict[str, Any]) -> dict[str, Any]:
        return {k: v for part in parts for k, v in part.items() if v is not None}

    return {"params": {name: prm.value for name, prm in pb.params.items()},
            "initial": given(pb.start.states, pb.start.velocities),
            "final": given(pb.end.states, pb.end.velocities), "T": pb.T}


def _fits(solver: CompiledProblem, args: dict[str, Any]) -> bool:
    """Whether the point's boundary values prescribe the same components as the NLP's."""
    try:
        solver.transcription.pack(**args)
    except BoundaryError:
        return False
    return True


def solver_for(structure: str, pb: Problem, cfg: Config, args: dict[str, Any]
               ) -> tuple[CompiledProblem, bool]:
    """This process's compiled NLP of ``structure``, or a new one; and whether it was built.

    A BoundaryError from packing the point's values (a structure key that missed a change
    of prescribed components) also builds anew.
    """
    solver = _solvers.get(structure)
    if solver is not None and _fits(solver, args):
        _solvers.move_to_end(structure)
        return solver, False
    f = cfg.file
    if f.horizon.N == "auto":  # a grid search per point is not a sweep's compiled NLP
        raise ConfigError("horizon.N: auto searches N point by point, which a sweep does not "
                          "do: give an integer N (or sweep over horizon.N)")
    from ..files.solving import method, options

    # the file's method and options; multi-start and continuation are each attempt's own
    solver = compile_problem(pb, method(cfg),
                             replace(options(cfg), multistart=False, continuation=()))
    _solvers[structure] = solver
    _solvers.move_to_end(structure)
    while len(_solvers) > CACHE_SIZE:
        _solvers.popitem(last=False)
    return solver, True


def neighbour(point: Point, done: dict[tuple[int, ...], tuple[str, Solution]],
              grid_axes: int) -> tuple[str, Solution] | None:
    """A solved grid neighbour of ``point``: one step along one grid axis (the fastest
    axis first, the step back first), same random sample."""
    for axis in reversed(range(grid_axes)):
        for step in (-1, 1):
            index = list(point.index)
            index[axis] += step
            if tuple(index) in done:
                return done[tuple(index)]
    return None


def solve_point(task: Task, point: Point, near: tuple[str, Solution] | None
                ) -> tuple[dict[str, Any], Solution | None]:
    """Solve one point (cold and/or from ``near``, per ``task.warm``); any error becomes
    the point's record, so one bad point never stops the chunk: a value the problem file
    rejects once the problem is built (``bounds`` whose lower side exceeds the upper) is
    INVALID, anything else ERROR."""
    from ..files import build

    t0 = time.perf_counter()
    built = False
    try:
        cfg = task.source.load(point.overrides)
        pb = build(cfg)
    except ConfigError as err:
        return record.failed(point, record.INVALID, str(err), time.perf_counter() - t0), None
    except Exception as err:  # noqa: BLE001  (recorded with its type and message)
        return record.failed(point, record.ERROR, record.describe(err),
                             time.perf_counter() - t0), None
    try:
        args = arguments(pb)
        solver, built = solver_for(task.structure, pb, cfg, args)
        sol, warm = _attempts(solver, cfg, args, near, task.warm)
    except Exception as err:  # noqa: BLE001  (recorded with its type and message)
        return record.failed(point, record.ERROR, record.describe(err),
                             time.perf_counter() - t0, built), None
    return record.solved(point, sol, built, warm, time.perf_counter() - t0), sol


def _attempts(solver: CompiledProblem, cfg: Config, args: dict[str, Any],
              near: tuple[str, Solution] | None, mode: Warm) -> tuple[Solution, bool]:
    """Solve in the order ``mode`` asks; the first success, else the first attempt's result,
    and whether the result came from the neighbour."""
    s = cfg.file.solver
    # a sweep's own globalisation is the warm start from a neighbour: multi-start (the
    # default of a single solve) only where the file asks for it
    multistart = s.multistart if "multistart" in s.model_fields_set else False

    def cold() -> Solution:
        return solver.solve(**args, multistart=multistart, continuation=s.continuation or None)

    def warm() -> Solution:
        assert near is not None
        tr = solver.transcription
        sol = near[1]
        xi = interpolate(tr, sol.x, sol.p, tr.N).xi
        # primal-dual when the neighbour's NLP is this one (a chunk shares its structure)
        return solver.solve(**args, guess=Guess(f"warm from {near[0]}", xi, sol.x, sol.lam_g,
                                                sol.lam_x))

    if near is None or mode == "off":
        return cold(), False
    order = [(warm, True), (cold, False)] if mode == "first" and not multistart else \
        [(cold, False), (warm, True)]
    tried = []
    for attempt, from_near in order:
        sol = attempt()
        if sol.success:
            return sol, from_near
        tried.append((sol, from_near))
    return tried[0]


def solve_chunk(task: Task) -> list[Outcome]:
    """Solve the chunk's points in order; the Dask task (also called in-process)."""
    done: dict[tuple[int, ...], tuple[str, Solution]] = {}
    out = []
    for p in task.points:
        rec, sol = solve_point(task, p, neighbour(p, done, task.grid_axes))
        if sol is not None and sol.success:
            done[p.index] = (p.id, sol)
        out.append(Outcome(rec, sol.to_json(indent=None) if sol is not None else None))
    return out

