"""The values a problem states — numbers, vectors, rotations, poses, directions — validated once.

Plain validators (:func:`number`, :func:`check_vector`, :func:`check_horizon`) serve the
Python API; the pydantic types built on them (:data:`Number`, :data:`Rotation`, ...) serve
the problem files' sections. Every message says what is wrong and how to write it instead.
"""

from __future__ import annotations

import reprlib
from functools import partial
from typing import Annotated, Any

import numpy as np
from pydantic import BaseModel, BeforeValidator, ConfigDict

from ..errors import ConfigError
from ..lie import se3, so3

_REPR = reprlib.Repr()
_REPR.maxlist = _REPR.maxtuple = 6
_REPR.maxdict, _REPR.maxlevel, _REPR.maxstring, _REPR.maxother = 4, 2, 60, 60


def short(value: Any) -> str:
    """``repr(value)`` cut to a line for messages: a list that an alias expands to thousands
    of values, or a long text, is shown by its beginning."""
    return _REPR.repr(value)


def number(v: Any, what: str = "value") -> float:
    """A finite real number (booleans and text are refused)."""
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise ConfigError(f"{what} must be a number, got {short(v)}; write e.g. 1.0")
    try:
        x = float(v)
    except OverflowError:  # an integer beyond the range of a float
        raise ConfigError(f"{what} is an integer too large for a float (beyond 1.8e+308); "
                          "write a smaller number") from None
    if not np.isfinite(x):
        raise ConfigError(f"{what} must be finite, got {v!r}; write a finite number")
    return x


def positive(v: Any, what: str = "value") -> float:
    """A finite number > 0."""
    x = number(v, what)
    if x <= 0:
        raise ConfigError(f"{what} must be > 0, got {x}")
    return x


def check_vector(v: Any, n: int, allow_none: bool = False, positive: bool = False,
                 what: str = "") -> list[Any]:
    """n finite numbers (a list, tuple or array; a scalar when n = 1), with None in single
    components when ``allow_none``."""
    prefix = f"{what}: " if what else ""
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if n == 1 and not isinstance(v, (list, tuple)) and v is not None:
        v = [v]
    if not isinstance(v, (list, tuple)) or len(v) != n:
        raise ConfigError(f"{prefix}expected a list of {n} numbers, got {short(v)}")
    out: list[float | None] = []
    for i, c in enumerate(v):
        if c is None:
            if not allow_none:
                raise ConfigError(f"{prefix}component {i} is null; give a number "
                                  "(single components cannot be left free here)")
            out.append(None)
            continue
        x = number(c, f"{prefix}component {i}")
        if positive and x <= 0:
            raise ConfigError(f"{prefix}component {i} must be > 0, got {x}")
        out.append(x)
    return out


def check_horizon(T: Any) -> float:
    """A finite, positive horizon T."""
    try:
        return positive(T, "horizon T")
    except ConfigError:
        raise ConfigError(f"horizon T must be finite and > 0, got {T!r}") from None


def unit_vector(v: Any) -> list[float]:
    """Three numbers of unit length (to 1e-6), normalised."""
    vec = np.array(check_vector(v, 3))
    scale = float(np.max(np.abs(vec)))  # the norm of a huge vector without overflow
    n = scale * float(np.linalg.norm(vec / scale)) if scale > 0 else 0.0
    if abs(n - 1.0) > 1e-6:
        raise ConfigError(f"must be a unit vector, |v| = {n:.6g}; normalise it")
    return (vec / n).tolist()


# ------------------------------------------------------------------ pydantic types


class Strict(BaseModel):
    """Unknown keys are errors; values are checked, not coerced from booleans."""

    model_config = ConfigDict(extra="forbid", frozen=True, arbitrary_types_allowed=True)


def _named(check: Any, name: str) -> Any:
    return partial(check, what=name)


Number = Annotated[float, BeforeValidator(number)]
PositiveNumber = Annotated[float, BeforeValidator(positive)]
Horizon = Annotated[float, BeforeValidator(_named(positive, "T"))]


def vector(n: int, allow_none: bool = False, positive: bool = False) -> Any:
    """The pydantic type of n numbers (None components allowed when ``allow_none``)."""
    return Annotated[list, BeforeValidator(partial(check_vector, n=n, allow_none=allow_none,
                                                   positive=positive))]


Vector6Free = vector(6, allow_none=True)
Vector3 = vector(3)
Vector3Free = vector(3, allow_none=True)
Vector2 = vector(2)
Vector2Free = vector(2, allow_none=True)
Positive3 = vector(3, positive=True)
Positive2 = vector(2, positive=True)
Rotation = Annotated[Any, BeforeValidator(so3.from_spec)]
Pose = Annotated[Any, BeforeValidator(se3.from_spec)]  # an SE(3) element, 4 x 4
UnitVector3 = Annotated[list, BeforeValidator(unit_vector)]

__all__ = ["number", "positive", "check_vector", "check_horizon", "unit_vector", "Strict",
           "Number", "PositiveNumber", "Horizon", "vector", "Vector3", "Vector3Free",
           "Vector2", "Vector2Free", "Vector6Free", "Positive3", "Positive2", "Rotation", "Pose",
           "UnitVector3", "short"]
