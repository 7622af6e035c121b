"""Run one formula on NumPy and on CasADi SX/MX alike.

Every Lie-group primitive is written once with CasADi operations. Called with CasADi
symbols it builds a graph; called with NumPy arrays (or lists, floats) it evaluates through
``casadi.DM`` and hands NumPy back, column vectors flattened to 1-D.
"""

from __future__ import annotations

import functools
from typing import Any, Callable, TypeVar

import casadi as ca
import numpy as np

F = TypeVar("F", bound=Callable[..., Any])

Symbolic = (ca.SX, ca.MX)


def is_symbolic(*args: Any) -> bool:
    """True when any argument is a CasADi SX or MX expression."""
    return any(isinstance(a, Symbolic) for a in args)


def to_numpy(value: Any) -> Any:
    """DM -> ndarray; an n x 1 column becomes shape (n,), a 1 x 1 a float."""
    if isinstance(value, tuple):
        return tuple(to_numpy(v) for v in value)
    if isinstance(value, ca.DM):
        arr = np.array(value.full())
        if arr.shape == (1, 1):
            return float(arr[0, 0])
        if arr.ndim == 2 and arr.shape[1] == 1:
            return arr[:, 0]
        return arr
    return value


def _to_dm(value: Any) -> Any:
    """Arrays, lists and NumPy scalars -> DM; DM, Python numbers and other objects (the
    group of a method) unchanged."""
    if isinstance(value, (np.ndarray, list, tuple, np.generic)):
        return ca.DM(np.asarray(value, dtype=float))
    return value


def dual(fn: F) -> F:
    """Decorate a CasADi-written formula (a function or a group's method) so that NumPy
    inputs give NumPy outputs."""

    @functools.wraps(fn)
    def wrapper(*args: Any) -> Any:
        if is_symbolic(*args):
            return fn(*args)
        return to_numpy(fn(*(_to_dm(a) for a in args)))

    return wrapper  # type: ignore[return-value]


def safe_if(small: Any, taylor: Any, exact: Any) -> Any:
    """``if_else`` whose branches were both built finite (the jaxlie 'safe' trick)."""
    return ca.if_else(small, taylor, exact)


def series(x: Any, coefficients: tuple[float, ...]) -> Any:
    """``sum_k c_k x^k`` by Horner's rule (the Taylor branch of a guarded formula)."""
    out: Any = coefficients[-1]
    for c in reversed(coefficients[:-1]):
        out = out * x + c
    return out


def guarded(t2: Any, below: float, coefficients: tuple[float, ...],
            exact: Callable[[Any, Any], Any]) -> Any:
    """A function f of t with a removable singularity at t = 0, at ``t^2 = t2``: the series
    ``sum_k c_k t2^k`` below ``t2 = below``, else ``exact(t, t^2)``, evaluated at a guarded
    argument so that neither branch, nor its derivative, is NaN."""
    small = t2 < below
    safe = safe_if(small, 1.0, t2)
    return safe_if(small, series(t2, coefficients), exact(ca.sqrt(safe), safe))


def row_major(matrix: Callable[[Any], Any]) -> Callable[[Any], Any]:
    """``s -> vec(matrix(s)^T)``: a matrix-valued map flattened row-major."""
    return dual(lambda s: ca.vec(matrix(s).T))
