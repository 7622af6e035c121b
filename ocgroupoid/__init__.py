"""ocgroupoid: optimal control on Lie groups and Lie groupoids, compiled to one NLP.

State the continuous problem with :class:`Problem` on a product of groupoid factors
(:class:`LieGroupFactor`, :class:`Pair`, :class:`SphereAction`), then ``compile`` it on N
intervals with a retraction and ``solve`` it with IPOPT.
"""

from . import lie
from .codegen import export_c
from .discretize import Discretization
from .errors import (
    BoundaryError,
    ConfigError,
    DimensionError,
    OcgError,
    SingularityError,
    SolverError,
    TranscriptionError,
)
from .groupoid import Groupoid, LieGroupFactor, Pair, SphereAction
from .lie import so3
from .problem import Problem
from .solution import Solution
from .solve import Solver, compile, solve
from .transcribe import Guess, Transcription

__version__ = "0.1.0"

__all__ = [
    "lie", "so3", "Problem", "Groupoid", "LieGroupFactor", "Pair", "SphereAction",
    "Discretization", "Transcription", "Guess", "Solver", "compile", "solve", "Solution",
    "OcgError", "ConfigError", "DimensionError", "SingularityError", "BoundaryError",
    "TranscriptionError", "SolverError", "export_c", "__version__",
]
