"""Running a problem forward: the discrete controlled Euler-Lagrange equations stepped by
Newton (:mod:`~ocgroupoid.simulation.flow`) under given controls, from given initial values
(:func:`~ocgroupoid.simulation.simulate.simulate`)."""

from .simulate import Simulation, simulate

__all__ = ["Simulation", "simulate"]
