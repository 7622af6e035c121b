"""Richardson's estimate of a discretisation error from two grids.

A scheme of order p gives ``J_N = J + C h^p + o(h^p)`` with h = T/N. Two grids N and rN
(r > 1) eliminate C: the error of the finer one is

    J_rN - J  ~  (J_rN - J_N) / (r^p - 1),

for r = 2 ``|J_2N - J_N| / (2^p - 1)`` (Richardson, 1911; Hairer, Norsett & Wanner,
*Solving ODEs I*, §II.4). It holds once both grids are in the asymptotic regime, which a
third grid, or the replay's terminal errors at both, confirms: their ratio r^q gives the
order q observed.
"""

from __future__ import annotations

import math
from itertools import pairwise
from typing import Any


def richardson_error(fine: float, coarse: float, order: float, ratio: float = 2.0) -> float:
    """``|J_fine - J_coarse| / (ratio^order - 1)``: the error of the value on the finer grid
    (``ratio`` times as many intervals) for a method of ``order``."""
    return abs(fine - coarse) / (ratio ** order - 1.0)


def observed_order(coarse_error: float, fine_error: float, ratio: float = 2.0
                   ) -> float | None:
    """``log_ratio(e_coarse / e_fine)``: the order at which errors (or the differences of
    successive values) fall from one grid to the next ``ratio`` times finer; None when
    either is zero or not finite (no rate to observe)."""
    if not (coarse_error > 0 and fine_error > 0 and math.isfinite(coarse_error)
            and math.isfinite(fine_error)):
        return None
    return math.log(coarse_error / fine_error, ratio)


def observed_orders(errors: list[float], ratio: float = 2.0) -> list[float | None]:
    """:func:`observed_order` of every pair of neighbours in ``errors``, measured on grids
    each ``ratio`` times finer than the last (one fewer than the errors)."""
    return [observed_order(coarse, fine, ratio) for coarse, fine in pairwise(errors)]


def relative(error: float, value: float) -> float:
    """``error / |value|`` (the error itself when the value is 0)."""
    return error / abs(value) if value != 0 else error


def estimate(cost: float, coarse_cost: float, N: int, coarse_N: int, order: float,
             nominal_order: int) -> dict[str, Any]:
    """The ``error_estimate`` entry of a Solution's diagnostics: the Richardson error of
    ``cost`` on N intervals from ``coarse_cost`` on ``coarse_N``, absolute and relative,
    with the order used (``order``, at most the scheme's ``nominal_order``)."""
    error = richardson_error(cost, coarse_cost, order, N / coarse_N)
    return {"cost": error, "cost_relative": relative(error, cost), "method": "Richardson",
            "N": [coarse_N, N], "costs": [coarse_cost, cost], "order": order,
            "scheme_order": nominal_order}
