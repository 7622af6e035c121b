"""Forward simulation with the discrete equations: the variational integrator itself.

:class:`~ocgroupoid.simulation.flow.DiscreteFlow` steps the discrete controlled Euler-Lagrange
equations of a second-order problem (the ``order2`` node stage, seed 000 eq. 27-29) forward.
With zero control this is the implicit-midpoint Lie-group integrator of the free system:
states stay on the group to rounding, the energy error at the nodes oscillates at O(h^2)
without drift, and quadratic first integrals of the interval velocities xi_k (the energy and
|I xi_k|^2 of the free rigid body) are conserved to rounding.

For comparison :func:`simulate` also integrates the continuous dynamics

    ds/dt = state_rate(s, y),      M(q, y) dy/dt = F(u) - c(q, y),    F_actuated = B u

(``M = dEL/d(dy)``, ``c = EL|_{dy=0}``: :class:`~ocgroupoid.nlp.dynamics.Dynamics`, which
the replay integrates too) with the classical RK4 method at the same step; its energy drifts
and its states leave the group. Both integrators run in compiled chunks
(:func:`~ocgroupoid.simulation.flow.accumulate`): 10^5 steps take seconds.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from ..errors import ConfigError, DimensionError
from ..model.boundary_values import prescribe
from ..model.problem import Problem
from ..nlp import dynamics
from ..nlp.dynamics import Dynamics
from ..nlp.method import DEFAULT_RETRACTION
from ..nlp.schemes import DEFAULT_RULE, NodeMidpoint
from .flow import Advance, DiscreteFlow, accumulate, check_mechanics

#: the progress bar appears once a run has taken this many seconds
SHOW_AFTER = 1.0

# ------------------------------------------------------------------ continuous dynamics


def rk4_step(f: ca.Function) -> ca.Function:
    """Classical RK4 for ``dz/dt = f(z, u, P)`` over one step h, with the control linear
    between the node values u_k, u_{k+1}: ``(z_k, u_k, u_{k+1}, h, P) -> z_{k+1}``."""
    z = ca.SX.sym("z", f.size1_in(0))
    u0, u1 = ca.SX.sym("u0", f.size1_in(1)), ca.SX.sym("u1", f.size1_in(1))
    h, P = ca.SX.sym("h"), ca.SX.sym("P", f.size1_in(2))
    return ca.Function("rk4_step", [z, u0, u1, h, P],
                       [dynamics.rk4(lambda x, s: f(x, (1 - s) * u0 + s * u1, P), z, h)])


def energy(problem: Problem) -> ca.SX:
    """``E(q, y, P) = y . dl/dy - l``: the Legendre transform of the reduced Lagrangian
    (kinetic plus potential energy)."""
    mech = problem.dynamics
    assert mech is not None
    l = mech.lagrangian
    return ca.dot(problem.y, ca.gradient(l, problem.y)) - l


# ------------------------------------------------------------------ results


@dataclass(frozen=True)
class Trajectory:
    """One integrator at the nodes ``t_k = k h``, k = 0..steps: node states s_k (rows),
    node velocities y_k, the energy and every declared conserved quantity there."""

    integrator: str
    t: np.ndarray
    states: np.ndarray
    velocities: np.ndarray
    energy: np.ndarray
    invariants: dict[str, np.ndarray]
    seconds: float

    @property
    def energy_error(self) -> np.ndarray:
        """``E_k - E_0``."""
        return self.energy - self.energy[0]


@dataclass(frozen=True)
class Simulation:
    """A forward simulation: the variational integrator and, for comparison, RK4 on the
    continuous dynamics at the same step h, from the same initial state and controls.

    ``xi`` are the variational integrator's own velocities, one per interval, and
    ``interval_energy`` the energy there, ``E(step(s_k, tau(h xi_k / 2)), xi_k)``: exactly
    conserved (to rounding) when E depends on the velocities only, as for the free rigid
    body, where the node energy oscillates at O(h^2)."""

    problem: str
    h: float
    steps: int
    retraction: str
    rule: str
    variational: Trajectory
    rk4: Trajectory
    xi: np.ndarray
    interval_energy: np.ndarray

    @property
    def t(self) -> np.ndarray:
        """Node times ``k h``, k = 0..steps."""
        return self.variational.t

    @property
    def states(self) -> np.ndarray:
        """The variational integrator's node states ((steps + 1) x state size)."""
        return self.variational.states

    @property
    def velocities(self) -> np.ndarray:
        """The variational integrator's node velocities ``(xi_{k-1} + xi_k)/2``."""
        return self.variational.velocities

    def summary(self) -> dict[str, Any]:
        """Per integrator: wall seconds, final and largest |energy error|, and the final
        and largest error of every conserved quantity (JSON-ready)."""
        out: dict[str, Any] = {"problem": self.problem, "h": self.h, "steps": self.steps,
                               "T": self.h * self.steps, "retraction": self.retraction,
                               "rule": self.rule}
        for tr in (self.variational, self.rk4):
            errors = {"energy": tr.energy_error,
                      **{name: v - v[0] for name, v in tr.invariants.items()}}
            out[tr.integrator] = {"seconds": tr.seconds, **{
                f"{name}_error_{at}": float(f(np.abs(e)))
                for name, e in errors.items() for at, f in (("final", lambda a: a[-1]),
                                                            ("max", np.max))}}
        dE = np.abs(self.interval_energy - self.interval_energy[0])
        out["variational"].update(interval_energy_error_final=float(dE[-1]),
                                  interval_energy_error_max=float(np.max(dE)))
        return out


