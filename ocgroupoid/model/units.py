"""Names, units and quantity groups of what a Solution reports (:meth:`Problem.describe`,
:meth:`Problem.control`, :meth:`Problem.labels`).

A :class:`Description` gives a quantity a meaning and, per component, a legend label, a unit
and a quantity group; a figure draws one panel per (group, unit) of a quantity, never two
units in one panel. What a model leaves undeclared gets a default from its factor
(:func:`default_description`): a rotation's tangent in rad and its velocity in rad per time
unit; a pose's translation in m (m per time unit); a direction on S^2 dimensionless; the
velocity of a vector state described in unit ``x`` in ``x`` per time unit ("rate of" its
meaning).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ..errors import ConfigError
from ..groupoid.base import Factor

#: tangent coordinates of the group factors, their units (``T``: the time unit) and labels
TANGENTS: dict[str, tuple[list[str], list[str], list[str]]] = {
    "SO(3)": (["about x", "about y", "about z"], ["rad"] * 3, ["rad/T"] * 3),
    "SE(3)": (["about x", "about y", "about z", "x", "y", "z"], ["rad"] * 3 + ["m"] * 3,
              ["rad/T"] * 3 + ["m/T"] * 3),
    "SE(2)": (["heading", "x", "y"], ["rad", "m", "m"], ["rad/T", "m/T", "m/T"]),
    "S^2": (["x", "y", "z"], ["1"] * 3, ["rad/T"] * 3),
}


@dataclass(frozen=True)
class Description:
    """What a reported quantity means (:meth:`Problem.describe`): a meaning, and one label,
    one unit ("" where none was declared) and one quantity group ("": the quantity's own)
    per component."""

    kind: str  # the section of the labels: time, states, velocities, controls, multipliers
    meaning: str
    components: tuple[str, ...]
    units: tuple[str, ...]
    groups: tuple[str, ...] = ()

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready; ``groups`` only where one was declared (files stay as they were)."""
        out: dict[str, Any] = {"meaning": self.meaning, "components": list(self.components),
                               "units": list(self.units)}
        if any(self.groups):
            out["groups"] = list(self.groups)
        return out


def per_component(value: Any, n: int, what: str, name: str, repeat: bool) -> list[str] | None:
    """None, or n strings: a list of n, or (``repeat``) one string for all of them."""
    where = f"describe({name!r})"
    if value is None:
        return None
    if isinstance(value, str):
        if repeat or n == 1:
            return [value] * n
        raise ConfigError(f"{where}: {name} has {n} components, so the {what} labels are "
                          f"a list of {n}, got the string {value!r}")
    items = list(value) if isinstance(value, (list, tuple)) else None
    if items is None or not all(isinstance(v, str) for v in items):
        raise ConfigError(f"{where}: the {what}s are strings (a list of {n}), got "
                          f"{value!r}")
    if len(items) != n:
        hint = "one string for all of them or " if repeat else ""
        raise ConfigError(f"{where}: {name} has {n} component{'s' * (n != 1)}, got "
                          f"{len(items)} {what}s {items}; give {hint}a list of {n}")
    return items


def describe(kind: str, n: int, name: str, meaning: str | None, unit: Any, components: Any,
             group: Any) -> Description:
    """The Description of ``name`` (``kind``, n components), its arguments checked (a
    ConfigError names the call and the fix)."""
    what = f"describe({name!r})"
    if meaning is not None and not isinstance(meaning, str):
        raise ConfigError(f"{what}: the meaning is a string, got {meaning!r}")
    meaning = meaning or name
    units = per_component(unit, n, "unit", name, repeat=True) or [""] * n
    labels = per_component(components, n, "component", name, repeat=False) or \
        ([meaning] if n == 1 else [f"{name}{i + 1}" for i in range(n)])
    groups = per_component(group, n, "group", name, repeat=True) or [""] * n
    if kind == "time" and (components is not None or group is not None):
        raise ConfigError(f"{what}: the time axis has no components or groups; give a "
                          "meaning and a unit")
    if len(set(labels)) != len(labels):
        raise ConfigError(f"{what}: component labels must differ (one legend entry "
                          f"each), got {labels}")
    return Description(kind, meaning, tuple(labels), tuple(units), tuple(groups))


def rate(unit: str, time_unit: str) -> str:
    """The unit of the rate of a quantity in ``unit``: ``m`` -> ``m/s``, ``1`` -> ``1/s``;
    "" (undeclared) stays undeclared."""
    if not unit:
        return ""
    return f"({unit})/{time_unit}" if "/" in unit else f"{unit}/{time_unit}"


def default_description(f: Factor, kind: str, time_unit: str,
                        state: Description | None = None) -> Description | None:
    """The Description of the state (``kind`` "states") or velocity ("velocities") of factor
    ``f`` when the model declares none: by its manifold (module docstring); a vector state's
    velocity in its state's unit per time unit when ``state`` declares one; else None."""
    name = f.state if kind == "states" else f.velocity
    if f.manifold in TANGENTS:
        labels, state_units, rate_units = TANGENTS[f.manifold]
        if kind == "states":
            return Description(kind, name, tuple(labels), tuple(state_units))
        units = [u.replace("/T", f"/{time_unit}") for u in rate_units]
        return Description(kind, name, tuple(f"{name}{i + 1}" for i in range(len(units))),
                           tuple(units))
    if kind == "velocities" and state is not None and any(state.units) and \
            len(state.units) == f.algebra_dim:
        meaning = f"rate of the {state.meaning}" if state.meaning != f.state else name
        return Description(kind, meaning, tuple(f"{name}{i + 1}" for i in range(f.algebra_dim))
                           if f.algebra_dim > 1 else (meaning,),
                           tuple(rate(u, time_unit) for u in state.units))
    return None


def control_labels(names: Sequence[str], inputs: dict[str, int],
                   d: dict[str, Description]) -> dict[str, Any]:
    """The ``controls`` section of the labels: one label, unit, symbol (the control declared
    with :meth:`Problem.control` a component belongs to, or its own name) and group per
    control, the meaning of all of them and of each described symbol."""
    group = d.get("u") if "u" not in names else None
    comps = list(group.components) if group else list(names)
    units = list(group.units) if group else [""] * len(names)
    groups = list(group.groups) if group and group.groups else [""] * len(names)
    symbols = list(names)
    meanings: dict[str, str] = {}
    k = 0
    for n, size in inputs.items():  # a control of its own (tau), described or not
        symbols[k:k + size] = [n] * size
        if n in d and d[n].kind == "controls" and size > 1:
            comps[k:k + size], units[k:k + size] = d[n].components, d[n].units
            groups[k:k + size] = d[n].groups or [""] * size
            meanings[n] = d[n].meaning
        k += size
    for j, n in enumerate(names):
        if n in d and d[n].kind == "controls":
            comps[j], units[j] = d[n].components[0], d[n].units[0]
            groups[j] = d[n].groups[0] if d[n].groups else ""
            meanings[n] = d[n].meaning
    one = d.get(names[0]) if len(names) == 1 else None  # a single control
    out: dict[str, Any] = {"meaning": group.meaning if group else one.meaning if one else
                           "controls", "components": comps, "units": units,
                           "symbols": symbols}
    if meanings:
        out["meanings"] = meanings
    if any(groups):
        out["groups"] = groups
    return out
