"""The NLP of (problem, method) with its backends: solve it for any parameters p.

The NLP — graph, layout, bounds, the shared Functions, the packing of p and the read-out —
is :class:`~ocgroupoid.nlp.program.NonlinearProgram`; the solvers are the backends
(:mod:`~ocgroupoid.nlp.backends`), built from it and the solver options
(:class:`~ocgroupoid.nlp.options.SolverOptions`); which of them runs is the solve's policy
(:func:`~ocgroupoid.nlp.backends.policy.in_turn`). A :class:`Transcription` is the three
together: ``tr.pack(...)``, ``tr.solve(guess, p)``, ``tr.readout(x, p)``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import casadi as ca
import numpy as np

from ..model.problem import Problem
from . import backends
from .assembly import Derivatives
from .backends import FatropBackend, IpoptBackend, Start, in_turn, ipopt_options
from .backends.base import Attempt, never
from .backends.policy import Rescue
from .method import Method
from .options import SolverOptions
from .program import Guess, NonlinearProgram
from .watch import Listener


@dataclass
class RawResult:
    """What the backend returned for one start, before diagnostics."""

    label: str
    x: np.ndarray
    p: np.ndarray
    lam_g: np.ndarray
    cost: float
    status: str
    success: bool
    iterations: int
    solve_seconds: float
    lam_x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: which solver produced it: ``ipopt``, ``fatrop``, ``ipopt after fatrop`` (fatrop
    #: failed and IPOPT solved from the same start; solve_seconds counts both) or ``ipopt
    #: polish after fatrop`` (IPOPT from the point where fatrop stopped, near a solution)
    backend: str = "ipopt"
    #: the runs before it from the same start: (who, status, iterations), in order
    earlier: tuple[Attempt, ...] = ()


class Transcription(NonlinearProgram):
    """The compiled NLP of (problem, method) and its backends, built for ``options``."""

    def __init__(self, problem: Problem, method: Method,
                 options: SolverOptions | None = None) -> None:
        t0 = time.perf_counter()
        options = options if options is not None else SolverOptions()
        super().__init__(problem, method,
                         Derivatives(lagrangian=backends.compiled_together(options)))
        self.options = options
        #: compiled evaluation (:mod:`~ocgroupoid.nlp.jit`), and the backend's name
        self.jit, self.backend = options.jit, options.backend
        #: the time limit of one run of the backend (IPOPT's ``max_wall_time``)
        self.max_seconds = float(ipopt_options(options)["max_wall_time"])
        #: the backends a solve runs in turn: IPOPT, or fatrop then IPOPT
        self.backends = backends.build(self, options)
        ipopt = self.backends[-1]
        assert isinstance(ipopt, IpoptBackend)  # the last in every turn (backends.build)
        #: the plain IPOPT instance (the exported C solver's, and the fallback of fatrop)
        self.solver = ipopt.solver
        #: the fatrop backend (solver.backend: fatrop), else None
        self.fatrop = self.backends[0] if isinstance(self.backends[0], FatropBackend) else None
        #: whether this build compiled its library (False: loaded from the cache, or no jit)
        self.jit_compiled = self.backends[0].jit_compiled
        self.build_seconds = time.perf_counter() - t0
        #: where the build time went: stage graphs and layout, derivative assembly, jit,
        #: IPOPT setup, fatrop's build
        self.build_phases.update({
            "jit": ipopt.jit_seconds, "nlpsol": ipopt.setup_seconds,
            "fatrop": self.fatrop.build_seconds if self.fatrop is not None else 0.0})

    def solve(self, guess: Guess, p: np.ndarray | None = None,
              listener: Listener | None = None, deadline: float | None = None,
              stop: Callable[[], bool] | None = None, rescue: Rescue | None = None
              ) -> RawResult:
        """Run the backends from ``guess`` with parameters ``p`` (default: the problem's).
        With IPOPT, ``listener(iteration, objective, infeasibility)`` hears every iteration
        and stops IPOPT by returning True (status ``User_Requested_Stop``), a guess with
        multipliers as well, which is a primal-dual warm start (with the bound pushes of
        :data:`~ocgroupoid.nlp.backends.ipopt.CARRIED_IPOPT` when the multipliers were
        carried from a coarser grid: the guess has a ``primal``). fatrop has neither: it starts
        from the guess's primal point, guarded (in this process, or in a helper process where
        it cannot be: :mod:`~ocgroupoid.nlp.backends.fatrop`) and stopped at ``deadline``
        (``time.monotonic()``; default: :attr:`max_seconds` from now), after repeated NaN
        evaluations, or once ``stop()`` is true; when it fails IPOPT solves from the same
        start with the time left (:func:`~ocgroupoid.nlp.backends.policy.in_turn`), after
        ``rescue`` if given. A run that used up the time has status
        ``Maximum_WallTime_Exceeded``."""
        x0, p = self.start_point(guess, self.pack() if p is None else p)
        if deadline is None:
            deadline = time.monotonic() + self.max_seconds
        warm = self._warm(guess)
        start = Start(x0, p, guess.lam_g if warm else None, guess.lam_x if warm else None,
                      listener, deadline, stop or never, carried=guess.primal is not None)
        run, label = in_turn(self.backends, start, lambda x, p: float(self.f_fun(x, p)),
                             rescue)
        return RawResult(guess.label, run.x, p, run.lam_g, run.f, run.status, run.success,
                         run.iterations, run.seconds, run.lam_x, label, run.earlier)

    def start_point(self, guess: Guess, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The NLP point a solve starts from, and its parameters: a free horizon's guess is
        the guess's T when it has one (a coarser grid's solved T, also with the whole point
        carried from it)."""
        p = np.asarray(p, dtype=float)
        if guess.T is not None and self.problem.T_free:
            p = p.copy()
            p[self.layout.p_slices["T"]] = guess.T
        x0 = guess.x if guess.x is not None and guess.x.size == self.nx else self.point(guess, p)
        return x0, p

    def solve_graph(self, x0: ca.MX, p: ca.MX, lam_g0: ca.MX | None = None,
                    lam_x0: ca.MX | None = None) -> dict[str, ca.MX]:
        """A solve from x0 as a graph (``x, f, g, lam_g, lam_x``) with the bounds of
        :attr:`bounds_function`: IPOPT's nlpsol inside, for the exported C solver (with
        ``solver.backend: fatrop`` the export runs fatrop's driver instead:
        :mod:`ocgroupoid.export.fatrop`). With multipliers, IPOPT's primal-dual warm start."""
        ipopt = self.backends[-1]
        assert isinstance(ipopt, IpoptBackend)  # the last in every turn (backends.build)
        return ipopt.graph(x0, p, lam_g0, lam_x0)

    def _warm(self, guess: Guess) -> bool:
        """Whether ``guess`` is a primal-dual point of this NLP (sizes match)."""
        return (guess.x is not None and guess.x.size == self.nx and guess.lam_g is not None
                and guess.lam_g.size == self.ng and guess.lam_x is not None
                and guess.lam_x.size == self.nx)


__all__ = ["Transcription", "RawResult", "Guess"]
