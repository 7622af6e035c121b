"""Lie groupoids of discrete mechanics: Lie groups, pair and action groupoids, products."""

from .action import SphereAction
from .base import Factor
from .lie_group import LieGroupFactor
from .pair import Pair
from .product import Groupoid, Layout

__all__ = ["Factor", "LieGroupFactor", "Pair", "SphereAction", "Groupoid", "Layout"]
