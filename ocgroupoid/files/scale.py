"""The numbers of a problem file against the ranges of :mod:`~ocgroupoid.model.ranges`.

After the sections are validated (types, lengths, signs), every number written in
``parameters``, ``initial``, ``final``, ``bounds`` and ``objective`` is checked against the
scale double precision resolves, and a positive parameter's components against the ratio it
resolves: such a problem is refused with the key, the line and the scale, before anything
is built (beyond it the NLP is singular or overflows: SVDs that do not converge, "KKT matrix
singular", Invalid_Number_Detected).
"""

from __future__ import annotations

from typing import Any, Iterator

from ..errors import ConfigError
from ..model.ranges import POSITIVE_RANGE, SIGNED_RANGE, Range, positive_parameters
from ..systems.registry import ModelSpec
from .source import Locator


def _numbers(value: Any) -> list[float] | None:
    """The numbers of a number or of a (nested) list holding only numbers and nulls, or None
    for anything else (a text, a mapping)."""
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return [float(value)]
    if isinstance(value, (list, tuple)):
        out: list[float] = []
        for v in value:
            if v is None:
                continue
            inner = _numbers(v)
            if inner is None:
                return None
            out += inner
        return out
    return None


def _leaves(value: Any, path: tuple) -> Iterator[tuple[tuple, list[float]]]:
    """(key path, numbers) of every number or list of numbers under ``value``."""
    numbers = _numbers(value)
    if numbers is not None:
        if numbers:
            yield path, numbers
    elif isinstance(value, dict):
        for k, v in value.items():
            yield from _leaves(v, (*path, k))
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            yield from _leaves(v, (*path, i))


def _check(rng: Range, path: tuple, numbers: list[float], locate: Locator,
           fix: str = "") -> None:
    message = rng.problem(".".join(map(str, path)), numbers)
    if message is not None:
        raise ConfigError(f"{locate(*path)}: {message}{fix}")


def check_scale(data: dict[str, Any], spec: ModelSpec, locate: Locator) -> None:
    """Refuse a number of a validated problem file outside its range (module docstring)."""
    positive = set(positive_parameters(spec.parameters))
    for name, value in (data.get("parameters") or {}).items():
        numbers = _numbers(value)
        if numbers:
            _check(POSITIVE_RANGE if name in positive else SIGNED_RANGE,
                   ("parameters", name), numbers, locate)
    for section in ("initial", "final", "objective"):
        for path, numbers in _leaves(data.get(section) or {}, (section,)):
            _check(SIGNED_RANGE, path, numbers, locate)
    for name, value in (data.get("bounds") or {}).items():
        for path, numbers in _leaves(value, ("bounds", name)):
            _check(SIGNED_RANGE, path[:2], numbers, locate, " (write null for an open side)")
