"""Checks that a problem says what it means, before anything is built.

A second-order problem (order 2, the default) discretises ``int Ltilde(q, y, dy) dt``: its
velocities are tied across nodes by their rates ``dy``, through the mechanics or the
accelerations the cost and the constraints read. A problem written without ``order: 1`` whose
cost, constraints and bounds never read a rate, and that has no mechanics, ties its
velocities to nothing between the nodes: the node stages see only the means
``(xi_{k-1} + xi_k)/2``, and the optimiser returns a zig-zag whose means obey every constraint
while the path does not (a Dubins car a quarter of its true length). Such a problem is a
first-order one in disguise, and is refused with the fix.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca

from ..errors import ConfigError

if TYPE_CHECKING:
    from .problem import Problem


def check_order(pb: "Problem") -> None:
    """Refuse a second-order problem whose velocities nothing ties together (module
    docstring), naming the fix."""
    if pb.order != 2 or pb.dynamics is not None:
        return
    exprs = [pb.cost, pb.terminal, *[c for _, c in pb.constraints],
             *[b.expr for b in pb.inequalities], *[c for _, c in pb.controls]]
    if any(e is not None and ca.depends_on(e, pb.dy) for e in exprs):
        return
    raise ConfigError(
        f"{pb.name} is written as a second-order problem (order 2, the default), but nothing "
        "in it reads a rate of its velocities: no mechanics(), and neither the cost, the "
        "constraints, the bounds nor the controls use an acceleration — its velocities are "
        "tied to nothing between the nodes, and the solver would return a zig-zag artefact. "
        "A problem whose velocities are the controls (a car, a kinematic model) is "
        "first-order: write `order: 1` in the definition (Problem(..., order=1) in Python)")
