"""What a discretisation scheme is: the small interface every scheme implements.

A scheme (rockit calls it a method) turns the continuous problem into stages on N intervals:

* :attr:`n_stage` variables of its own in x, arranged by :meth:`index` (which also gives
  the w-indices of the node states and of the final velocity, where the shared final
  conditions read them);
* :meth:`blocks`: its stage Functions with their index columns (the reconstruction, the
  discrete action sum and the discrete constraints Phi_d, whose multipliers are the seeds'
  lambda^k);
* :meth:`point`: the NLP point of a guess given as interval velocities;
* :meth:`readout`: what a solution reports — algebra increments per interval, the node
  states by exact reconstruction, velocities and controls with their time stamps — as
  graphs of w, so that Python and exported C evaluate the same Function;
* :meth:`euler_lagrange_residual`: the discrete Euler-Lagrange equations checked with the
  solver's multipliers. By default the gradient of the reduced discrete action (the states
  eliminated by exact reconstruction, so that only the multipliers lambda^k of Phi_d and
  those of the final conditions enter) over each node's velocity variables
  (:attr:`velocity_groups`).

A new scheme is one new class registered in :mod:`ocgroupoid.nlp.schemes`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, Callable, ClassVar

import casadi as ca
import numpy as np

from ...lie.retraction import Retraction, retraction
from ...model.problem import Problem
from ..assembly import Block
from ..layout import Layout
from ..stages import Stages

Pick = Callable[[np.ndarray], ca.MX]  # w-indices -> the gathered graph, shaped like them
#: the rule of the constraints every scheme has (order2 also takes a problem's own ``rules``)
DEFAULT_RULE = "midpoint"


def stage_function(name: str, sizes: list[int], body: Callable[..., Any]) -> ca.Function:
    """``name(z) -> (f, g)`` with z the concatenation of arguments of the given sizes."""
    z = ca.SX.sym("z", sum(sizes))
    parts = ca.vertsplit(z, np.cumsum([0, *sizes]).tolist())
    f, g = body(*parts)
    return ca.Function(name, [z], [f, g])


def columns(*parts: np.ndarray, ncols: int) -> np.ndarray:
    """Stack index rows; 1-D parts (T, P) are repeated for every column."""
    rows = [np.tile(p[:, None], (1, ncols)) if p.ndim == 1 else p for p in parts]
    return np.vstack(rows).astype(np.int64)


@dataclass
class Readout:
    """Graphs of w that a scheme reads off a point (times as fractions of T).

    The control the scheme implies is a piecewise polynomial in ``scipy.interpolate.PPoly``'s
    convention: breakpoints ``control_breaks`` and coefficients of ``(t - t_j)^(k-1-i)``,
    highest power first, stored as rows ``i * n_u + component`` with one column per piece.
    """

    steps: ca.MX  # dim y x N: algebra increments a_k, s_{k+1} = step(s_k, tau(a_k))
    states: ca.MX  # ds x (N+1): s_0 and the states reached by the exact reconstruction
    velocity_t: np.ndarray
    velocities: ca.MX  # dim y x len(velocity_t)
    control_t: np.ndarray
    controls: ca.MX  # n_u x len(control_t)
    control_breaks: np.ndarray  # pieces + 1 breakpoints
    control_coefficients: ca.MX  # (k n_u) x pieces


def piecewise_linear(u: ca.MX, t: np.ndarray, T: ca.MX) -> ca.MX:
    """PPoly coefficients of the linear interpolant of samples u (n_u x len(t)) at the
    times t (fractions of T): slopes, then values at the left breakpoints."""
    dt = T * ca.DM(np.diff(t)).T
    return ca.vertcat((u[:, 1:] - u[:, :-1]) / ca.repmat(dt, u.size1(), 1), u[:, :-1])


class Scheme(ABC):
    """A discretisation of a problem on N intervals (module docstring)."""

    name: ClassVar[str]
    accuracy: ClassVar[int]  # the order at which costs and trajectories converge
    adaptive_steps: ClassVar[bool] = False  # whether its stages read per-interval steps
    variational: ClassVar[bool] = True  # whether it has discrete Euler-Lagrange equations
    #: the cheaper scheme a failed solve is restarted through on the same grid (its solution
    #: the start of this one; :meth:`~ocgroupoid.solve.CompiledProblem.solve`), or None
    rescue: ClassVar[str | None] = None
    problem_order: ClassVar[int]  # 2: second-order problems (Ltilde); 1: first-order (l)
    summary: ClassVar[str]

    @property
    def cost_order(self) -> int:
        """The order at which this instance's cost converges, for Richardson estimates:
        :attr:`accuracy`, unless its stages limit it (:class:`~.order6.CubicGauss`)."""
        return self.accuracy

    #: w-indices set by :meth:`index`
    states: np.ndarray  # ds x (N+1) node states
    end_velocity: np.ndarray  # dim y: the velocity at t = T (final conditions read it)

    def __init__(self, problem: Problem, N: int, retraction_name: str, rule: str) -> None:
        self.problem, self.N, self.rule = problem, N, rule
        self.retraction = retraction_name
        self.retractions: list[Retraction] = [retraction(retraction_name, f.group)
                                              for f in problem.groupoid.factors]
        self.stages = self.make_stages()
        self.layout: Layout | None = None

    def held_rows(self, points: int) -> np.ndarray:
        """Which of an interval's ``points`` bound rows a phase of adaptive steps holds at its
        side in a bang-bang arc (a boolean mask): the row at the first Gauss point (at the
        first point where the scheme has none, or bounds only at its ends), the others
        bounded. One equality per interval: more would over-determine the interval's unknowns
        where a problem has conditions that its conservation laws already imply; the optimum
        holds the rest."""
        times = np.asarray(getattr(self, "bound_times", np.zeros(points)))
        collocation = getattr(self, "collocation", None)
        gauss = np.isclose(times, collocation[0]) if collocation is not None \
            else np.zeros(points, dtype=bool)
        return gauss if gauss.any() else np.arange(points) == 0

    def make_stages(self) -> Stages:
        """The stage Functions of this scheme's problem and retractions (a scheme may draw
        some of them otherwise: ``order4``'s lines, :mod:`~ocgroupoid.nlp.control_lines`)."""
        return Stages(self.problem, self.retractions)

    @property
    @abstractmethod
    def n_stage(self) -> int:
        """Number of the scheme's own decision variables (first in x)."""

    @abstractmethod
    def index(self, layout: Layout) -> None:
        """Arrange the stage variables; set :attr:`states`, :attr:`end_velocity`."""

    @abstractmethod
    def blocks(self) -> list[Block]:
        """The stage Functions with their index columns."""

    @abstractmethod
    def point(self, XI: ca.MX, pick: Pick) -> list[tuple[np.ndarray, ca.MX]]:
        """Values of the NLP point for interval velocities XI (dim y x N): pairs of w-indices
        and graphs, for :meth:`Layout.compose`."""

    @abstractmethod
    def readout(self, pick: Pick) -> Readout:
        """What a solution reports, as graphs of w."""

    @property
    def velocity_groups(self) -> np.ndarray:
        """w-indices of the velocity variables whose residuals are reported, one row per node
        (or interval): the discrete Euler-Lagrange equations there."""
        raise NotImplementedError

    def euler_lagrange(self, lagrangian: ca.Function, reconstruct: ca.Function
                       ) -> Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]:
        """The residuals of the discrete Euler-Lagrange equations (one row per node), as a
        map ``(x, p, lam) -> residuals`` built once and evaluated at each solution.

        ``lagrangian(x, p, lam)`` is the action sum plus the constraints times their
        multipliers (the reconstruction's set to zero), ``reconstruct(x, p)`` the point
        with every state recomputed from the velocities. The residual is the gradient of
        their composition — the reduced discrete action with multipliers — over
        :attr:`velocity_groups`: zero exactly where the discrete trajectory extremises it
        (seed 000, eq. 18, for the reduced variables).
        """
        xs, ps, ls = lagrangian.mx_in()
        gradient = ca.Function("reduced", [xs, ps, ls],
                               [ca.gradient(lagrangian(reconstruct(xs, ps), ps, ls), xs)])
        groups = self.velocity_groups

        def residual(x: np.ndarray, p: np.ndarray, lam: np.ndarray) -> np.ndarray:
            g = np.concatenate([np.array(gradient(x, p, lam)).ravel(), np.zeros(p.size)])
            return g[groups]
        return residual

    def final_state(self) -> tuple[np.ndarray, ca.Function]:
        """The w-indices the final conditions read, and the map from them to the stored
        final state (the identity, unless the scheme carries states in its own
        coordinates)."""
        s = ca.SX.sym("s", self.problem.groupoid.state_size)
        return self.states[:, self.N], ca.Function("stored", [s], [s])

    def reconstructed(self, r: Readout) -> list[tuple[np.ndarray, ca.MX]]:
        """Pairs (w-indices, graphs) that put the exactly reconstructed node states of the
        read-out ``r`` into a point (the reduced action of the Euler-Lagrange check)."""
        return [(self.states[:, 1:], r.states[:, 1:])]

    def troubles(self, w: np.ndarray, failed: bool = False) -> list[str]:
        """What this scheme knows went wrong at the point w = [x; p] (a baseline's
        coordinate singularity, ...), ``failed``: IPOPT did not solve; sentences for the
        hint, none by default."""
        return []

    @abstractmethod
    def unpack(self, w: np.ndarray) -> dict[str, np.ndarray]:
        """The scheme's variables of a numeric point w = [x; p], by name."""

    def step_over(self, pick: Pick) -> ca.MX:
        """The states s_1..s_N reached from s_0 by the steps (exact reconstruction)."""
        assert self.layout is not None
        steps = self.readout_steps(pick)
        return self.stages.step.mapaccum(self.N)(pick(self.layout.s0), steps)

    @abstractmethod
    def readout_steps(self, pick: Pick) -> ca.MX:
        """The algebra increments a_k (dim y x N) of a point."""