# ------------------------------------------------------------------ the entry point


def simulate(problem: Problem, h: float = 0.01, steps: int = 1000,
             initial: dict[str, Any] | None = None, controls: Any = None,
             retraction: str = DEFAULT_RETRACTION, rule: str = DEFAULT_RULE,
             params: dict[str, Any] | None = None, progress: bool | None = None
             ) -> Simulation:
    """Simulate a second-order problem forward over ``steps`` steps of length ``h`` with its
    variational integrator (the ``order2`` node equations, module docstring), and with RK4 on
    its continuous dynamics for comparison.

    ``initial`` overrides the problem's initial states and velocities by name (every one must
    be given, here or in the problem); ``controls`` are the node controls: None (zero), one
    row (constant) or ``steps + 1`` rows; ``params`` override parameter values. ``retraction``
    and ``rule`` choose the discretisation as in :func:`~ocgroupoid.solve.compile_problem`.
    ``progress``: a rich bar on stderr (None: once the run has taken :data:`SHOW_AFTER` s).
    Raises :class:`~ocgroupoid.errors.SolverError` when Newton fails at a node (decrease h).
    """
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 1:
        raise ConfigError(f"steps must be an integer >= 1, got {steps!r}")
    if isinstance(h, bool) or not isinstance(h, (int, float, np.floating)) \
            or not math.isfinite(h) or h <= 0:
        raise ConfigError(f"the step h must be a finite number > 0, got {h!r}")
    check_mechanics(problem)
    scheme = NodeMidpoint(problem, 1, retraction, rule)  # N = 1: its horizon T is the step h
    flow = DiscreteFlow(scheme)
    rhs = Dynamics(problem, scheme.stages).rhs
    assert rhs is not None  # second order with mechanics (check_mechanics)
    s0, V0 = initial_state(problem, initial)
    P = problem.parameter_values(params)
    U = node_controls(problem, controls, steps + 1)
    with StepProgress(2 * steps + 1, progress) as bar:
        bar.describe("variational integrator")
        t0 = time.perf_counter()
        S, xi = flow.run(s0, V0, U, h, P, bar.advance)  # nodes 0..steps: s_{steps+1}, xi_steps
        t1 = time.perf_counter()
        bar.describe("RK4")
        Z = rk4(rhs, np.concatenate([s0, V0]), U, h, P, bar.advance)
        t2 = time.perf_counter()
    measure = Measures(problem, flow.step, P, h, steps)
    Y = (np.vstack([2 * V0 - xi[0], xi[:-1]]) + xi) / 2  # the ghost xi_{-1} at node 0
    ds = problem.groupoid.state_size
    return Simulation(problem.name, float(h), int(steps), retraction, rule,
                      measure("variational", S[:-1], Y, t1 - t0),
                      measure("rk4", Z[:ds].T, Z[ds:].T, t2 - t1), xi[:steps],
                      measure.interval_energy(S[:steps], xi[:steps]))


def rk4(rhs: ca.Function, z0: np.ndarray, U: np.ndarray, h: float, P: np.ndarray,
        advance: Advance) -> np.ndarray:
    """``z_0..z_n`` (columns, ``z = (s, y)``) of RK4 on ``dz/dt = rhs(z, u, P)`` with the
    node controls U (n + 1 rows), linear between nodes."""
    step = rk4_step(rhs)
    chunks = accumulate({}, step, z0, [U[:-1].T, U[1:].T], [h, P], advance)
    return np.hstack([z0[:, None], *[Z for _, Z, _ in chunks]])


