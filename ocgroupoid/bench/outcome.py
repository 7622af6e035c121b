"""The outcome of one solve of a stability map, judged as a user would need it judged.

In order of precedence:

* ``failed``: IPOPT did not converge (its status), or building or solving raised;
* ``other minimum``: the attitude turns another way than the reference (its net turn about
  the manoeuvre's axis differs by more than :data:`TURN` rad: the long way round);
* ``off target``: the controls replayed through the continuous dynamics miss a prescribed
  final value by more than :data:`~ocgroupoid.verify.verdict.REPLAY_TOLERANCE` (5%) of the
  distance it covers (the verdict's measure);
* ``off group``: a state is off its manifold by more than :data:`MANIFOLD`, as reported or in
  the baseline's own coordinates (:mod:`~ocgroupoid.bench.drift`);
* ``unverified``: none of these, yet the verdict rejects the solution (e.g. an Euler pitch
  near 90 degrees): its hint says why;
* ``converged``: a verified success.

Each record carries the message a user gets (the solution's hint or the exception's text).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from ..nlp.transcription import Transcription
from ..solve import Solution
from ..verify.verdict import REPLAY_TOLERANCE, scales
from .drift import coordinate_drift
from .methods import Method

OUTCOMES = ("converged", "unverified", "off group", "off target", "other minimum", "failed")
MANIFOLD = 1e-6  # distance off the group that counts as off it
TURN = 0.5  # rad: a net turn this far from the reference's goes another way round


def increments(R: np.ndarray) -> np.ndarray:
    """Rotation vectors of the body increments ``log(R_k^T R_{k+1})`` (N x 3)."""
    rel = np.einsum("kji,kjl->kil", R[:-1], R[1:])
    return Rotation.from_matrix(rel).as_rotvec()


def net_turn(R: np.ndarray, axis: np.ndarray) -> float:
    """The turn about ``axis`` summed over the steps (rad, signed): +angle the direct way,
    angle - 2 pi the other way round."""
    return float(np.sum(increments(R) @ (axis / np.linalg.norm(axis))))


def replay_miss(tr: Transcription, sol: Solution) -> float | None:
    """The replay's largest miss as a fraction of the distance covered (the verdict's
    measure); inf when the replay diverged, None without a replay."""
    rep = sol.diagnostics.get("replay", {})
    if not rep.get("available"):
        return float("inf") if "diverged" in rep.get("reason", "") else None
    scale = scales(tr, tr.readout(sol.x, sol.p), sol.p)
    return max((e / max(scale.get(n, 0.0), 1e-12) for n, e in rep["terminal_error"].items()),
               default=0.0)


def judge(method: Method, N: int, angle: float, state: str, axis: np.ndarray,
          tr: Transcription, sol: Solution, reference: dict[str, Any]) -> dict[str, Any]:
    """The record of a solve (module docstring); ``reference`` holds the manoeuvre's cost
    and net turn."""
    d = sol.diagnostics
    solved = sol.status == "Solve_Succeeded"
    R = np.asarray(sol.states[state], dtype=float)
    turn = net_turn(R, axis)
    miss = replay_miss(tr, sol) if solved else None
    drift = coordinate_drift(tr, sol)
    off = max([*d["manifold_distance"].values(), *drift.values()], default=0.0)
    if not solved:
        outcome = "failed"
    elif abs(turn - reference["net_turn"]) > TURN:
        outcome = "other minimum"
    elif miss is not None and miss > REPLAY_TOLERANCE:
        outcome = "off target"
    elif off > MANIFOLD:
        outcome = "off group"
    else:
        outcome = "converged" if sol.success else "unverified"
    return {"kind": "cell", "method": method.label, "scheme": method.scheme,
            "retraction": method.retraction, "angle": angle, "N": N, "outcome": outcome,
            "status": sol.status, "success": sol.success, "iterations": sol.iterations,
            "cost": sol.cost, "cost_error": abs(sol.cost - reference["cost"]) /
            abs(reference["cost"]) if solved else None,
            "net_turn": turn, "step_max": float(np.max(np.linalg.norm(increments(R), axis=1))),
            "replay_miss": miss, "replay_error": d.get("replay", {}).get("terminal_error"),
            "manifold_distance": d["manifold_distance"],
            "coordinate_drift": drift, "off_group": off,
            "message": sol.hint}


def error_cell(method: Method, N: int, angle: float, error: Exception) -> dict[str, Any]:
    """The record of a solve that raised (building the NLP or solving): failed, with the
    exception's text as the message."""
    return {"kind": "cell", "method": method.label, "scheme": method.scheme,
            "retraction": method.retraction, "angle": angle, "N": N, "outcome": "failed",
            "status": type(error).__name__, "success": False,
            "message": str(error) or type(error).__name__}
