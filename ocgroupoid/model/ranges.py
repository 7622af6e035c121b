"""The ranges a problem's numbers lie in: one table for the problem files and the C driver.

Double precision holds about 16 significant digits. The NLP adds a problem's numbers to its
rotations' and unit vectors' (of order 1), and IPOPT resolves its rows to ~1e-8 of their
size; a number far beyond that scale makes the NLP singular or overflow (an SVD that does not
converge, "KKT matrix singular", Invalid_Number_Detected) rather than fail with a message. So:

- a physical parameter the model requires positive (inertias, masses, radii) lies in
  [1e-12, 1e12], and its components within a factor :data:`RATIO` of each other;
- any other parameter, boundary value, bound or weight lies within +-:data:`SCALE`;
- the final time lies in :data:`T_RANGE`.

Beyond 1e12, a number next to one of order 1 keeps fewer than 4 of its 16 digits (1e12 x
2.2e-16 = 2.2e-4). The problem files check these ranges (``files``), and the exported C
driver checks its parameter files against the same table, generated from :func:`block_range`
(``export``), with the same messages (:meth:`Range.problem`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Any, Sequence

from . import values as checks

#: the largest magnitude of a parameter, boundary value, bound side or weight
SCALE = 1e12
#: the largest ratio between the components of a positive parameter
RATIO = 1e12
#: the final times a problem may state (seconds, or the model's unit of time): beyond them
#: the step h = T/N under- or overflows the scaling of the NLP (SVD and LAPACK failures)
T_RANGE = (1e-6, 1e6)

#: the largest problem file or parameter file (bytes): a few kilobytes of text is plenty
FILE_BYTES = 1_000_000

#: the kinds of range, as the C table numbers them (ocg_params.c)
SIGNED, POSITIVE, TIME = 0, 1, 2


def _g(x: float) -> str:
    return f"{x:g}"


@dataclass(frozen=True)
class Range:
    """Where the numbers of one key lie: ``kind`` (:data:`SIGNED`, :data:`POSITIVE`,
    :data:`TIME`), the interval [lo, hi] and, for a positive vector, the largest ratio of its
    components (0: none)."""

    kind: int
    lo: float
    hi: float
    ratio: float = 0.0

    def problem(self, key: str, numbers: Sequence[float]) -> str | None:
        """The message for the first number of ``key`` outside the range, or None. The C
        driver prints the same (ocg_params.c)."""
        many = len(numbers) > 1
        for i, v in enumerate(numbers):
            what = f"component {i}" if many else "value"
            if self.kind == TIME and not self.lo <= v <= self.hi:
                return (f"{key} = {_g(v)} is outside [{_g(self.lo)}, {_g(self.hi)}], the "
                        "range of times the NLP's scaling tolerates; rescale the units of time "
                        "(and the parameters with them)")
            if self.kind == POSITIVE and not v > 0:
                return f"{key}: {what} must be > 0, got {v!r}"
            if not self.lo <= v <= self.hi:
                return (f"{key}: {what} is {_g(v)}, outside [{_g(self.lo)}, {_g(self.hi)}], the "
                        "scale double precision resolves next to the problem's other numbers; "
                        "rescale its units")
        if self.ratio and many:
            small, large = min(numbers), max(numbers)
            if large > self.ratio * small:
                return (f"{key}: its components span a factor {_g(large / small)} ({_g(small)} "
                        f"to {_g(large)}), beyond the {_g(self.ratio)} double precision "
                        "resolves (the smaller keep fewer than 4 digits next to the larger); "
                        "bring them closer")
        return None


SIGNED_RANGE = Range(SIGNED, -SCALE, SCALE)
POSITIVE_RANGE = Range(POSITIVE, 1.0 / SCALE, SCALE, RATIO)
TIME_RANGE = Range(TIME, *T_RANGE)


def block_range(key: str, kind: str, positive: bool) -> Range:
    """The range of a value block of an instance (``nlp.parameters.ValueBlock``: its key
    and kind; ``positive``: a parameter the model requires > 0)."""
    if kind == "horizon":
        return TIME_RANGE
    return POSITIVE_RANGE if positive else SIGNED_RANGE


def positive_parameters(schema: type[Any]) -> list[str]:
    """The fields of a model's ``parameters`` schema (pydantic) that must be > 0, as the
    problem files validate them (:func:`~ocgroupoid.model.values.positive`, ``Positive3``...):
    their range is :data:`POSITIVE_RANGE`."""
    out = []
    for name, info in getattr(schema, "model_fields", {}).items():
        for meta in info.metadata:
            func = getattr(meta, "func", None)
            if func is checks.positive or (isinstance(func, partial) and func.func is
                                           checks.check_vector and func.keywords.get("positive")):
                out.append(name)
    return out
