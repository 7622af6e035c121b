"""ocgroupoid: optimal control on Lie groups and Lie groupoids, compiled to one NLP.

State the continuous problem with :class:`Problem` on a product of groupoid factors
(:class:`LieGroupFactor`, :class:`Pair`, :class:`SphereAction`), choose how to discretise it
(:class:`Method`: N intervals, a scheme, a retraction) and how to solve it
(:class:`SolverOptions`: IPOPT or fatrop, their options), then ``compile_problem`` it once and
``solve`` it (``og.solve(problem, og.Method(N=64), og.SolverOptions())``, or by keyword,
``og.solve(problem, N=64)``).

The package is laid out as its pipeline: ``lie`` -> ``groupoid`` -> ``model`` (problem,
mechanics) -> ``nlp`` (schemes, layout, assembly, transcription) -> ``verify`` (replay, verdict,
the checks that do not trust the solver) -> ``solve`` (the compiled problem, guesses,
read-out, solution) and ``simulation`` (the variational integrator run forward) ->
``systems`` (the canonical systems) -> ``files``
(YAML), ``export`` (C code), ``plotting`` -> ``sweep``, ``bench``, ``mpc`` -> ``cli`` (see
docs/explanation/architecture.md).
"""

from . import _startup  # noqa: F401  (first: Ctrl-C while the command line starts, one line)

# isort: split
import warnings
from typing import Any

from . import lie
from ._version import __version__
from .errors import (
    BoundaryError,
    ConfigError,
    DimensionError,
    OcgError,
    SingularityError,
    SolverError,
    TranscriptionError,
)
from .export import export_c
from .groupoid import Groupoid, LieGroupFactor, Pair, SphereAction
from .lie import SE2, SE3, SO3, se2, se3, so3
from .model import GuessContext, Problem
from .mpc import MpcResult, mpc
from .nlp import Discretization, Guess, Method, SolverOptions, Transcription
from .plotting import plot, view  # registers Solution.plot; matplotlib loads on use
from .simulation import Simulation, simulate
from .solve import (
    CompiledProblem,
    Solution,
    close_workers,
    compile_problem,
    solve,
    solve_to_accuracy,
)
from .sweep import sweep  # Dask, pandas and pyarrow are imported when a sweep runs

#: the names of earlier releases, still answered with a DeprecationWarning (:func:`__getattr__`)
_RENAMED = {"compile": "compile_problem", "Solver": "CompiledProblem"}


def __getattr__(name: str) -> Any:
    """``og.compile`` and ``og.Solver``, the names of earlier releases: the same objects as
    ``og.compile_problem`` and ``og.CompiledProblem``, with a DeprecationWarning (``compile``
    shadowed Python's builtin; ``Solver`` was not the IPOPT or fatrop solver but a compiled
    problem)."""
    if name in _RENAMED:
        new = _RENAMED[name]
        warnings.warn(f"og.{name} is now og.{new} (same arguments); the old name will go",
                      DeprecationWarning, stacklevel=2)
        return globals()[new]
    raise AttributeError(f"module 'ocgroupoid' has no attribute {name!r}")

__all__ = [
    "lie", "so3", "Problem", "GuessContext", "Groupoid", "LieGroupFactor", "Pair",
    "SphereAction", "Method", "SolverOptions", "Discretization", "Transcription", "Guess",
    "CompiledProblem", "compile_problem", "solve",
    "solve_to_accuracy", "close_workers",
    "Solution", "OcgError", "ConfigError", "DimensionError", "SingularityError",
    "BoundaryError", "TranscriptionError", "SolverError", "export_c", "sweep", "__version__",
    "SO3", "SE3", "SE2", "se3", "se2", "plot", "view",
    "simulate", "Simulation", "mpc", "MpcResult",
]
