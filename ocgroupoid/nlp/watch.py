"""IPOPT's progress, iteration by iteration: casadi's ``iteration_callback`` of nlpsol.

:class:`Watch` is called by IPOPT after every iteration with the iterate; it passes the
iteration number, the objective and the largest constraint violation to a listener, and
stops IPOPT (status ``User_Requested_Stop``) when the listener returns True — how a Ctrl-C
ends a long solve cleanly. The listener changes per solve; the Callback object stays (casadi
holds it by reference for the solver's lifetime).
"""

from __future__ import annotations

from typing import Callable, Sequence

import casadi as ca
import numpy as np

#: ``listener(iteration, objective, infeasibility) -> stop?``
Listener = Callable[[int, float, float], bool]


class Watch(ca.Callback):
    """The iteration callback of one nlpsol (see the module docstring)."""

    def __init__(self, nx: int, ng: int, np_: int) -> None:
        ca.Callback.__init__(self)
        self.sizes = {"x": (nx, 1), "f": (1, 1), "g": (ng, 1), "lam_x": (nx, 1),
                      "lam_g": (ng, 1), "lam_p": (np_, 1)}
        self.listener: Listener | None = None
        self.lbg = self.ubg = np.zeros(ng)
        self.iteration = 0
        self.construct("watch", {})

    def get_n_in(self) -> int:
        return ca.nlpsol_n_out()

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return ca.nlpsol_out(i)

    def get_name_out(self, i: int) -> str:
        return "ret"

    def get_sparsity_in(self, i: int) -> ca.Sparsity:
        n, m = self.sizes[ca.nlpsol_out(i)]
        return ca.Sparsity.dense(n, m)

    def start(self, listener: Listener | None, lbg: np.ndarray, ubg: np.ndarray) -> None:
        """Arm for one solve with constraint bounds (lbg, ubg)."""
        self.listener, self.lbg, self.ubg, self.iteration = listener, lbg, ubg, 0

    def eval(self, arg: Sequence[ca.DM]) -> list[int]:
        if self.listener is None:
            return [0]
        g = np.array(arg[2]).ravel()
        infeasibility = float(np.max(np.maximum(self.lbg - g, g - self.ubg), initial=0.0))
        stop = self.listener(self.iteration, float(arg[1]), infeasibility)
        self.iteration += 1
        return [1 if stop else 0]
