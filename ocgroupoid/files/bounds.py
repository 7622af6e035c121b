"""The ``bounds:`` section of a problem file: names mapped to ``[lower, upper]``.

A name is a control (``u1``, ``f``), a control of its own with all its components
(``tau``), ``u`` for all the controls, a velocity (``Omega``, ``dtheta``)
or the state of an R^n factor (``theta``, ``xy``), or one component or a slice of any of
these (``xi[0]``, ``Omega[1:3]``). A value is one pair for every component, ``[-1, 1]``, or
one pair per component, ``[[-1, 1], null, [null, 2]]``; ``null`` leaves a side open, and a
``null`` pair leaves that component unbounded.
A side may be an expression of the parameters, ``[-umax, umax]`` with ``umax`` in
``parameters:``: it changes without a rebuild (and is a runtime parameter of the C export).
Each entry becomes :meth:`Problem.bound`, imposed wherever the scheme evaluates its
constraints.
"""

from __future__ import annotations

import re
from typing import Any, Callable

import casadi as ca

from ..errors import ConfigError
from ..model.problem import Problem
from ..model.values import number
from .expressions import CONSTANTS, compile_expression

_COMPONENT = re.compile(r"\s*([A-Za-z_]\w*)\s*\[\s*([-+]?\d+)?\s*(?::\s*([-+]?\d+)?\s*)?\]\s*")


def expression(pb: Problem, name: str) -> ca.SX:
    """The expression a bounds key names (module docstring)."""
    if "[" in name:
        return _component(pb, name)
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


def _component(pb: Problem, name: str) -> ca.SX:
    """``xi[0]``, ``Omega[1:3]``: a component or a slice of what a name bounds."""
    m = _COMPONENT.fullmatch(name)
    if m is None or (m.group(2) is None and ":" not in name):
        raise ConfigError(f"{name!r}: write a component as name[i] or a slice as name[i:j], "
                          "e.g. xi[0] or Omega[0:2]")
    base = expression(pb, m.group(1))
    n = base.numel()
    if ":" in name:
        lo, hi = (int(v) if v is not None else None for v in (m.group(2), m.group(3)))
        picked = list(range(n))[slice(lo, hi)]
    else:
        i = int(m.group(2))
        picked = [i % n] if -n <= i < n else []
    if not picked:
        raise ConfigError(f"{name!r} selects no component: {m.group(1)} has {n} "
                          f"(0..{n - 1})")
    return base[picked]


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
    per = value if any(isinstance(v, (list, tuple)) for v in value) else [value] * n
    per = [[None, None] if v is None else v for v in per]  # a null pair: unbounded
    if len(per) != n or any(not isinstance(v, (list, tuple)) or len(v) != 2 for v in per):
        raise ConfigError(f"bounds.{name} needs one [lower, upper] pair or {n} of them "
                          f"(one per component, null for none), got {value!r}")
    lo = [side(pb, v[0], f"bounds.{name} lower") for v in per]
    hi = [side(pb, v[1], f"bounds.{name} upper") for v in per]
    for i, (a, b) in enumerate(zip(lo, hi)):
        if isinstance(a, float) and isinstance(b, float) and a > b:
            raise ConfigError(f"bounds.{name}: component {i} has lower {a} > upper {b}")
    if all(a is None and b is None for a, b in zip(lo, hi)):
        raise ConfigError(f"bounds.{name}: every component is open on both sides; drop the "
                          "entry or give a side")
    return lo, hi


def apply(pb: Problem, bounds: dict[str, Any], where: Callable[..., str]) -> None:
    """Impose every entry of a ``bounds:`` section on the problem."""
    for name, value in bounds.items():
        try:
            expr = expression(pb, name)
            lo, hi = pairs(pb, value, expr.numel(), name)
            keep = [i for i, (a, b) in enumerate(zip(lo, hi)) if a is not None or b is not None]
            if len(keep) < len(lo):  # null pairs: those components unbounded
                expr, lo, hi = expr[keep], [lo[i] for i in keep], [hi[i] for i in keep]
            pb.bound(expr, lo, hi, name=name)
        except ConfigError as err:
            raise ConfigError(f"{where('bounds', name)}: {err}") from None
