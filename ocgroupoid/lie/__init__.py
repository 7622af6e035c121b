"""Lie groups and retractions, written once for NumPy and CasADi SX/MX.

One class per group over one base (:class:`LieGroup`), its elements held as the numbers
node states store; ``SO3``, ``SE3`` and ``SE2`` are the groups, ``Rn(n)`` the vector spaces.
The modules ``so3``, ``se3`` and ``se2`` also hold the constructors problem files use
(``so3.from_axis_angle``, ``se3.from_spec``, ...), which return group matrices.
"""

from . import se2, se3, so3
from .group import LieGroup
from .retraction import (
    RETRACTION_NAMES,
    Cayley,
    Exp,
    FirstOrder,
    Retraction,
    Translation,
    retraction,
)
from .rn import Rn
from .se2 import SE2, SE2Group
from .se3 import SE3, SE3Group
from .so3 import SO3, SO3Group

__all__ = [
    "LieGroup", "SO3", "SE3", "SE2", "SO3Group", "SE3Group", "SE2Group", "Rn", "so3", "se3",
    "se2", "Retraction", "Cayley", "Exp", "FirstOrder", "Translation", "retraction",
    "RETRACTION_NAMES",
]
