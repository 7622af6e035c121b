"""The continuous problem: a reduced Lagrangian (or a cost) on a Lie algebroid, its controls,
constraints and boundary values, and the Euler-Lagrange operator derived from it.

``model`` (singular) is the modelling *language*: :class:`Problem` and what it is written
with — declarations, statement, boundary values, labels, mechanics. The *models* written in
it, the canonical systems a problem file names with ``model:``, are in
:mod:`ocgroupoid.systems` (plural), one layer up.
"""

from .mechanics import Mechanics, euler_lagrange, split
from .problem import Boundary, GuessContext, Problem

__all__ = ["Problem", "Boundary", "GuessContext", "Mechanics", "euler_lagrange", "split"]
