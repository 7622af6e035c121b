"""Lie groups and retractions, written once for NumPy and CasADi SX/MX."""

from . import se2, se3, so3
from .form import StateForm
from .group import LieGroup, MatrixGroup
from .retraction import (
    RETRACTION_NAMES,
    Cayley,
    Exp,
    FirstOrder,
    Retraction,
    Translation,
    cay,
    dcay,
    dcay_inv,
    retraction,
)
from .rn import Rn
from .se2 import SE2
from .se3 import SE3
from .so3 import SO3

__all__ = [
    "LieGroup", "MatrixGroup", "StateForm", "SO3", "SE3", "SE2", "Rn", "so3", "se3", "se2",
    "Retraction", "Cayley", "Exp", "FirstOrder", "Translation", "retraction",
    "RETRACTION_NAMES", "cay", "dcay", "dcay_inv",
]
