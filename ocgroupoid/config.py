"""Problem files: YAML, validated by pydantic, errors that name the key, the line and the fix.

A problem file is data::

    model: rigid_body            # a registered model (ocgroupoid list)
    parameters: {inertia: [1, 2, 3]}
    horizon: {T: 5.0, N: 64}
    initial: {R: identity, Omega: [0, 0, 0]}
    final:   {R: {axis_angle: {axis: [1, 2, 3], angle: 2.5}}, Omega: [0, 0, 0]}
    discretization: {retraction: cayley}
    solver: {ipopt: {tol: 1.0e-10}, multistart: false}

``load`` reads it (``yaml.safe_load`` only), applies ``--set key=value`` overrides (the value
parsed as YAML), validates everything, and ``build`` turns it into a Problem. A boundary key
left out, or written null (also per component: ``[0, 0, null]``), is free.
"""

from __future__ import annotations

import difflib
from functools import partial
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import yaml
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError

from .errors import ConfigError
from .lie import so3

# ------------------------------------------------------------------ value types


def _number(v: Any, what: str = "value") -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValueError(f"{what} must be a number, got {v!r}; write e.g. 1.0")
    if not np.isfinite(v):
        raise ValueError(f"{what} must be finite, got {v!r}; write a finite number")
    return float(v)


def _positive(v: Any, what: str = "value") -> float:
    x = _number(v, what)
    if x <= 0:
        raise ValueError(f"{what} must be > 0, got {x}")
    return x


Number = Annotated[float, BeforeValidator(_number)]
PositiveNumber = Annotated[float, BeforeValidator(_positive)]


def check_vector(v: Any, n: int, allow_none: bool = False, positive: bool = False
                 ) -> list[Any]:
    """A list of n finite numbers (null components allowed when ``allow_none``)."""
    if not isinstance(v, (list, tuple)) or len(v) != n:
        raise ValueError(f"expected a list of {n} numbers, got {v!r}")
    out: list[float | None] = []
    for i, c in enumerate(v):
        if c is None and allow_none:
            out.append(None)
            continue
        if c is None:
            raise ValueError(f"component {i} is null; give a number")
        x = _number(c, f"component {i}")
        if positive and x <= 0:
            raise ValueError(f"component {i} must be > 0, got {x}")
        out.append(x)
    return out


def _vector(n: int, allow_none: bool = False, positive: bool = False) -> Any:
    return Annotated[list, BeforeValidator(partial(check_vector, n=n, allow_none=allow_none,
                                                   positive=positive))]


Vector3 = _vector(3)
Vector3Free = _vector(3, allow_none=True)
Vector2 = _vector(2)
Vector2Free = _vector(2, allow_none=True)
Positive3 = _vector(3, positive=True)
Positive2 = _vector(2, positive=True)

ROTATION_FORMS = ("identity, {rotvec: [x, y, z]}, {axis_angle: {axis: [x, y, z], angle: a}}, "
                  "{quaternion: [w, x, y, z]} or {matrix: [[..], [..], [..]]}")


