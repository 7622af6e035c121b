"""Lie groups and retractions, written once for NumPy and CasADi SX/MX."""

from . import so3
from .group import LieGroup
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
from .so3 import SO3

__all__ = [
    "LieGroup", "SO3", "Rn", "so3", "Retraction", "Cayley", "Exp", "FirstOrder",
    "Translation", "retraction", "RETRACTION_NAMES", "cay", "dcay", "dcay_inv",
]
