"""From a continuous problem to one NLP: the method and the solver options, schemes,
variable layout, boundary conditions, derivative assembly, the NLP, its backends (IPOPT,
fatrop) and the transcription that ties them together."""

from .assembly import Block, Kind
from .layout import Layout, Masks
from .method import Discretization, Method
from .options import SolverOptions
from .program import Guess, NonlinearProgram
from .schemes import SCHEME_NAMES, Scheme, make_scheme
from .transcription import RawResult, Transcription

__all__ = ["Block", "Kind", "Layout", "Masks", "Scheme", "SCHEME_NAMES", "make_scheme",
           "Method", "SolverOptions", "Discretization", "Guess", "NonlinearProgram",
           "RawResult", "Transcription"]
