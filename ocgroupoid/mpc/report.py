"""What a closed loop records, its summary and its JSON file (``DIR/mpc.json``).

Per step (one solve at each sample time ``t_i = i h``; step 0 is the initial, cold solve):
``step_seconds`` (preparation + feedback + reading the control out: the computation a sample
costs), ``prepare_seconds`` and ``feedback_seconds`` (the latency from the measurement to the
control), ``iterations`` (IPOPT's, or the QP's for a real-time iteration), ``status``,
``success``, ``tracking_error`` (the plant's state against the open-loop plan at t_i, on the
groupoid: :func:`~ocgroupoid.mpc.state.distance`) and its largest entry, ``bound_violation``
(the largest violation of the NLP's bounds at the points where they are imposed, by the plan
solved at t_i) and ``control`` (the control applied at t_i). The summary's timing statistics
are over the warm steps (i >= 1) that solved something: the steps of a shrinking horizon
that hold the last plan (status :data:`HOLD`) take no time and are left out.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

#: the status of a step that applies the last plan without solving
HOLD = "hold"


@dataclass
class Step:
    """One sample of the loop (module docstring)."""

    t: float
    status: str
    success: bool
    iterations: int
    step_seconds: float
    prepare_seconds: float
    feedback_seconds: float
    tracking_error: dict[str, float]
    bound_violation: float
    control: list[float]

    @property
    def tracking_error_max(self) -> float:
        return max(self.tracking_error.values(), default=0.0)

    def as_dict(self) -> dict[str, Any]:
        return {**self.__dict__, "tracking_error_max": self.tracking_error_max}


def percentiles(seconds: list[float]) -> dict[str, float]:
    """Median, 99th percentile and maximum (seconds), and the count."""
    if not seconds:
        return {"count": 0}
    a = np.asarray(seconds)
    return {"count": int(a.size), "median": float(np.median(a)),
            "p99": float(np.percentile(a, 99)), "max": float(a.max())}


@dataclass
class MpcResult:
    """A closed-loop run: settings, per-step records, the plant's trajectory, the open-loop
    plan and the terminal errors."""

    problem: str
    settings: dict[str, Any]
    steps: list[Step]
    #: plant states z = (s, y) at t_0 .. t_K (one row each), and the times
    t: np.ndarray
    z: np.ndarray
    #: the applied control, densely sampled: times and values (one row per time)
    control_t: np.ndarray
    control: np.ndarray
    #: the open-loop plan: node times, node states, velocity times and velocities, controls
    plan: dict[str, np.ndarray]
    terminal_error: dict[str, float]
    final_tracking_error: dict[str, float]
    control_names: list[str]
    bounds: list[dict[str, Any]] = field(default_factory=list)

    @property
    def failed_steps(self) -> int:
        return sum(not s.success for s in self.steps)

    @property
    def bound_violation_max(self) -> float:
        return max((s.bound_violation for s in self.steps), default=0.0)

    @property
    def tracking_error_max(self) -> float:
        return max([s.tracking_error_max for s in self.steps] +
                   list(self.final_tracking_error.values()))

    @property
    def warm(self) -> list[Step]:
        """The steps after the first that solved (held steps left out)."""
        return [s for s in self.steps[1:] if s.status != HOLD]

    def timing(self) -> dict[str, dict[str, float]]:
        """Statistics of the warm steps' times (:func:`percentiles`)."""
        warm = self.warm
        return {"step": percentiles([s.step_seconds for s in warm]),
                "prepare": percentiles([s.prepare_seconds for s in warm]),
                "feedback": percentiles([s.feedback_seconds for s in warm])}

    def summary(self) -> dict[str, Any]:
        warm = self.warm
        return {"steps": len(self.steps), "failed_steps": self.failed_steps,
                "terminal_error": self.terminal_error,
                "tracking_error_max": self.tracking_error_max,
                "bound_violation_max": self.bound_violation_max,
                "iterations_mean": float(np.mean([s.iterations for s in warm])) if warm else 0.0,
                "timing": self.timing()}

    def to_dict(self) -> dict[str, Any]:
        return {"problem": self.problem, "settings": self.settings, "summary": self.summary(),
                "steps": [s.as_dict() for s in self.steps],
                "trajectory": {"t": self.t.tolist(), "z": self.z.tolist(),
                               "control_t": self.control_t.tolist(),
                               "control": self.control.tolist()},
                "plan": {k: np.asarray(v).tolist() for k, v in self.plan.items()},
                "control_names": self.control_names, "bounds": self.bounds}

    def to_json(self, path: str | Path) -> Path:
        """Write :meth:`to_dict` to ``path``; returns the path."""
        path = Path(path)
        path.write_text(json.dumps(self.to_dict(), indent=1, allow_nan=True))
        return path

    def plot(self, path: str | Path) -> Path:
        """The figure (:mod:`~ocgroupoid.mpc.figure`) as a PNG at ``path``."""
        from .figure import figure

        return figure(self, Path(path))
