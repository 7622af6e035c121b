"""Solving a transcription: guesses, IPOPT (multi-start, continuation), the read-out into a
Solution, and the checks that do not trust the solver."""

from .auto import Level, solve_to_accuracy
from .entry import compile, solve
from .guesses import geodesic_guesses, interpolate, perturbed_guesses
from .readout import make_solution
from .solution import Solution, write_atomic
from .solver import Minimum, Solver, distinct_minima

__all__ = ["Solver", "compile", "solve", "Solution", "Minimum", "distinct_minima",
           "make_solution", "geodesic_guesses", "perturbed_guesses", "interpolate",
           "write_atomic", "solve_to_accuracy", "Level"]
