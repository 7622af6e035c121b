"""One exception hierarchy: every message names the cause and the fix."""

from __future__ import annotations


class OcgError(Exception):
    """Base class of every error ocgroupoid raises on purpose."""


class ConfigError(OcgError, ValueError):
    """A problem file or API argument is malformed (bad key, type, value)."""


class DimensionError(OcgError, ValueError):
    """An array has the wrong shape for the slot it is given to."""


class SingularityError(OcgError, ArithmeticError):
    """A retraction or chart was evaluated at its singularity."""


class BoundaryError(OcgError, ValueError):
    """The boundary conditions are over- or under-determined."""


class TranscriptionError(OcgError, RuntimeError):
    """The NLP could not be assembled from the problem."""


class SolverError(OcgError, RuntimeError):
    """IPOPT did not converge; the message carries its status and a hint."""


class ExportError(OcgError, RuntimeError):
    """Exported C code could not be written or built (missing compiler, IPOPT, ...)."""


class DependencyError(OcgError, ImportError):
    """An optional dependency is not installed; the message names the extra to install."""


class StorageError(OcgError, RuntimeError):
    """A result could not be written (a full disk, a read-only folder); what was written
    before stays whole. The command line exits with :data:`STORAGE_EXIT`."""


#: the exit code of a command stopped by a StorageError (0 done, 1 failed, 2 bad input)
STORAGE_EXIT = 3
