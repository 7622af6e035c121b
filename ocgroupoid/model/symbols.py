"""This problem's symbols as its user names them, for messages.

CasADi names the elements of a vector symbol ``s_0, s_1, ...``; a message that says "the
Lagrangian uses s_6" names an internal. :func:`symbol_labels` maps every element of a
problem's symbols to what the user wrote (``the node state g``, ``the rate of Omega``,
``the control f``), and :func:`foreign_message` explains a symbol that is not the problem's.
:func:`check_symbols` refuses, with such a message, an expression (a Lagrangian, a cost, a
bound...) that reads a symbol it may not.
"""

from __future__ import annotations

import re

import casadi as ca

from ..errors import ConfigError
from .declarations import Declarations

#: the names CasADi gives the elements of a Problem's own vector symbols
_INTERNAL = re.compile(r"(q|s|y|dy)_\d+")


def symbol_labels(pb: Declarations) -> list[tuple[ca.SX, str]]:
    """(element, label) for every scalar symbol of the problem."""
    G = pb.groupoid
    out: list[tuple[ca.SX, str]] = []
    for name, prm in pb.params.items():
        out += [(e, f"the parameter {name}") for e in ca.vertsplit(prm.symbol)]
    for f, ss, bs, vs in zip(G.factors, G.state_layout.slices, G.base_layout.slices,
                             G.velocity_layout.slices):
        out += [(pb.s[i], f"the node state {f.state}") for i in range(ss.start, ss.stop)]
        out += [(pb.q[i], f"the state {f.state}") for i in range(bs.start, bs.stop)]
        out += [(pb.y[i], f"the velocity {f.velocity}") for i in range(vs.start, vs.stop)]
        out += [(pb.dy[i], f"the rate of {f.velocity} ({f.velocity}_dot)")
                for i in range(vs.start, vs.stop)]
    for name, sym in pb.inputs.items():
        out += [(e, f"the control {name}") for e in ca.vertsplit(sym)]
    return out


def foreign_message(what: str, names: list[str]) -> str:
    """Why symbols that are not the problem's cannot be used, and what to use instead."""
    internal = [n for n in names if _INTERNAL.fullmatch(n)]
    other = [n for n in names if n not in internal]
    parts = []
    if internal:
        parts.append("symbols of another Problem (each Problem has its own)")
    if other:
        parts.append(f"{', '.join(repr(n) for n in dict.fromkeys(other))}, declared outside "
                     "this problem (e.g. with ca.SX.sym)")
    return (f"{what} uses {' and '.join(parts)}: build it from this problem's symbols — "
            "pb.parameter, pb.state, pb.node_state, pb.velocity, pb.acceleration, pb.control")


def check_symbols(pb: Declarations, expr: ca.SX, what: str, states: bool = False,
                  rates: bool = True, velocities: bool = True, params_only: bool = False,
                  controls: bool = False) -> None:
    """Refuse symbols that ``what`` may not read, or that are not this problem's
    (compared by identity, not by name); the message names them as the user does."""
    groups = [("the parameters", pb.P)]
    if not params_only:
        groups.append(("the base coordinates (pb.state)", pb.q))
        if states:
            groups.append(("the node states (pb.node_state)", pb.s))
        if velocities:
            groups.append(("the velocities", pb.y))
        if rates and pb.order == 2:
            groups.append(("their rates (pb.acceleration)", pb.dy))
        if controls:
            groups.append(("the controls (pb.control)", pb.U))
    allowed = ca.vertsplit(ca.vertcat(*[g for _, g in groups]))
    bad = [v for v in ca.symvar(expr) if not any(ca.is_equal(v, a) for a in allowed)]
    if not bad:
        return
    mine = symbol_labels(pb)
    known = list(dict.fromkeys(label for v in bad for sym, label in mine
                               if ca.is_equal(v, sym)))
    strangers = [v.name() for v in bad if not any(ca.is_equal(v, sym) for sym, _ in mine)]
    may = ", ".join(n for n, _ in groups)
    parts = []
    if known:
        parts.append(f"{what} may not depend on {', '.join(known)}: it may read {may}")
    if strangers:
        parts.append(foreign_message(what, strangers))
    raise ConfigError("; ".join(parts))
