"""What a sweep varies: grid axes, random draws, and the points they span.

``--grid KEY=START:STOP:COUNT`` is ``numpy.linspace`` (integers when START and STOP are
integers and every value is one, so ``horizon.N=16:64:4`` gives 16, 32, 48, 64);
``--grid KEY=[v1, v2, ...]`` is a YAML list whose items may be nested YAML (rotations such
as ``{rotvec: [0, 0, 1]}``). ``--random KEY=normal(mu, sigma)`` or ``uniform(a, b)`` draws
``--samples M`` values with ``--seed S``. The points are the cartesian product of the axes
(the last axis varies fastest), times the M samples when draws are given (the same samples
at every grid point). Nothing is evaluated: the text is split, read as YAML
(the problem files' safe loader: ``1e-6`` is a number there too) or matched by a regular
expression.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import re
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np
import yaml

from ..errors import ConfigError
from ..files.source import Refusal, parse_yaml

KEY = re.compile(r"[A-Za-z_]\w*(\.\w+)*")
LAW = re.compile(r"\s*(\w+)\s*\(([^()]*)\)\s*")
LAWS = {"normal": "normal(mu, sigma)", "uniform": "uniform(a, b)"}
GRID_FORMS = "KEY=START:STOP:COUNT (e.g. horizon.T=2:6:5) or KEY=[v1, v2, ...]"


def yaml_text(value: Any) -> str:
    """``value`` as one line of YAML that ``yaml.safe_load`` reads back exactly.

    PyYAML writes floats with ``repr`` (the shortest exact form) and ``1.0e-05`` rather than
    ``1e-05``, which YAML 1.1 would read as a string.
    """
    text = yaml.safe_dump(value, default_flow_style=True, width=1 << 30).strip()
    return text[:-3].rstrip() if text.endswith("\n...") else text


def plain(value: Any) -> Any:
    """NumPy scalars and arrays as Python numbers and lists (what YAML can write)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def check_key(key: str, option: str) -> str:
    """A dotted key of the problem file (``final.R.axis_angle.angle``), or ConfigError."""
    key = key.strip()
    if not KEY.fullmatch(key):
        raise ConfigError(f"{option} {key!r}: expected a dotted key of the problem file before "
                          "'=', e.g. horizon.T or final.R.axis_angle.angle")
    return key


def _number(text: str, what: str) -> int | float:
    """A finite number written as Python writes ints and floats (``2``, ``-0.5``, ``1e-3``)."""
    t = text.strip()
    for kind in (int, float):
        try:
            value = kind(t)
        except ValueError:
            continue
        if math.isfinite(value):
            return value
    raise ConfigError(f"{what}: {t!r} is not a finite number")


@dataclass(frozen=True)
class Axis:
    """One grid axis: a key of the problem file and its values (plain YAML data)."""

    key: str
    values: tuple[Any, ...]


def linspace(key: str, text: str) -> Axis:
    """The axis of ``START:STOP:COUNT``."""
    parts = text.split(":")
    if len(parts) != 3:
        raise ConfigError(f"--grid {key}={text}: expected {GRID_FORMS}")
    what = f"--grid {key}={text}"
    start, stop = _number(parts[0], what), _number(parts[1], what)
    count = _number(parts[2], what)
    if not isinstance(count, int) or count < 1:
        raise ConfigError(f"{what}: COUNT must be an integer >= 1, got {parts[2].strip()!r}")
    values = np.linspace(start, stop, count)
    if isinstance(start, int) and isinstance(stop, int) and np.all(values == np.round(values)):
        return Axis(key, tuple(int(v) for v in np.round(values)))
    return Axis(key, tuple(float(v) for v in values))


def listed(key: str, values: Any, text: str) -> Axis:
    """The axis of an explicit, non-empty list of values."""
    if not isinstance(values, (list, tuple)) or not values:
        raise ConfigError(f"--grid {key}={text}: expected a non-empty YAML list [v1, v2, ...]")
    return Axis(key, tuple(plain(v) for v in values))


def axis(key: str, spec: str | Sequence[Any]) -> Axis:
    """An axis from ``START:STOP:COUNT``, a YAML list text, or a Python sequence; its
    values must differ (a point is its values: it is solved once)."""
    key = check_key(key, "--grid")
    if not isinstance(spec, str):
        out = listed(key, list(spec), repr(spec))
    elif spec.strip().startswith("["):
        try:
            out = listed(key, parse_yaml(spec)[0], spec.strip())
        except Refusal as err:
            raise ConfigError(f"--grid {key}={spec.strip()}: {err.message}") from None
        except yaml.YAMLError as err:
            raise ConfigError(f"--grid {key}={spec.strip()}: not a valid YAML list "
                              f"({getattr(err, 'problem', err)}); check the brackets") from None
    else:
        out = linspace(key, spec.strip())
    texts = [yaml_text(v) for v in out.values]
    twice = sorted({t for t in texts if texts.count(t) > 1})
    if twice:
        raise ConfigError(f"--grid {key}: {', '.join(twice)} given more than once; give "
                          "distinct values (START:STOP:1 for a single one)")
    return out


