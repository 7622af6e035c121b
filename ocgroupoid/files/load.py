"""Problem files: YAML, validated, turned into a Problem.

A problem file is data::

    model: rigid_body            # a registered model (ocgroupoid list)
    parameters: {inertia: [1, 2, 3]}
    horizon: {T: 5.0, N: 64}
    initial: {R: identity, Omega: [0, 0, 0]}
    final:   {R: {axis_angle: {axis: [1, 2, 3], angle: 2.5}}, Omega: [0, 0, 0]}
    discretization: {scheme: order2, retraction: cayley}
    solver: {ipopt: {tol: 1.0e-10}, multistart: false}

``load`` reads it (``yaml.safe_load`` only, :mod:`~ocgroupoid.files.source`), applies
``--set key=value`` overrides (the value parsed as YAML), validates everything
(:mod:`~ocgroupoid.files.schema`, the model's sections, messages from
:mod:`~ocgroupoid.files.messages`), and ``build`` turns it into a Problem. A boundary key
left out, or written null (also per component: ``[0, 0, null]``), is free. A number in
``parameters``, ``initial`` and ``final`` may be written as an expression of constants, as in
expressions: ``theta: [pi]``, ``angle: pi/2``. Every number lies within the scale double
precision resolves (:mod:`~ocgroupoid.files.scale`). What the machine can take is checked too
(:mod:`~ocgroupoid.files.limits`): N within a memory estimate, an installed linear solver.
``horizon.N: auto`` with ``solver.accuracy`` (or ``solver.replay_accuracy``) leaves N to the
search of :mod:`~ocgroupoid.solve.accuracy` (its keys checked together by :func:`check_auto`).
"""

from __future__ import annotations

import ast
import difflib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import BaseModel

from ..errors import ConfigError
from ..model.problem import Problem
from ..nlp.schemes import SCHEME_NAMES
from ..systems import MODELS
from ..systems.registry import ModelSpec
from . import bounds, limits
from .custom import Definition, spec as custom_spec
from .expressions import CONSTANTS, FUNCTIONS, compile_expression
from .messages import validate
from .scale import check_scale
from .schema import ProblemFile
from .source import Locator, apply_override, read_yaml


@dataclass
class Config:
    """A validated problem file and its model's sections."""

    path: Path | None
    file: ProblemFile
    spec: ModelSpec  # registered, or built from a custom definition
    parameters: BaseModel
    initial: BaseModel
    final: BaseModel
    raw: dict[str, Any] = field(default_factory=dict)
    locate: Locator = field(default_factory=lambda: Locator(None, {}, set()))

    @property
    def name(self) -> str:
        return self.file.name or (self.path.stem if self.path else self.file.model)


def load(path: str | Path | None = None, overrides: list[str] | None = None,
         data: dict[str, Any] | None = None) -> Config:
    """Read, override and validate a problem file (or an already parsed dict)."""
    lines: dict[tuple, int] = {}
    if data is None:
        if path is None:
            raise ConfigError("give a problem file path or data")
        data, lines = read_yaml(path)
    data = dict(data)
    overridden = {apply_override(data, a) for a in overrides or []}
    locate = Locator(path, lines, overridden)
    for key in CONSTANT_SECTIONS:
        if key in data:
            data[key] = constants(data[key], (key,), locate)
    top = validate(ProblemFile, data, (), locate)
    check_auto(top, locate)
    finer = [n for n in top.solver.continuation  # none with N: auto
             if not isinstance(n, str) and n >= top.horizon.N]
    if finer:
        raise ConfigError(f"{locate('solver', 'continuation')}: solver.continuation {finer} "
                          f"must be coarser than horizon.N = {top.horizon.N}; lower or drop "
                          "them")
    limits.check_ipopt_options(top.solver.ipopt, locate)
    limits.check_fatrop_options(top.solver.fatrop, locate)
    if top.model == "custom":
        if top.definition is None:
            raise ConfigError(f"{locate('model')}: model: custom needs a definition section "
                              "(groupoid, cost, ...); see problems/custom_rigid_body.yaml")
        spec = custom_spec(validate(Definition, top.definition, ("definition",), locate),
                           locate)
    elif top.model in MODELS:
        if top.definition is not None:
            raise ConfigError(f"{locate('definition')}: definition is only read for "
                              f"model: custom; remove it or set model: custom")
        spec = MODELS[top.model]
    else:
        close = difflib.get_close_matches(top.model, [*MODELS, "custom"], 1)
        hint = f" did you mean {close[0]!r}?" if close else ""
        raise ConfigError(f"{locate('model')}: unknown model {top.model!r};{hint} "
                          f"choose one of {', '.join(sorted(MODELS))} or custom")
    parameters, initial, final = [
        validate(schema, data.get(key), (key,), locate)
        for key, schema in (("parameters", spec.parameters), ("initial", spec.initial),
                            ("final", spec.final))]
    check_scale(data, spec, locate)
    return Config(Path(path) if path is not None else None, top, spec, parameters, initial,
                  final, raw=data, locate=locate)


CONSTANT_SECTIONS = ("parameters", "initial", "final")  # numbers may be written as pi/2


