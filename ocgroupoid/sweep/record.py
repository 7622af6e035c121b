"""The record of one point: its values, how the solve went, and where its solution came from.

A record is a flat dict of JSON values: written as ``points/<id>.json`` (the resume marker),
one row of the sweep's table.
"""

from __future__ import annotations

import os
import socket
from typing import Any

from ..errors import OcgError
from ..solve import Solution
from .spec import Point

#: statuses of points that never reached IPOPT
INVALID = "invalid"  # the problem file rejects the point's values
ERROR = "error"  # building or solving raised (the message says what)
WORKER_LOST = "worker_lost"  # the Dask task died (e.g. its worker process was killed)


def worker() -> str:
    """``host:pid`` of the process solving, to see how the points were spread."""
    return f"{socket.gethostname()}:{os.getpid()}"


def _base(point: Point) -> dict[str, Any]:
    return {"id": point.id, "index": list(point.index), "values": point.values}


def solved(point: Point, sol: Solution, built: bool, warm: bool, seconds: float
           ) -> dict[str, Any]:
    """The record of a point IPOPT ran on (``success`` may be False).

    ``build_seconds`` is the time this point spent building the NLP: 0 when a compiled one
    was reused (``nlp_built`` False). ``start`` labels the guess the reported solution came
    from (a geodesic, a multi-start guess, or ``warm from <id>``), ``minima`` counts the
    distinct local minima met.
    """
    replay = sol.diagnostics.get("replay", {})
    return {**_base(point), "status": sol.status, "success": sol.success, "cost": sol.cost,
            "iterations": sol.iterations, "solve_seconds": sol.solve_seconds,
            "build_seconds": sol.build_seconds if built else 0.0, "nlp_built": built,
            "start": sol.discretization.get("start", ""), "warm": warm,
            "minima": len(sol.minima), "replay_error": replay.get("max_terminal_error"),
            "message": "" if sol.success else sol.hint, "seconds": seconds,
            "worker": worker()}


def failed(point: Point, status: str, message: str, seconds: float = 0.0,
           built: bool = False) -> dict[str, Any]:
    """The record of a point that has no solution: ``status`` is INVALID, ERROR or
    WORKER_LOST and ``message`` says why."""
    return {**_base(point), "status": status, "success": False, "cost": None,
            "iterations": 0, "solve_seconds": 0.0, "build_seconds": 0.0, "nlp_built": built,
            "start": "", "warm": False, "minima": 0, "replay_error": None,
            "message": message, "seconds": seconds, "worker": worker()}


def describe(err: BaseException) -> str:
    """An error as a message: ocgroupoid's own say cause and fix; others get their type."""
    return str(err) if isinstance(err, OcgError) else f"{type(err).__name__}: {err}"
