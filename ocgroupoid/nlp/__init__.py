"""From a continuous problem to one NLP: schemes, variable layout, boundary conditions,
derivative assembly and the transcription that ties them to IPOPT."""

from .assembly import Block, Kind
from .layout import Layout, Masks
from .schemes import SCHEME_NAMES, Scheme, make_scheme
from .transcription import Discretization, Guess, RawResult, Transcription

__all__ = ["Block", "Kind", "Layout", "Masks", "Scheme", "SCHEME_NAMES", "make_scheme",
           "Discretization", "Guess", "RawResult", "Transcription"]
