"""Which backends a solve runs, in turn: the first, and the next when one fails.

``solver.backend: fatrop`` runs fatrop, and when it fails (its Riccati recursion needs every
stage's reduced Hessian positive definite and regularises until it is: slow or stuck on
some nonconvex problems) IPOPT from the same start with the time left. A run that used up
the time, or was interrupted, ends the turn: the next backend would have no time either.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable, Sequence

import numpy as np

from .base import INTERRUPTED, TIMED_OUT, Backend, Run, Start

#: ``objective(x, p)``: the cost of a point, for a run stopped before it had one
Objective = Callable[[np.ndarray, np.ndarray], float]


def in_turn(backends: Sequence[Backend], start: Start, objective: Objective
            ) -> tuple[Run, str]:
    """The run of the first backend that succeeds or is stopped by the time or an
    interrupt, else of the last; with the label of who produced it (``fatrop``,
    ``ipopt``, ``ipopt after fatrop``). Its seconds count every run."""
    names: list[str] = []
    spent = 0.0
    for i, backend in enumerate(backends):
        run = backend.run(start)
        names.insert(0, backend.name)
        spent += run.seconds
        last = i == len(backends) - 1
        if last or run.success or run.status in (TIMED_OUT, INTERRUPTED):
            if not run.success and not last:  # stopped: the cost of the point it reached
                run = replace(run, f=objective(run.x, start.p))
            return replace(run, seconds=spent), " after ".join(names)
    raise ValueError("no backend to run")
