"""Whether a solution is in the reference's local minimum: by its cost, its path, and the
minima the reference's multi-start met.

A cost error beyond :data:`OTHER_COST` alone does not tell a coarse grid from another
minimum (RK4 shooting on 8 intervals is off by 1.5% in the same minimum). A row is in the
reference's minimum when any of these holds:

1. its relative cost error is at most :data:`OTHER_COST`;
2. its path follows the reference's: the path deviation, over the states and the nodes,

       max_k |s_k - s_ref(t_k)| / max_k |s_ref(t_k) - s_ref(0)|

   (Frobenius norm for matrices; the reference's nodes matched by the fraction k/N of the
   horizon, so a free final time scales both alike) is at most :data:`OTHER_PATH`;
3. of the distinct minima the reference's multi-start met on its coarsest grid, the one
   nearest in cost is the reference's (a mirror image of equal cost, which the path alone
   would call another minimum, is the same minimum for the cost).

Otherwise it is in another minimum (the long way round, a rotor left at rest, a point
IPOPT stopped at far from any minimum met).
"""

from __future__ import annotations

import numpy as np

from ..solve import Solution

OTHER_COST = 1e-2  # relative cost error
OTHER_PATH = 0.2  # path deviation, relative to the reference's motion
SAME_COST = 1e-6  # relative: two costs this close are one minimum's


def path_deviation(sol: Solution, ref: Solution) -> float:
    """The path deviation of ``sol`` from ``ref`` (module docstring, item 2)."""
    k_ref = np.rint(np.arange(sol.N + 1) * ref.N / sol.N).astype(int)
    worst = 0.0
    for name, s in sol.states.items():
        r = np.asarray(ref.states[name], dtype=float)
        s = np.asarray(s, dtype=float)
        motion = np.max(np.linalg.norm((r - r[0]).reshape(len(r), -1), axis=1))
        miss = np.max(np.linalg.norm((s - r[k_ref]).reshape(len(s), -1), axis=1))
        worst = max(worst, float(miss / max(motion, 1e-6)))
    return worst


def which_minimum(cost: float, J_ref: float, deviation: float, minima: list[float],
                  own: float) -> str:
    """``same`` or ``other`` (module docstring); ``minima`` are the costs of the minima met
    on the reference's coarsest grid, ``own`` the reference's among them."""
    if abs(cost - J_ref) <= OTHER_COST * abs(J_ref) or deviation <= OTHER_PATH:
        return "same"
    nearest = min(minima, key=lambda m: abs(cost - m), default=own)
    return "same" if abs(nearest - own) <= SAME_COST * max(1.0, abs(own)) else "other"
