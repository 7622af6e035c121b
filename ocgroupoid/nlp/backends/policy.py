"""Which backends a solve runs, in turn: the first, and the next when one fails.

``solver.backend: fatrop`` runs fatrop, and when it fails (its Riccati recursion needs every
stage's reduced Hessian positive definite and regularises until it is: slow or stuck on
some nonconvex problems) IPOPT from the same start with the time left; when it stalled near
a solution (its acceptable stop), IPOPT from the point it reached, with its multipliers. A
run that used up the time, or was interrupted, ends the turn: the next backend would have no
time either; so does a run its listener stopped (at a deadline, a Ctrl-C or a further
start's budget, which would stop the next one as well).
Between the two a rescue may run (:class:`~ocgroupoid.solve.CompiledProblem` gives order4
one: order2 on the same grid, then fatrop again from its solution).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable, Sequence

import numpy as np

from .base import ACCEPTABLE, INTERRUPTED, LISTENER_STOP, TIMED_OUT, Attempt, Backend, Run, Start

#: what ends the turn: the time used up, an interrupt, the listener's stop (the same
#: listener would stop the next backend)
ENDS_TURN = (TIMED_OUT, INTERRUPTED, LISTENER_STOP)
#: ``objective(x, p)``: the cost of a point, for a run stopped before it had one
Objective = Callable[[np.ndarray, np.ndarray], float]
#: ``rescue(start, failed)``: another way from the same start, tried after the first
#: backend's run ``failed`` and before the next backend; its run and the label of who
#: produced it, or None (not tried)
Rescue = Callable[[Start, Run], "tuple[Run, str] | None"]


def in_turn(backends: Sequence[Backend], start: Start, objective: Objective,
            rescue: Rescue | None = None) -> tuple[Run, str]:
    """The run of the first backend that succeeds or is stopped by the time or an
    interrupt, else of the last; with the label of who produced it (``fatrop``,
    ``ipopt``, ``ipopt after fatrop``). Its seconds count every run, and its ``earlier``
    names the runs before it with their status and iterations. A run that stopped at an
    acceptable point (:data:`ACCEPTABLE`: near a solution, converging slowly) hands the
    next backend its point and multipliers, a warm start (``ipopt polish after fatrop``);
    after any other failure the next starts from ``start``. ``rescue`` runs after the first
    backend failed of itself, not near a solution, before the next: its run (in this NLP's
    variables) is the answer if it succeeded (its label, e.g. ``fatrop through order2``) or
    was stopped; else the next backend runs (``ipopt after order2 rescue after fatrop``)."""
    names: list[str] = []
    earlier: list[Attempt] = []
    spent = 0.0
    polish = False  # the previous run stopped at an acceptable point: start from it
    for i, backend in enumerate(backends):
        run = backend.run(start)
        names.insert(0, f"{backend.name} polish" if polish else backend.name)
        spent += run.seconds
        last = i == len(backends) - 1
        stopped = run.status in ENDS_TURN
        polish = run.status == ACCEPTABLE
        if not (last or run.success or stopped or polish) and i == 0 and rescue is not None:
            rescued = rescue(start, run)
            if rescued is not None:
                earlier.append((names[0], run.status, run.iterations))
                run, label = rescued
                earlier += run.earlier  # the rescue's runs before its last
                polish = run.status == ACCEPTABLE
                spent += run.seconds
                names.insert(0, label)
                stopped = run.status in ENDS_TURN
                if run.success:
                    return replace(run, seconds=spent, earlier=tuple(earlier)), label
        if last or run.success or stopped:
            if not run.success and not last:  # stopped: the cost of the point it reached
                run = replace(run, f=objective(run.x, start.p))
            return replace(run, seconds=spent, earlier=tuple(earlier)), " after ".join(names)
        earlier.append((names[0], run.status, run.iterations))
        if polish:
            start = replace(start, x0=run.x, lam_g0=run.lam_g, lam_x0=run.lam_x)
    raise ValueError("no backend to run")