class Measures:
    """The energy and the declared conserved quantities of a problem, evaluated by one
    mapped Function along node trajectories."""

    def __init__(self, problem: Problem, step: ca.Function, P: np.ndarray, h: float,
                 steps: int) -> None:
        G = problem.groupoid
        self.P, self.t = P, h * np.arange(steps + 1)
        self.names = [name if e.numel() == 1 else f"{name}[{i}]"
                      for name, e in problem.invariants for i in range(e.numel())]
        s, xi = ca.SX.sym("s", G.state_size), ca.SX.sym("xi", G.algebra_dim)
        E = energy(problem)
        exprs = ca.substitute(ca.vertcat(E, *[e for _, e in problem.invariants]),
                              ca.vertcat(problem.q, problem.s), ca.vertcat(G.base(s), s))
        #: ``(s_k, y_k, P) -> [E, invariants...]`` at every node
        self.nodes = ca.Function("node_quantities", [s, problem.y, problem.P],
                                 [exprs]).map(steps + 1)
        s_half = step(s, h / 2 * xi)
        #: ``(s_k, xi_k, P) -> E(step(s_k, tau(h xi_k / 2)), xi_k)`` on every interval
        self.intervals = ca.Function("interval_energy", [s, xi, problem.P], [ca.substitute(
            ca.substitute(E, ca.vertcat(problem.q, problem.s), ca.vertcat(G.base(s_half),
                                                                          s_half)),
            problem.y, xi)]).map(steps)

    def __call__(self, integrator: str, S: np.ndarray, Y: np.ndarray, seconds: float
                 ) -> Trajectory:
        """The :class:`Trajectory` of node states S and velocities Y (rows)."""
        Q = np.array(self.nodes(S.T, Y.T, self.P))
        return Trajectory(integrator, self.t, S, Y, Q[0],
                          dict(zip(self.names, Q[1:])), seconds)

    def interval_energy(self, S: np.ndarray, xi: np.ndarray) -> np.ndarray:
        """The energy on the intervals of node states S[:-1] and velocities xi (rows)."""
        return np.array(self.intervals(S.T, xi.T, self.P)).ravel()


def initial_state(problem: Problem, initial: dict[str, Any] | None) -> tuple[np.ndarray,
                                                                             np.ndarray]:
    """The initial node state s_0 (normalised: a unit quaternion) and velocity V_0: the
    problem's initial values, overridden by ``initial``; none may be left free."""
    start = problem.start.copy()
    prescribe(start, initial or {}, "initial", problem.groupoid, problem.end_velocities)
    s0: list[np.ndarray] = []
    V0: list[np.ndarray] = []
    for f in problem.groupoid.factors:
        for name, value, out in ((f.state, start.states.get(f.state), s0),
                                 (f.velocity, start.velocities.get(f.velocity), V0)):
            if value is None or any(v is None for v in np.asarray(value, dtype=object).ravel()):
                raise ConfigError(f"initial.{name} is free in {problem.name}: a simulation "
                                  f"starts from every initial state and velocity; pass "
                                  f"initial={{'{name}': ...}}")
            out.append(np.asarray(value, dtype=float).ravel())
        s0[-1] = np.asarray(f.state_of_target(f.pack_target(s0[-1])), dtype=float).ravel()
    return np.concatenate(s0), np.concatenate(V0)


def node_controls(problem: Problem, controls: Any, nodes: int) -> np.ndarray:
    """Node controls as a (nodes x n_u) array: zero for None, one row repeated, or as given."""
    nu = len(problem.controls)
    if controls is None:
        return np.zeros((nodes, nu))
    U = np.asarray(controls, dtype=float)
    if U.shape == (nu,):
        U = np.tile(U, (nodes, 1))
    if U.shape != (nodes, nu):
        raise DimensionError(f"controls of {problem.name} are one row of {nu} values or "
                             f"steps + 1 = {nodes} rows of {nu} (one per node), got shape "
                             f"{np.shape(controls)}")
    if not np.all(np.isfinite(U)):
        raise ConfigError("controls must be finite numbers")
    return U


class StepProgress:
    """A rich progress bar over the steps on stderr: shown from the start (``show=True``),
    never (False), or once the run has taken :data:`SHOW_AFTER` seconds (None)."""

    def __init__(self, total: int, show: bool | None) -> None:
        self.total, self.show, self.done = total, show, 0
        self.bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                            TimeElapsedColumn(), console=Console(stderr=True), transient=True)
        self.task: Any = None
        self.t0 = time.perf_counter()
        self.description = "simulating"

    def __enter__(self) -> "StepProgress":
        self.t0 = time.perf_counter()
        if self.show:
            self._start()
        return self

    def _start(self) -> None:
        self.bar.start()
        self.task = self.bar.add_task(self.description, total=self.total, completed=self.done)

    def describe(self, text: str) -> None:
        """Name what the steps counted from now on are."""
        self.description = text
        if self.task is not None:
            self.bar.update(self.task, description=text)

    def advance(self, steps: int) -> None:
        """Count ``steps`` more steps done."""
        self.done += steps
        if self.task is None and self.show is None and \
                time.perf_counter() - self.t0 > SHOW_AFTER and self.done < self.total:
            self._start()
        if self.task is not None:
            self.bar.update(self.task, completed=self.done)

    def __exit__(self, *exc: object) -> None:
        if self.task is not None:
            self.bar.stop()
