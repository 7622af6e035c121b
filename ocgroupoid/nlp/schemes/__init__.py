"""Discretisation schemes by name: one class per scheme and problem order."""

from __future__ import annotations

from ...errors import ConfigError
from ...model.problem import Problem
from .base import DEFAULT_RULE, Readout, Scheme
from .gauss_stages import GaussStages, GaussStages3
from .order2 import IntervalMidpoint, Node, NodeMidpoint
from .order4 import QuadraticGauss
from .order6 import CubicGauss
from .shooting import RK4Euler, RK4Matrix, RK4Quaternion

#: scheme name -> problem order (1 or 2) -> class
SCHEMES: dict[str, dict[int, type[Scheme]]] = {
    "order2": {2: NodeMidpoint, 1: IntervalMidpoint},
    "order4": {2: QuadraticGauss, 1: GaussStages},
    "order6": {2: CubicGauss, 1: GaussStages3},
    "rk4_quat": {2: RK4Quaternion, 1: RK4Quaternion},
    "rk4_matrix": {2: RK4Matrix, 1: RK4Matrix},
    "rk4_euler": {2: RK4Euler, 1: RK4Euler},
}
#: the baselines: RK4 shooting as a rockit/Opti user writes it, there to be measured against
BASELINES = ("rk4_quat", "rk4_matrix", "rk4_euler")
SCHEME_NAMES = tuple(SCHEMES)
DEFAULT_SCHEME = "order2"


def make_scheme(name: str, problem: Problem, N: int, retraction: str, rule: str,
                bound_points: int = 0) -> Scheme:
    """The scheme called ``name`` for ``problem`` (its class depends on the problem order);
    ``bound_points`` more points per interval where the bounds hold (order4 and order6)."""
    if name not in SCHEMES:
        raise ConfigError(f"unknown scheme {name!r}; choose one of {', '.join(SCHEME_NAMES)}")
    cls = SCHEMES[name][problem.order]
    if bound_points and not cls.adaptive_steps:
        raise ConfigError(f"discretization.bound_points imposes the bounds at more points "
                          f"inside order4's and order6's intervals; {name} evaluates them at "
                          "its nodes: choose scheme order4, or increase N")
    if bound_points:  # only the schemes with adaptive_steps take them (checked above)
        return cls(problem, N, retraction, rule, bound_points)  # type: ignore[call-arg]
    return cls(problem, N, retraction, rule)


__all__ = ["Scheme", "Readout", "Node", "NodeMidpoint", "IntervalMidpoint", "QuadraticGauss",
           "CubicGauss", "GaussStages", "GaussStages3", "SCHEMES", "BASELINES",
           "SCHEME_NAMES", "DEFAULT_SCHEME", "DEFAULT_RULE", "make_scheme"]