def check_auto(top: ProblemFile, locate: Locator) -> None:
    """The keys of ``horizon.N: auto`` (:mod:`~ocgroupoid.solve.accuracy`) go together: it needs
    a target (``solver.accuracy`` or ``solver.replay_accuracy``), the targets and
    ``scheme: auto`` need it, and it replaces ``solver.continuation`` and adaptive steps."""
    s, d = top.solver, top.discretization
    targets = [k for k in ("accuracy", "replay_accuracy") if getattr(s, k) is not None]
    if top.horizon.N != "auto":
        if targets:
            raise ConfigError(f"{locate('solver', targets[0])}: solver.{targets[0]} is the "
                              "target of horizon.N: auto; write N: auto, or remove it")
        if d.scheme == "auto":
            raise ConfigError(f"{locate('discretization', 'scheme')}: scheme: auto is chosen "
                              "with horizon.N: auto; write N: auto, or choose one of "
                              f"{', '.join(SCHEME_NAMES)}")
        return
    if not targets:
        raise ConfigError(f"{locate('horizon', 'N')}: horizon.N: auto needs a target: "
                          "solver.accuracy (a relative cost error, e.g. 1.0e-6) or "
                          "solver.replay_accuracy (the replay's terminal error); add one")
    if s.continuation:
        raise ConfigError(f"{locate('solver', 'continuation')}: horizon.N: auto solves its own "
                          "grids, each from the one before; remove solver.continuation")
    if d.steps == "adaptive":
        raise ConfigError(f"{locate('discretization', 'steps')}: horizon.N: auto compares "
                          "uniform grids; remove steps: adaptive or give a fixed N")


def fixed_grid(cfg: Config, command: str) -> int:
    """``horizon.N``, refused with the fix when it is ``auto`` (``command`` needs one grid)."""
    f = cfg.file
    if f.horizon.N != "auto":
        return f.horizon.N
    sets = ["horizon.N=128"] + [f"solver.{k}=null" for k in ("accuracy", "replay_accuracy")
                                if getattr(f.solver, k) is not None]
    if f.discretization.scheme == "auto":
        sets.append("discretization.scheme=order4")
    raise ConfigError(f"{cfg.locate('horizon', 'N')}: {command} needs a fixed grid, not "
                      "horizon.N: auto: run `ocgroupoid solve` to pick N, then write it, "
                      f"e.g. {' '.join('--set ' + a for a in sets)}")


def constants(value: Any, path: tuple, locate: Locator) -> Any:
    """``value`` with every text that is an expression of constants only (``pi/2``,
    ``-2*pi``) replaced by its number; other texts (``identity``) are left to the schemas."""
    if isinstance(value, dict):
        return {k: constants(v, (*path, k), locate) for k, v in value.items()}
    if isinstance(value, list):
        return [constants(v, (*path, i), locate) for i, v in enumerate(value)]
    if not isinstance(value, str) or not _only_constants(value):
        return value
    where = f"{locate(*path)}: {'.'.join(map(str, path))}"
    expr = compile_expression(value, {}, where)
    if expr.numel() != 1:
        return value
    return float(expr)


def _only_constants(text: str) -> bool:
    """True when ``text`` parses as an expression whose names are constants and functions."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return False
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    return bool(names) and names <= set(CONSTANTS) | set(FUNCTIONS) or \
        (not names and not isinstance(tree.body, ast.Constant))


def build(cfg: Config) -> Problem:
    """The Problem a validated Config describes: the model's, with the file's horizon,
    objective weights and bounds; refused when its N exceeds the memory or the time
    (``solver.max_seconds``) a solve may take (:mod:`~ocgroupoid.files.limits`)."""
    f, locate = cfg.file, cfg.locate
    horizon = f.horizon
    pb = cfg.spec.build(cfg.parameters, cfg.initial, cfg.final, horizon.guess, cfg.name)
    starts = 0 if f.solver.multistart is False else \
        3 if f.solver.multistart is True else int(f.solver.multistart)
    limits.check_size(pb, horizon.grids[1] if horizon.N == "auto" else horizon.N, starts,
                      locate("horizon", "N"))
    if horizon.N != "auto":  # each grid of N: auto is held to solver.max_seconds as it runs
        limits.check_time(pb, horizon.N, f.solver.multistart, f.solver.backend,
                          f.solver.max_seconds, locate("horizon", "N"))
    try:
        if horizon.T == "free":
            pb.horizon(horizon.guess, free=True, T_min=horizon.T_min, T_max=horizon.T_max)
        if f.objective.time > 0 and horizon.T != "free":
            raise ConfigError(f"{locate('objective', 'time')}: a time weight needs a free "
                              "final time: write horizon.T: free with T_min and T_max")
        if (f.objective.effort, f.objective.time) != (1.0, 0.0):
            pb.objective(f.objective.effort, f.objective.time)
    except ConfigError as err:
        raise ConfigError(f"{locate('horizon')}: {err}") from None
    bounds.apply(pb, f.bounds, locate)
    return pb


def estimate(cfg: Config, pb: Problem) -> limits.Estimate | None:
    """The time a solve of the file takes, about (None with ``horizon.N: auto``)."""
    f = cfg.file
    if f.horizon.N == "auto":
        return None
    return limits.estimate(pb, f.horizon.N, f.solver.multistart, f.solver.backend)
