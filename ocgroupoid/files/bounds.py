"""The ``bounds:`` section of a problem file: names mapped to ``[lower, upper]``.

A name is a control (``u1``, ``f``), a control of its own with all its components
(``tau``), ``u`` for all the controls, a velocity (``Omega``, ``dtheta``)
or the state of an R^n factor (``theta``, ``xy``). A value is one pair for every component,
``[-1, 1]``, or one pair per component, ``[[-1, 1], [null, 2]]``; ``null`` leaves a side open.
A side may be an expression of the parameters, ``[-umax, umax]`` with ``umax`` in
``parameters:``: it changes without a rebuild (and is a runtime parameter of the C export).
Each entry becomes :meth:`Problem.bound`, imposed wherever the scheme evaluates its
constraints.
"""

from __future__ import annotations

from typing import Any, Callable

import casadi as ca

from ..errors import ConfigError
from ..model.problem import Problem
from ..model.values import number
from .expressions import CONSTANTS, compile_expression


def expression(pb: Problem, name: str) -> ca.SX:
    """The expression a bounds key names (module docstring)."""
    controls = dict(pb.controls)
    if name in controls:
        return controls[name]
    if name in pb.inputs:  # a control of its own, all its components (tau)
        return pb.inputs[name]
    if name == "u" and controls:
        return ca.vertcat(*controls.values())
    G = pb.groupoid
    if name in G.velocity_names:
        return pb.velocity(name)
    if name in G.state_names:
        _, f = G.by_state(name)
        if not f.componentwise:
            raise ConfigError(f"{name} lives on {f.manifold}, which has no components to "
                              "bound; write a path inequality (custom model: definition.path) "
                              "such as a keep-out cone instead")
        return pb.state(name)
    known = [*controls, *[n for n in pb.inputs if n not in controls],
             *(["u"] if controls else []), *G.velocity_names,
             *[f.state for f in G.factors if f.componentwise]]
    raise ConfigError(f"unknown name {name!r}; bounds apply to {', '.join(known) or 'nothing'}")


Side = float | ca.SX | None


def side(pb: Problem, v: Any, what: str) -> Side:
    """One side of a bound: None (open), a number, or an expression of the parameters."""
    if v is None:
        return None
    if isinstance(v, str):
        symbols = {**CONSTANTS, **{k: prm.symbol for k, prm in pb.params.items()}}
        expr = compile_expression(v, symbols, what)
        if expr.numel() != 1:
            raise ConfigError(f"{what}: {v!r} is not a scalar")
        return expr if ca.depends_on(expr, pb.P) else float(ca.evalf(expr))
    return number(v, what)


def pairs(pb: Problem, value: Any, n: int, name: str) -> tuple[list[Side], list[Side]]:
    """Lower and upper bounds (n each, None = open) of a ``[lo, hi]`` or per-component value."""
    if not isinstance(value, (list, tuple)) or not value:
        raise ConfigError(f"bounds.{name} is [lower, upper] or a list of such pairs, got "
                          f"{value!r}")
    per = value if isinstance(value[0], (list, tuple)) else [value] * n
    if len(per) != n or any(not isinstance(v, (list, tuple)) or len(v) != 2 for v in per):
        raise ConfigError(f"bounds.{name} needs one [lower, upper] pair or {n} of them "
                          f"(one per component), got {value!r}")
    lo = [side(pb, v[0], f"bounds.{name} lower") for v in per]
    hi = [side(pb, v[1], f"bounds.{name} upper") for v in per]
    for i, (a, b) in enumerate(zip(lo, hi)):
        if isinstance(a, float) and isinstance(b, float) and a > b:
            raise ConfigError(f"bounds.{name}: component {i} has lower {a} > upper {b}")
        if a is None and b is None:
            raise ConfigError(f"bounds.{name}: component {i} is open on both sides; drop it "
                              "or give a side")
    return lo, hi


def apply(pb: Problem, bounds: dict[str, Any], where: Callable[..., str]) -> None:
    """Impose every entry of a ``bounds:`` section on the problem."""
    for name, value in bounds.items():
        try:
            expr = expression(pb, name)
            lo, hi = pairs(pb, value, expr.numel(), name)
            pb.bound(expr, lo, hi, name=name)
        except ConfigError as err:
            raise ConfigError(f"{where('bounds', name)}: {err}") from None
