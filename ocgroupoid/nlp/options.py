"""How an NLP is solved: the solver options, one object.

acados keeps what is solved (``AcadosOcp``) apart from how (its ``solver_options``); here
``og.SolverOptions(backend="fatrop", jit=True, multistart=True)``. It is validated once,
when it is made, and passed whole to everything that solves. Every default of a solve is
here (IPOPT's own option values are the IPOPT backend's,
:data:`~ocgroupoid.nlp.backends.ipopt.DEFAULT_IPOPT`; problem files start several starts by
default, :mod:`~ocgroupoid.files.schema`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from numbers import Integral, Real
from typing import Any

from ..errors import ConfigError
from .schemes import SCHEME_NAMES

#: the wall time one solve may take (seconds, ``solver.max_seconds``): IPOPT's
#: ``max_wall_time`` for each of its runs, and the deadline of a fatrop run
#: (:mod:`~ocgroupoid.nlp.isolated`); :class:`~ocgroupoid.solve.CompiledProblem` holds every
#: start of one solve to it together
MAX_SECONDS = 600.0
#: the NLP solvers: IPOPT on the whole sparse KKT system (MUMPS), or fatrop on the stage form
#: (:mod:`~ocgroupoid.nlp.backends.fatrop`)
BACKENDS = ("ipopt", "fatrop")
DEFAULT_BACKEND = "ipopt"
#: the starts of a solve: the first geodesic guess only (the exported C solver's too)
DEFAULT_MULTISTART = False


def check_seconds(seconds: Any, what: str = "max_seconds") -> float:
    """A wall-time limit: a finite number of seconds > 0."""
    if isinstance(seconds, bool) or not isinstance(seconds, (int, float)) or \
            not math.isfinite(seconds) or seconds <= 0:
        raise ConfigError(f"{what} must be a finite number of seconds > 0, got {seconds!r}; "
                          f"e.g. {MAX_SECONDS:g}")
    return float(seconds)


@dataclass(frozen=True, kw_only=True)
class SolverOptions:
    """The backend and its options, compiled evaluation, the time limit of one solve and the
    globalisation (multi-start and its worker processes, continuation).

    >>> SolverOptions(backend="fatrop", ipopt={"tol": 1e-8})   # doctest: +SKIP
    """

    #: ``ipopt`` or ``fatrop`` (:data:`BACKENDS`)
    backend: str = DEFAULT_BACKEND
    #: IPOPT's options over :data:`~ocgroupoid.nlp.backends.ipopt.DEFAULT_IPOPT` (fatrop
    #: reads the ones it shares, and is given the rows scaled as ``nlp_scaling_*`` says)
    ipopt: dict[str, Any] = field(default_factory=dict)
    #: fatrop's own options, by fatrop's names, over the ones it is given by default and
    #: shares with IPOPT (:data:`~ocgroupoid.nlp.backends.fatrop.DEFAULT_FATROP`,
    #: :data:`~ocgroupoid.nlp.backends.fatrop.ACCEPTABLE_STOP`), wherever fatrop runs (its
    #: names and the kinds of their values are checked here, against fatrop's list)
    fatrop: dict[str, Any] = field(default_factory=dict)
    #: evaluate the NLP's Functions as compiled C (:mod:`~ocgroupoid.nlp.jit`)
    jit: bool = False
    #: the wall time of one solve, every start and grid together
    max_seconds: float = MAX_SECONDS
    #: True (every geodesic guess, the model's and 3 perturbed starts), False (the first
    #: geodesic guess) or a number of perturbed starts
    multistart: bool | int = DEFAULT_MULTISTART
    #: what is solved first, each solution interpolated onto the next: coarser N (integers,
    #: in increasing order), then other schemes on the final grid (names, in the order
    #: given; e.g. ``("order2",)`` before an ``order4`` solve)
    continuation: tuple[int | str, ...] = ()
    #: the processes a multi-start solves its starts on, this one among them
    #: (:mod:`~ocgroupoid.solve.parallel`): None, one per core; 1, one start after the other
    #: in this process
    workers: int | None = None

    def __post_init__(self) -> None:
        if self.backend not in BACKENDS:
            raise ConfigError(f"unknown solver backend {self.backend!r}; choose one of "
                              f"{', '.join(BACKENDS)}")
        if not isinstance(self.ipopt, dict) or not all(isinstance(k, str) for k in self.ipopt):
            raise ConfigError(f"ipopt options are a dict of option names and values, e.g. "
                              f"{{'tol': 1e-8}}, got {self.ipopt!r}")
        if not isinstance(self.fatrop, dict) or not all(
                isinstance(k, str) and isinstance(v, (bool, Real, str))
                for k, v in self.fatrop.items()):
            raise ConfigError(f"fatrop options are a dict of fatrop's option names and "
                              f"numbers, booleans or strings, e.g. {{'acceptable_iter': 5}}, "
                              f"got {self.fatrop!r}")
        if self.fatrop:
            from .backends.fatrop_ocp import option_kinds  # here: the backends import this module
            option_kinds(self.fatrop)
        if not isinstance(self.jit, bool):
            raise ConfigError(f"jit is True or False, got {self.jit!r}")
        multistart = self.multistart
        if not isinstance(multistart, (bool, Integral)) or multistart < 0:
            raise ConfigError(f"multistart is True, False or a number of perturbed starts "
                              f"(>= 0), got {multistart!r}")
        grids = tuple(self.continuation)
        if not all(n in SCHEME_NAMES if isinstance(n, str) else
                   isinstance(n, Integral) and not isinstance(n, bool) and n >= 2
                   for n in grids):
            raise ConfigError(f"continuation lists coarser grids, integers >= 2, and schemes "
                              f"to solve first on the final grid ({', '.join(SCHEME_NAMES)}), "
                              f"e.g. (16, 32) or ('order2',), got {self.continuation!r}")
        workers = self.workers
        if workers is not None and (isinstance(workers, bool) or not isinstance(
                workers, Integral) or workers < 1):
            raise ConfigError(f"workers is the number of processes a multi-start solves its "
                              f"starts on: an integer >= 1 (1: one start after the other) or "
                              f"None (one per core), got {workers!r}")
        object.__setattr__(self, "ipopt", dict(self.ipopt))
        object.__setattr__(self, "fatrop", dict(self.fatrop))
        object.__setattr__(self, "workers", None if workers is None else int(workers))
        object.__setattr__(self, "max_seconds", check_seconds(self.max_seconds))
        object.__setattr__(self, "continuation",
                           tuple(n if isinstance(n, str) else int(n) for n in grids))

    @property
    def run_ipopt(self) -> dict[str, Any]:
        """IPOPT's options of each run: the given ones, ``max_wall_time`` the solve's limit
        unless they set it."""
        return {"max_wall_time": self.max_seconds, **self.ipopt}


#: the names of the solver options (the keyword shortcuts of og.solve that make them)
OPTION_KEYS = tuple(f.name for f in fields(SolverOptions))
