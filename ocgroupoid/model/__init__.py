"""The continuous problem: a reduced Lagrangian (or a cost) on a Lie algebroid, its controls,
constraints and boundary values, and the Euler-Lagrange operator derived from it."""

from .mechanics import Mechanics, euler_lagrange, split
from .problem import Boundary, GuessContext, Problem

__all__ = ["Problem", "Boundary", "GuessContext", "Mechanics", "euler_lagrange", "split"]
