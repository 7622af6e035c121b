"""The keyword shortcuts of ``og.solve``/``og.compile_problem`` turned into the two objects, in one
place.

``og.solve(problem, N=16, scheme="order4", jit=True)`` reads as
``og.solve(problem, og.Method(N=16, scheme="order4"), og.SolverOptions(jit=True))``;
keywords given beside an object replace its fields (``og.compile_problem(problem, method, N=32)``).
The positional form of older code, ``compile_problem(problem, N, retraction, rule, ipopt, scheme,
steps, jit, backend, max_seconds)``, is read here too.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from ..errors import ConfigError
from .method import METHOD_KEYS, Method
from .options import OPTION_KEYS, SolverOptions

#: the positional options of older code after the problem, in order
POSITIONAL = ("N", "retraction", "rule", "ipopt", "scheme", "steps", "jit", "backend",
              "max_seconds")


def choose(method: Method | int | None = None, options: SolverOptions | str | None = None,
           *positional: Any, **keywords: Any) -> tuple[Method, SolverOptions]:
    """The method and the solver options of a call: the objects given (default: every
    option's default), their fields replaced by the keywords that are not None; or, when
    ``method`` is a number of intervals, the positional form (:data:`POSITIONAL`)."""
    given = dict(keywords)
    if method is not None and not isinstance(method, Method):
        legacy = (method, options, *positional)
        if len(legacy) > len(POSITIONAL):
            raise ConfigError(f"{len(legacy)} positional options given after the problem; "
                              f"the most are {len(POSITIONAL)} ({', '.join(POSITIONAL)})")
        for key, value in zip(POSITIONAL, legacy):
            if key in given:
                raise ConfigError(f"{key} is given twice: by position and by keyword")
            given[key] = value
        method = options = None
    elif positional or isinstance(options, str):
        raise ConfigError("after an og.Method, give og.SolverOptions, or the options by "
                          "keyword (retraction=..., rule=..., backend=...)")
    unknown = sorted(set(given) - set(METHOD_KEYS) - set(OPTION_KEYS))
    if unknown:
        raise ConfigError(f"unknown option {unknown[0]!r}; a method takes "
                          f"{', '.join(METHOD_KEYS)}, the solver options "
                          f"{', '.join(OPTION_KEYS)}")
    chosen = {k: v for k, v in given.items() if v is not None}
    if options is not None and not isinstance(options, SolverOptions):
        raise ConfigError(f"options must be og.SolverOptions, got {type(options).__name__}")
    return (_with(method or Method(), {k: v for k, v in chosen.items() if k in METHOD_KEYS}),
            _with(options or SolverOptions(),
                  {k: v for k, v in chosen.items() if k in OPTION_KEYS}))


def _with(obj: Any, changes: dict[str, Any]) -> Any:
    """``obj`` with ``changes`` (validated again), or itself when there are none."""
    return replace(obj, **changes) if changes else obj
