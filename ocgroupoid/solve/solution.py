"""The Solution of a solve: trajectory, controls, multipliers, stats and diagnostics.

``to_json``/``from_json`` use the format of shared/PROBLEMS.md ("What a solution file
holds"), extended with the discretisation, the parameters, the multi-start minima, the NLP
point (so a file is enough to warm-start or to compare with exported C code) and the control
the scheme implies as a piecewise polynomial, ``controls.ppoly = {"x": breakpoints, "c":
[k][pieces][m]}`` in ``scipy.interpolate.PPoly``'s convention (highest power first, local
coordinates from each breakpoint): ``PPoly(np.array(c), x)(t)`` is the control at t.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..errors import SolverError
from .outputs import write_atomic  # noqa: F401  (re-exported: callers import it from here)
from .rows import Rows


def _jsonable(v: Any) -> Any:
    if isinstance(v, np.ndarray):
        return _jsonable(v.tolist())
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, (np.floating, float)):
        f = float(v)
        return f if math.isfinite(f) else None
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.bool_):
        return bool(v)
    return v


#: draws a Solution (``plot(solution, path)``): set by :mod:`ocgroupoid.plotting` when it is
#: imported (as ``import ocgroupoid`` does), a layer above this one
PLOTTER: Callable[["Solution", "str | Path | None"], Any] | None = None


@dataclass
class Solution:
    """A solved (or failed) instance; arrays are NumPy, one row per time."""

    problem: str
    success: bool
    status: str
    N: int
    T: float
    cost: float
    #: the iterations of the run that produced it; ``diagnostics["runs"]`` lists every run
    #: from its start (a fatrop run before IPOPT's polish, ...), which ``solve_seconds`` counts
    iterations: int
    solve_seconds: float
    build_seconds: float
    discretization: dict[str, Any]
    parameters: dict[str, list[float]]
    t: np.ndarray
    states: dict[str, np.ndarray]
    velocity_t: np.ndarray
    velocities: dict[str, np.ndarray]
    controls_t: np.ndarray
    controls: np.ndarray
    control_names: list[str]
    multipliers: dict[str, Any]
    diagnostics: dict[str, Any]
    minima: list[dict[str, Any]] = field(default_factory=list)
    hint: str = ""
    #: breakpoints ``x`` and coefficients ``c`` (k x pieces x m) of the control (PPoly)
    control_ppoly: dict[str, np.ndarray] = field(default_factory=dict)
    x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    p: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: IPOPT's multipliers of the constraints g and of the variable bounds: with x, the
    #: primal-dual point a re-solve warm-starts from (``CompiledProblem.solve(warm=solution)``)
    lam_g: np.ndarray = field(default_factory=lambda: np.zeros(0))
    lam_x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: the manifold of every state (``SO(3)``, ``SE(3)``, ``S^2``, ``R^2``, ...)
    manifolds: dict[str, str] = field(default_factory=dict)
    #: names and units of what it reports, the prescribed final states and the bounds at the
    #: solved parameters (:meth:`~ocgroupoid.model.problem.Problem.labels`; {} in old files)
    labels: dict[str, Any] = field(default_factory=dict)
    #: IPOPT runs of the solve (multi-start) and their summed time; ``solve_seconds`` is the
    #: best start's
    starts: int = 1
    ipopt_seconds_total: float = 0.0
    #: the solver of the best start (``ipopt``, ``fatrop``, ``ipopt after fatrop``, ``ipopt
    #: polish after fatrop``: IPOPT from fatrop's acceptable point)
    backend: str = "ipopt"
    #: the constraint rows of the NLP it was solved on, so that ``solve(guess=solution)`` on
    #: another grid carries its multipliers over (:mod:`~ocgroupoid.solve.multipliers`);
    #: None when read from a file (the solve then takes those of its own grid of this N, when
    #: the file's problem and method are its own)
    rows: Rows | None = field(default=None, repr=False, compare=False)

    def __repr__(self) -> str:
        return (f"Solution({self.problem!r}, status={self.status!r}, cost={self.cost:.10g}, "
                f"N={self.N}, T={self.T:g}, iterations={self.iterations})")

    @property
    def error_estimate(self) -> float | None:
        """The estimated relative error of the cost (Richardson, from a coarser grid of the
        same solve: ``horizon.N: auto`` or ``continuation``; details in
        ``diagnostics["error_estimate"]``), or None when no coarser grid was solved."""
        est = self.diagnostics.get("error_estimate")
        return None if est is None else est.get("cost_relative")

    def control(self, t: Any) -> np.ndarray:
        """The control the scheme implies at the times t (rows), from its piecewise
        polynomial (``scipy.interpolate.PPoly``)."""
        from scipy.interpolate import PPoly

        if not self.control_ppoly:
            raise ValueError("this solution carries no control polynomial (an old file?)")
        return PPoly(np.asarray(self.control_ppoly["c"], dtype=float),
                     np.asarray(self.control_ppoly["x"], dtype=float))(t)

    def plot(self, path: str | Path | None = None) -> Any:
        """The figure of this solution (a matplotlib Figure, :func:`ocgroupoid.plot`); with
        ``path``, also written there as a PNG."""
        if PLOTTER is None:
            raise RuntimeError("no plotter registered: import ocgroupoid (or ocgroupoid.plotting)")
        return PLOTTER(self, path)

    def raise_for_status(self) -> "Solution":
        """Raise SolverError (with IPOPT's status and the hint) unless solved."""
        if not self.success:
            raise SolverError(f"IPOPT: {self.status}. {self.hint}".strip())
        return self

    def to_dict(self) -> dict[str, Any]:
        return _jsonable({
            "problem": self.problem,
            "success": self.success,
            "status": self.status,
            "N": self.N,
            "T": self.T,
            "cost": self.cost,
            "stats": {"iterations": self.iterations, "solve_seconds": self.solve_seconds,
                      "build_seconds": self.build_seconds, "starts": self.starts,
                      "ipopt_seconds_total": self.ipopt_seconds_total,
                      "backend": self.backend},
            "discretization": self.discretization,
            "parameters": self.parameters,
            "controls": {"t": self.controls_t, "u": self.controls, "names": self.control_names,
                         "ppoly": self.control_ppoly},
            "states": {"t": self.t, **self.states},
            "manifolds": self.manifolds,
            "labels": self.labels,
            "velocities": {"t": self.velocity_t, **self.velocities},
            "multipliers": self.multipliers,
            "diagnostics": self.diagnostics,
            "minima": self.minima,
            "hint": self.hint,
            "nlp": {"x": self.x, "p": self.p, "lam_g": self.lam_g, "lam_x": self.lam_x},
        })

    def to_json(self, path: str | Path | None = None, indent: int | None = 1) -> str:
        """The solution as JSON text; with ``path``, also written there atomically."""
        text = json.dumps(self.to_dict(), indent=indent)
        if path is not None:
            write_atomic(path, text + "\n")
        return text

    @staticmethod
    def from_json(source: str | Path) -> "Solution":
        """Read a solution from JSON text or from a file path. ``success`` is read as
        verified only when the file also carries a verdict that says so
        (``diagnostics.verdict.verified``): a file whose ``success`` stands alone (a solver's
        status, an edited file) is never upgraded to a verified Solution."""
        text = str(source)
        if not text.lstrip().startswith("{"):
            text = Path(source).read_text()
        d = json.loads(text)
        states = dict(d["states"])
        vels = dict(d.get("velocities", {"t": []}))
        ctrl = d["controls"]
        arr = lambda v: np.array(v, dtype=float)  # noqa: E731  (None -> nan)
        verdict = (d.get("diagnostics") or {}).get("verdict") or {}
        verified = d.get("success") is True and verdict.get("verified") is True
        hint = d.get("hint", "")
        if d.get("success") is True and not verified:
            hint = "; ".join(filter(None, ["the file carries no verdict that verifies it "
                                           "(diagnostics.verdict): read as not verified", hint]))
        return Solution(
            problem=d["problem"], success=verified, status=d["status"], N=int(d["N"]),
            T=float(d["T"]), cost=float("nan") if d["cost"] is None else float(d["cost"]),
            iterations=int(d["stats"]["iterations"]),
            solve_seconds=float(d["stats"]["solve_seconds"]),
            build_seconds=float(d["stats"].get("build_seconds", 0.0)),
            starts=int(d["stats"].get("starts", 1)),
            ipopt_seconds_total=float(d["stats"].get("ipopt_seconds_total", 0.0)),
            backend=str(d["stats"].get("backend", "ipopt")),
            discretization=d.get("discretization", {}), parameters=d.get("parameters", {}),
            t=arr(states.pop("t")), states={k: np.array(v, dtype=float) for k, v in states.items()},
            velocity_t=arr(vels.pop("t")),
            velocities={k: np.array(v, dtype=float) for k, v in vels.items()},
            controls_t=arr(ctrl["t"]), controls=np.array(ctrl["u"], dtype=float),
            control_names=list(ctrl.get("names", [])), multipliers=d.get("multipliers", {}),
            control_ppoly=_ppoly(ctrl.get("ppoly", {})),
            diagnostics=d.get("diagnostics", {}), minima=d.get("minima", []),
            manifolds=dict(d.get("manifolds", {})), labels=dict(d.get("labels", {})),
            hint=hint, x=np.array(d.get("nlp", {}).get("x", []), dtype=float),
            p=np.array(d.get("nlp", {}).get("p", []), dtype=float),
            lam_g=np.array(d.get("nlp", {}).get("lam_g", []), dtype=float),
            lam_x=np.array(d.get("nlp", {}).get("lam_x", []), dtype=float),
        )


def _ppoly(d: dict[str, Any]) -> dict[str, np.ndarray]:
    """A control polynomial read from JSON: ``c`` keeps its (k, pieces, m) shape when there are
    no controls (an empty list otherwise reads as shape (0,))."""
    out = {k: np.array(v, dtype=float) for k, v in d.items()}
    if "c" in out and out["c"].size == 0 and "x" in out:
        out["c"] = out["c"].reshape(0, max(out["x"].size - 1, 0), 0)
    return out
