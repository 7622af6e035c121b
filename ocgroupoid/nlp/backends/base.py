"""What an NLP solver is to the transcription: one small interface every backend implements.

A backend is built once from the NLP (its graph, its derivative Functions, its bounds) and the
solver options (:class:`~ocgroupoid.nlp.options.SolverOptions`), and then:

* :meth:`Backend.run` solves from a :class:`Start` (a primal point, parameters, optionally
  multipliers for a primal-dual warm start, a listener of iterations, a deadline and a stop
  request) and returns a :class:`Run`: the point, its multipliers, status and iterations.

The exported C solver is each backend's own: IPOPT's the same solve as a CasADi graph
(``IpoptBackend.graph``), which CasADi's code generator writes; fatrop's its driver on the
stage form's Functions (``FatropBackend.exported``, :mod:`ocgroupoid.export.fatrop`).

What a backend cannot do it ignores (fatrop has no dual warm start, and hears its
listener only through its own C interface in this process). Which backends run, and in what
order, is the solve's policy (:mod:`~ocgroupoid.nlp.backends.policy`), not the NLP's.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Callable, ClassVar, Protocol

import casadi as ca
import numpy as np

from ..assembly import Block, Derivatives
from ..watch import Listener

#: what a solve reports that was stopped at its deadline (IPOPT's name for it) or by Ctrl-C
TIMED_OUT = "Maximum_WallTime_Exceeded"
INTERRUPTED = "interrupted"
#: what a run reports that its listener stopped (IPOPT's name; fatrop's too, where it has one)
LISTENER_STOP = "User_Requested_Stop"
#: what a run reports that stopped near a solution, its error below the acceptable level for
#: many iterations but not below the tolerance (IPOPT's name; not a success)
ACCEPTABLE = "Solved_To_Acceptable_Level"


def never() -> bool:
    """A stop request that never comes."""
    return False


class Graph(Protocol):
    """What a backend reads off the NLP it solves."""

    function_name: str
    nlp: dict[str, ca.MX]
    functions: dict[str, ca.Function]
    blocks: list[Block]
    derivatives: Derivatives
    nx: int
    np: int
    ng: int
    bounds_function: ca.Function


@dataclass(frozen=True)
class Start:
    """Where one run starts: the primal point x0 and the parameters p; the multipliers of a
    primal-dual warm start (both or neither); who hears the iterations (and may stop them);
    the deadline (``time.monotonic()``) and a stop request (Ctrl-C); whether the
    multipliers were carried from a coarser grid (:mod:`~ocgroupoid.solve.multipliers`),
    not those of a solution of this NLP (IPOPT's
    :data:`~ocgroupoid.nlp.backends.ipopt.CARRIED_IPOPT`)."""

    x0: np.ndarray
    p: np.ndarray
    lam_g0: np.ndarray | None = None
    lam_x0: np.ndarray | None = None
    listener: Listener | None = None
    deadline: float = math.inf
    stop: Callable[[], bool] = never
    carried: bool = False

    @property
    def warm(self) -> bool:
        """Whether the start carries multipliers."""
        return self.lam_g0 is not None and self.lam_x0 is not None


#: a run that came before another from the same start: who ran (a backend, or a rescue's
#: scheme), its status and its iterations
Attempt = tuple[str, str, int]


@dataclass
class Run:
    """What one backend returned, in the NLP's own variables and rows (``note``: why it
    was stopped, if it was; ``earlier``: the runs before it from the same start, in order)."""

    x: np.ndarray
    f: float
    lam_g: np.ndarray
    lam_x: np.ndarray
    status: str
    success: bool
    iterations: int
    seconds: float
    note: str = ""
    earlier: tuple[Attempt, ...] = ()


class Backend(ABC):
    """An NLP solver built for one NLP (module docstring)."""

    #: the name ``solver.backend`` gives it
    name: ClassVar[str]
    #: whether building it compiled a library (False: none, or loaded from the cache)
    jit_compiled: bool = False

    @abstractmethod
    def run(self, start: Start) -> Run:
        """Solve from ``start``."""