@dataclass(frozen=True)
class Draw:
    """A random key: ``normal(mu, sigma)`` or ``uniform(a, b)``."""

    key: str
    law: str
    a: float
    b: float

    def sample(self, rng: np.random.Generator, count: int) -> list[float]:
        """``count`` values from the law (NumPy's Generator: reproducible from the seed)."""
        if self.law == "normal":
            return rng.normal(self.a, self.b, count).tolist()
        return rng.uniform(self.a, self.b, count).tolist()


def draw(key: str, text: str) -> Draw:
    """Parse ``normal(mu, sigma)`` (sigma >= 0) or ``uniform(a, b)`` (a < b)."""
    key = check_key(key, "--random")
    what = f"--random {key}={text.strip()}"
    m = LAW.fullmatch(text)
    if m is None or m.group(1) not in LAWS or len(m.group(2).split(",")) != 2:
        raise ConfigError(f"{what}: expected {' or '.join(LAWS.values())} with numbers")
    law = m.group(1)
    a, b = (float(_number(t, what)) for t in m.group(2).split(","))
    if law == "normal" and b < 0:
        raise ConfigError(f"{what}: sigma must be >= 0, got {b:g}")
    if law == "uniform" and not a < b:
        raise ConfigError(f"{what}: uniform(a, b) needs a < b, got a={a:g}, b={b:g}")
    return Draw(key, law, a, b)


def split(assignment: str, option: str) -> tuple[str, str]:
    """``KEY=SPEC`` into its two sides."""
    key, eq, spec = assignment.partition("=")
    if not eq or not spec.strip():
        example = GRID_FORMS if option == "--grid" else "KEY=normal(mu, sigma)"
        raise ConfigError(f"{option} {assignment!r}: expected {example}")
    return key, spec


def axes(grid: Mapping[str, Any] | Sequence[str] | None) -> list[Axis]:
    """Grid axes from ``{key: spec}`` or from ``["KEY=SPEC", ...]`` (the CLI's form)."""
    items = grid.items() if isinstance(grid, Mapping) else \
        [split(a, "--grid") for a in grid or []]
    return [axis(k, v) for k, v in items]


def draws(random: Mapping[str, str] | Sequence[str] | None) -> list[Draw]:
    """Random keys from ``{key: "normal(0, 1)"}`` or from ``["KEY=LAW", ...]``."""
    items = random.items() if isinstance(random, Mapping) else \
        [split(a, "--random") for a in random or []]
    return [draw(k, v) for k, v in items]


@dataclass(frozen=True)
class Point:
    """One problem of the sweep: values of the swept keys and where it sits on the grid.

    ``index`` holds the grid indices, then the sample number (absent without draws);
    ``id`` is a digest of the base problem and the values, so it is the same in every run.
    """

    id: str
    index: tuple[int, ...]
    values: dict[str, Any]

    @property
    def overrides(self) -> list[str]:
        """The values as ``--set`` assignments."""
        return [f"{k}={yaml_text(v)}" for k, v in self.values.items()]


def point_id(base: str, values: Mapping[str, Any]) -> str:
    """A short digest of the base problem (file and --set) and the point's values."""
    text = json.dumps([base, [[k, yaml_text(v)] for k, v in values.items()]])
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def points(grid: Sequence[Axis], random: Sequence[Draw], samples: int | None, seed: int,
           base: str) -> list[Point]:
    """Every point: the grid's cartesian product, each with the M random samples."""
    keys = [a.key for a in grid] + [d.key for d in random]
    twice = sorted({k for k in keys if keys.count(k) > 1})
    if twice:
        raise ConfigError(f"{', '.join(twice)} swept twice; give each key one --grid or "
                          "--random")
    if random and (samples is None or samples < 1):
        raise ConfigError("--random needs --samples M (M >= 1), the number of draws")
    if samples is not None and not random:
        raise ConfigError("--samples counts random draws; add --random KEY=normal(mu, sigma)"
                          " or leave --samples out")
    if not keys:
        raise ConfigError("nothing to sweep: give --grid KEY=START:STOP:COUNT or "
                          "--random KEY=normal(mu, sigma) --samples M")
    rng = np.random.default_rng(seed)
    drawn = [d.sample(rng, samples or 0) for d in random]
    out = []
    for grid_index in itertools.product(*(range(len(a.values)) for a in grid)):
        values = {a.key: a.values[i] for a, i in zip(grid, grid_index)}
        for s in range(samples or 1) if random else [None]:
            v = dict(values)
            if s is not None:
                v.update({d.key: column[s] for d, column in zip(random, drawn)})
            index = grid_index if s is None else (*grid_index, s)
            out.append(Point(point_id(base, v), tuple(index), v))
    return out
