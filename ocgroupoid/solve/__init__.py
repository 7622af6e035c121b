"""Solving: the compiled problem (multi-start, continuation, adaptive steps), its guesses, the
read-out into a Solution, and accuracy on demand. Verifying a solution is
:mod:`ocgroupoid.verify`'s job; running a problem forward, :mod:`ocgroupoid.simulation`'s."""

from .accuracy import Level, solve_to_accuracy
from .compiled import CompiledProblem, Minimum, distinct_minima
from .entry import compile_problem, solve
from .guesses import geodesic_guesses, interpolate, perturbed_guesses
from .parallel import close as close_workers
from .readout import make_solution
from .solution import Solution, write_atomic

__all__ = ["CompiledProblem", "compile_problem", "solve", "Solution", "Minimum", "distinct_minima",
           "make_solution", "geodesic_guesses", "perturbed_guesses", "interpolate",
           "write_atomic", "solve_to_accuracy", "Level", "close_workers"]
