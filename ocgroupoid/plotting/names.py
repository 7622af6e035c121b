"""What a Solution says about its quantities: meanings, component labels and units, the
prescribed final states and the bounds (``Solution.labels``), with defaults for files written
before it was recorded."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

ANGLES = {"rad", "deg", "°", "rev"}  # units of an R^2 state that is not a point of a plane


@dataclass(frozen=True)
class Quantity:
    """A reported quantity: its symbol, meaning, and one label, unit and quantity group per
    component; ``symbols`` (per component) and ``meanings`` (per symbol) when it gathers
    several declared quantities (the controls: a thrust f and torques tau)."""

    name: str
    meaning: str
    components: list[str]
    units: list[str]
    groups: list[str] = field(default_factory=list)
    symbols: list[str] = field(default_factory=list)
    meanings: dict[str, str] = field(default_factory=dict)

    def panels(self) -> list[tuple[str, str, list[int]]]:
        """The components by (group, unit), in order of first appearance: one panel each
        (never two units in one panel)."""
        groups = self.groups or [""] * len(self.units)
        out: dict[tuple[str, str], list[int]] = {}
        for i, key in enumerate(zip(groups, self.units)):
            out.setdefault(key, []).append(i)
        return [(g, u, idx) for (g, u), idx in out.items()]

    def symbol(self, idx: list[int]) -> str:
        """The symbol of components ``idx``: the one they share, else the quantity's."""
        syms = {self.symbols[i] for i in idx} if self.symbols else set()
        return syms.pop() if len(syms) == 1 else self.name


def with_unit(text: str, unit: str) -> str:
    """``text [unit]``; "1" is dimensionless (``[-]``), "" an undeclared unit (no brackets)."""
    if unit == "1":
        return f"{text} [-]"
    return f"{text} [{unit}]" if unit else text


def called(meaning: str, name: str) -> str:
    """How a title names the quantity ``name``: its meaning followed by its symbol ("attitude
    R"), the meaning alone when it already holds the symbol as a word (an undescribed quantity's
    meaning is its symbol: "g", never "g g")."""
    if re.search(rf"(?<!\w){re.escape(name)}(?!\w)", meaning):
        return meaning
    return f"{meaning} {name}"


def manifold(sol: Any, name: str) -> str:
    """The manifold of a state: as the Solution names it, else from its shape (a solution
    written before manifolds were recorded: 3 x 3 matrices are rotations, 4 x 4 poses)."""
    shape = np.shape(sol.states[name])[1:]
    default = {(3, 3): "SO(3)", (4, 4): "SE(3)"}.get(shape, f"R^{shape[0]}" if shape else "")
    return sol.manifolds.get(name) or default


class Names:
    """The labels of one Solution, defaults filled in."""

    def __init__(self, sol: Any) -> None:
        self.sol = sol
        self.labels: dict[str, Any] = dict(getattr(sol, "labels", None) or {})

    @property
    def time_unit(self) -> str:
        """The unit of t ("s" unless the model declared another)."""
        return str(self.labels.get("time", {}).get("unit", "s"))

    @property
    def time_label(self) -> str:
        """The time axis: ``time t [s]`` (the model's meaning and unit of t)."""
        return with_unit(f"{self.labels.get('time', {}).get('meaning', 'time')} t",
                         self.time_unit)

    def free_horizon(self) -> list[float | None] | None:
        """``[T_min, T_max]`` when the final time was a decision variable, else None."""
        free = self.sol.discretization.get("T_range") or self.labels.get("time", {}).get("free")
        return list(free) if free else None

    def quantity(self, kind: str, name: str, n: int, defaults: Sequence[str] | None = None,
                 units: Sequence[str] | None = None) -> Quantity:
        """A state, velocity or multiplier group of n components: as described, else named
        ``defaults`` (or after its symbol: ``Omega1``...) in ``units`` (or no unit)."""
        d = self.labels.get(kind, {}).get(name)
        if d and len(d.get("components", [])) == n and len(d.get("units", [])) == n:
            return Quantity(name, d.get("meaning") or name, list(d["components"]),
                            list(d["units"]), _groups(d, n))
        comps = list(defaults) if defaults else \
            ([name] if n == 1 else [f"{name}{i + 1}" for i in range(n)])
        return Quantity(name, name, comps, list(units) if units else [""] * n)

    def controls(self) -> Quantity:
        """All the controls, with the symbol (f, tau) and group of each, as declared."""
        names = list(self.sol.control_names) or \
            [f"u{i + 1}" for i in range(self.sol.controls.shape[1])]
        n = len(names)
        d = self.labels.get("controls")
        symbol = names[0] if n == 1 else "u"
        if d and len(d.get("components", [])) == n:
            symbols = d.get("symbols") if len(d.get("symbols") or []) == n else names
            return Quantity(symbol, d.get("meaning") or "controls", list(d["components"]),
                            list(d["units"]), _groups(d, n), list(symbols),
                            dict(d.get("meanings") or {}))
        return Quantity(symbol, "controls", names, [""] * n, symbols=names)

    def final(self, name: str) -> bool | list[bool]:
        """Whether the final value of a state was prescribed (per component for R^n); a file
        without labels: the states its diagnostics report a final residual for."""
        if "final" in self.labels:
            return self.labels["final"].get(name, False)
        return name in (self.sol.diagnostics.get("final_residual") or {})

    def bounds(self, kind: str, name: str | None = None) -> dict[int, tuple[float | None,
                                                                         float | None]]:
        """Component index -> (lower, upper) of the bounds on one quantity (``kind``
        "controls": index = control column; "velocities"/"states": component of ``name``)."""
        out: dict[int, tuple[float | None, float | None]] = {}
        for b in self.labels.get("bounds", []):
            if b.get("quantity") == kind and (kind == "controls" or b.get("of") == name):
                out[int(b["index"])] = (self._side(b, "lower"), self._side(b, "upper"))
        return out

    def _side(self, bound: dict[str, Any], key: str) -> float | None:
        """A side of a bound: its affine form in the parameters evaluated at the solution's
        (the exported C solver's files carry only that), else the recorded value."""
        form = bound.get(f"{key}_affine")
        params = self.sol.parameters or {}
        if form and all(k in params for k in form["gradient"]):
            return float(form["constant"] + sum(np.dot(g, params[k])
                                                for k, g in form["gradient"].items()))
        return bound.get(key)

    @staticmethod
    def planar(q: Quantity) -> bool:
        """Whether an R^2 state is a point of a plane (drawn as a path): both components in
        one declared unit that is not an angle (two rotor angles are not a point)."""
        return len(q.units) == 2 and q.units[0] == q.units[1] and \
            q.units[0] not in ANGLES | {""}

    def final_miss(self, name: str) -> float:
        """How far the final value of ``name`` is from its target (the solution's
        ``diagnostics.final_residual``: an angle in rad for rotations and directions); 0 when
        not recorded."""
        return float((self.sol.diagnostics.get("final_residual") or {}).get(name, 0.0))


def _groups(d: dict[str, Any], n: int) -> list[str]:
    """The quantity groups of a labels entry: one per component ("" where none declared)."""
    groups = d.get("groups") or []
    return [str(g) for g in groups] if len(groups) == n else [""] * n