def parse_rotation(v: Any) -> np.ndarray:
    """A rotation in any of the documented forms, as a 3 x 3 matrix."""
    if isinstance(v, np.ndarray) and v.shape == (3, 3):
        return so3.from_matrix(v)
    if v == "identity":
        return np.eye(3)
    if not isinstance(v, dict) or len(v) != 1:
        raise ValueError(f"a rotation is {ROTATION_FORMS}; got {v!r}")
    (kind, val), = v.items()
    try:
        if kind == "rotvec":
            return so3.from_rotvec(check_vector(n=3, v=val))
        if kind == "axis_angle":
            if not isinstance(val, dict) or set(val) != {"axis", "angle"}:
                raise ValueError("axis_angle needs exactly the keys axis and angle")
            axis = check_vector(n=3, v=val["axis"])
            return so3.from_axis_angle(axis, _number(val["angle"], "angle"))
        if kind == "quaternion":
            return so3.from_quaternion(check_vector(n=4, v=val))
        if kind == "matrix":
            if not isinstance(val, list) or len(val) != 3:
                raise ValueError("matrix needs 3 rows of 3 numbers")
            return so3.from_matrix([check_vector(n=3, v=r) for r in val])
    except ConfigError as err:
        raise ValueError(str(err)) from None
    close = difflib.get_close_matches(str(kind), ["rotvec", "axis_angle", "quaternion", "matrix"], 1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise ValueError(f"unknown rotation form {kind!r}{hint} A rotation is {ROTATION_FORMS}")


Rotation = Annotated[Any, BeforeValidator(parse_rotation)]


def _unit3(v: Any) -> list[float]:
    vec = np.array(check_vector(n=3, v=v))
    n = float(np.linalg.norm(vec))
    if abs(n - 1.0) > 1e-6:
        raise ValueError(f"must be a unit vector, |v| = {n:.6g}; normalise it")
    return (vec / n).tolist()


UnitVector3 = Annotated[list, BeforeValidator(_unit3)]


class Strict(BaseModel):
    """Unknown keys are errors; values are checked, not coerced from booleans."""

    model_config = ConfigDict(extra="forbid", frozen=True, arbitrary_types_allowed=True)


def _positive_time(v: Any) -> float:
    return _positive(v, "T")


class Horizon(Strict):
    """Final time and number of intervals."""

    T: Annotated[float, BeforeValidator(_positive_time)] = Field(
        description="final time (> 0)")
    N: Annotated[int, Field(strict=True, ge=2, description="number of intervals (>= 2)")]


class DiscretizationSection(Strict):
    """Retraction of the group factors and rule of the constraints."""

    retraction: Literal["cayley", "exp", "first_order"] = Field(
        "cayley", description="cayley (default), exp, or first_order (the seeds' rule)")
    rule: str = Field("midpoint", description="discretisation rule of the constraints")


class SolverSection(Strict):
    """IPOPT options and the globalisation strategy."""

    ipopt: dict[str, str | int | float] = Field(
        default_factory=dict, description="options passed to IPOPT (e.g. tol, max_iter)")
    multistart: bool | Annotated[int, Field(strict=True, ge=0)] = Field(
        False, description="true, or the number of perturbed starts on top of the geodesics")
    continuation: list[Annotated[int, Field(strict=True, ge=2)]] = Field(
        default_factory=list, description="coarser N solved first, e.g. [16, 32]")


class OutputSection(Strict):
    """Where the CLI writes its results (overridden by --out/--plot)."""

    file: str | None = Field(None, description="solution JSON path")
    plot: str | None = Field(None, description="PNG path for the plot")


class ProblemFile(Strict):
    """The top level of a problem file."""

    model: str = Field(description="a built-in model (see `ocgroupoid list`) or custom")
    name: str | None = Field(None, description="problem name (default: the file's stem)")
    definition: dict[str, Any] | None = Field(
        None, description="model: custom only — groupoid, Lagrangian, cost, constraints")
    parameters: dict[str, Any] = Field(default_factory=dict, description="model parameters")
    horizon: Horizon
    initial: dict[str, Any] = Field(default_factory=dict, description="initial conditions")
    final: dict[str, Any] = Field(default_factory=dict, description="final conditions")
    discretization: DiscretizationSection = Field(default_factory=DiscretizationSection)
    solver: SolverSection = Field(default_factory=SolverSection)
    output: OutputSection = Field(default_factory=OutputSection)


# ------------------------------------------------------------------ loading


@dataclass
class Config:
    """A validated problem file and its model's sections."""

    path: Path | None
    file: ProblemFile
    spec: Any  # the ModelSpec (registered, or built from a custom definition)
    parameters: BaseModel
    initial: BaseModel
    final: BaseModel
    raw: dict[str, Any] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return self.file.name or (self.path.stem if self.path else self.file.model)


def _lines(node: yaml.Node | None, prefix: tuple = ()) -> dict[tuple, int]:
    """Map every key path of a composed YAML document to its 1-based line."""
    out: dict[tuple, int] = {}
    if isinstance(node, yaml.MappingNode):
        for k, v in node.value:
            path = (*prefix, k.value)
            out[path] = k.start_mark.line + 1
            out.update(_lines(v, path))
    elif isinstance(node, yaml.SequenceNode):
        for i, v in enumerate(node.value):
            out[(*prefix, i)] = v.start_mark.line + 1
            out.update(_lines(v, (*prefix, i)))
    return out


def read_yaml(path: str | Path) -> tuple[dict[str, Any], dict[tuple, int]]:
    """Safe-load a problem file; return the data and the line of every key."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as err:
        raise ConfigError(f"{path}: cannot read ({err.strerror}); check the path") from None
    if b"\x00" in raw:
        raise ConfigError(f"{path}: this is a binary file, not YAML; give a .yaml problem file")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: not UTF-8 text; give a .yaml problem file") from None
    try:
        data = yaml.safe_load(text)
        lines = _lines(yaml.compose(text))
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f":{mark.line + 1}:{mark.column + 1}" if mark else ""
        problem = getattr(err, "problem", None) or str(err)
        raise ConfigError(f"{path}{where}: invalid YAML ({problem}); check indentation, "
                          "colons and brackets") from None
    if data is None:
        raise ConfigError(f"{path}: the file is empty; a problem file needs at least the keys "
                          "model and horizon (see problems/ for examples)")
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: the top level must be a mapping of keys (model, horizon, "
                          f"...), got a {type(data).__name__}")
    return data, lines


def apply_override(data: dict[str, Any], assignment: str) -> tuple[str, ...]:
    """Apply ``key.path=value`` (value parsed as YAML) to nested dicts; return the path."""
    if "=" not in assignment:
        raise ConfigError(f"--set {assignment!r}: expected KEY=VALUE, e.g. horizon.N=128")
    key, _, text = assignment.partition("=")
    path = tuple(p for p in key.strip().split(".") if p)
    if not path:
        raise ConfigError(f"--set {assignment!r}: empty key; write e.g. horizon.N=128")
    try:
        value = yaml.safe_load(text) if text.strip() else None
    except yaml.YAMLError as err:
        raise ConfigError(f"--set {key}: the value {text!r} is not valid YAML "
                          f"({getattr(err, 'problem', err)}); quote it or fix the brackets"
                          ) from None
    node = data
    for part in path[:-1]:
        if not isinstance(node.get(part), dict):
            node[part] = {}
        node = node[part]
    node[path[-1]] = value
    return path


class Locator:
    """``file:line`` of a key path, or a note that the value came from --set."""

    def __init__(self, path: str | Path | None, lines: dict[tuple, int],
                 overridden: set[tuple]) -> None:
        self.file = str(path) if path is not None else "<problem>"
        self.lines, self.overridden = lines, overridden

    def __call__(self, *key: Any) -> str:
        if any(key[: len(o)] == o or o[: len(key)] == key for o in self.overridden):
            return f"{self.file} (--set {'.'.join(map(str, key))})"
        for n in range(len(key), 0, -1):
            line = self.lines.get(tuple(key[:n]))
            if line:
                return f"{self.file}:{line}"
        return self.file


def _fix(err: dict[str, Any], key: str, known: list[str] | None) -> str:
    """A message with the fix for one pydantic error."""
    kind, value = err["type"], err.get("input")
    ctx = err.get("ctx") or {}
    last = key.rsplit(".", 1)[-1]
    if kind == "extra_forbidden":
        close = difflib.get_close_matches(last, known or [], 1)
        hint = f" did you mean {close[0]!r}?" if close else ""
        return (f"unknown key {key!r};{hint} keys allowed here: {', '.join(known or [])}")
    if kind == "missing":
        return f"missing key {key!r}; add it (see problems/ for an example)"
    if kind in ("int_type", "int_from_float", "int_parsing"):
        return f"{key} must be an integer (e.g. 64), got {value!r}"
    if kind in ("greater_than_equal", "greater_than"):
        bound = ctx.get("ge", ctx.get("gt"))
        op = ">=" if kind == "greater_than_equal" else ">"
        return f"{key} must be {op} {bound}, got {value!r}; raise it"
    if kind == "literal_error":
        options = [o.strip(" '") for o in str(ctx.get("expected", "")).replace(" or ", ", ")
                   .split(",")]
        close = difflib.get_close_matches(str(value), options, 1)
        hint = f" did you mean {close[0]!r}?" if close else ""
        return f"{key}: {value!r} is not allowed;{hint} choose one of {', '.join(options)}"
    if kind in ("dict_type", "model_type", "model_attributes_type"):
        return f"{key} must be a mapping (key: value), got {value!r}"
    if kind == "list_type":
        return f"{key} must be a list, e.g. [1, 2, 3], got {value!r}"
    if kind in ("string_type",):
        return f"{key} must be text, got {value!r}; quote it"
    if kind in ("bool_type", "bool_parsing"):
        return f"{key} must be true or false, got {value!r}"
    if kind in ("float_type", "float_parsing", "finite_number"):
        return f"{key} must be a finite number, got {value!r}"
    msg = str(err["msg"]).removeprefix("Value error, ")
    return f"{key}: {msg}"


def _fields_at(model: type[BaseModel], loc: tuple) -> list[str] | None:
    """Field names of the (sub)model that owns the last key of ``loc``."""
    current: Any = model
    for part in loc[:-1]:
        fields = getattr(current, "model_fields", None)
        if not fields or part not in fields:
            return None
        ann = fields[part].annotation
        current = ann if isinstance(ann, type) and issubclass(ann, BaseModel) else None
        if current is None:
            return None
    return list(getattr(current, "model_fields", {}) or [])


def validate(model: type[BaseModel], data: Any, prefix: tuple, locate: Locator) -> Any:
    """``model.model_validate(data)`` with errors that name the key, the line and the fix."""
    try:
        return model.model_validate(data if data is not None else {})
    except ValidationError as exc:
        messages = []
        for err in exc.errors():
            loc = tuple(x for x in err["loc"] if not str(x).startswith("function-"))
            path = (*prefix, *loc)
            key = ".".join(map(str, path))
            messages.append(f"{locate(*path)}: {_fix(err, key, _fields_at(model, loc))}")
        raise ConfigError("\n".join(messages)) from None


def load(path: str | Path | None = None, overrides: list[str] | None = None,
         data: dict[str, Any] | None = None) -> Config:
    """Read, override and validate a problem file (or an already parsed dict)."""
    from .models import MODELS

    lines: dict[tuple, int] = {}
    if data is None:
        if path is None:
            raise ConfigError("give a problem file path or data")
        data, lines = read_yaml(path)
    data = dict(data)
    overridden = {apply_override(data, a) for a in overrides or []}
    locate = Locator(path, lines, overridden)
    top = validate(ProblemFile, data, (), locate)
    if top.model == "custom":
        from .custom import Definition, spec as custom_spec

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
    sections = [validate(schema, data.get(key), (key,), locate)
                for key, schema in (("parameters", spec.parameters), ("initial", spec.initial),
                                    ("final", spec.final))]
    return Config(Path(path) if path is not None else None, top, spec, *sections, raw=data)


def build(cfg: Config) -> Any:
    """The Problem a validated Config describes."""
    return cfg.spec.build(cfg.parameters, cfg.initial, cfg.final, cfg.file.horizon.T, cfg.name)
