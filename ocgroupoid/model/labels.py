"""Names, meanings and units of what a Solution reports, for figures and solution files.

:class:`Labels` adds to the declarations (:mod:`~ocgroupoid.model.declarations`)
``describe`` (what a state, velocity, control, multiplier or the time axis means, and its
unit) and ``labels``: everything a Solution reports, named, with its units, which final
values are prescribed and what each bound row limits. Undescribed states and velocities of
group factors get their units from :mod:`ocgroupoid.model.units`.
"""

from __future__ import annotations

from typing import Any, Sequence

import casadi as ca
import numpy as np

from ..errors import ConfigError
from .boundary_values import prescribed
from .declarations import Declarations
from .units import control_labels, default_description, describe


class Labels(Declarations):
    """What the quantities of a problem mean and their units (see the module docstring)."""

    def describe(self, name: str, meaning: str | None = None,
                 unit: str | Sequence[str] | None = None,
                 components: Sequence[str] | None = None,
                 group: str | Sequence[str] | None = None) -> None:
        """Say what ``name`` means and its unit, for plots and solution files::

            pb.describe("Omega", "body angular velocity", "rad/s",
                        components=["about body axis 1", "about body axis 2", "about body axis 3"])

        ``name`` is a state, a velocity, a control, ``u`` (all the controls), a constraint
        (its multipliers) or ``t`` (the time axis; "s" unless declared). ``unit`` is one
        string for every component or a list of one per component; ``components`` labels
        each component (the legend); ``group`` (one string, or one per component) names the
        quantity group a component is drawn with: a figure has one panel per (group, unit)
        of a quantity, so components of one unit in different groups get panels of their
        own. A vector state's components are its entries; a group state's are its tangent
        coordinates, in its velocity's order (SO(3): 3 angles; SE(3): 3 angles, then the
        position; SE(2): the heading, then x, y). A later call for the same name replaces an
        earlier one. Undescribed states and velocities of group factors get their units by
        default (:mod:`ocgroupoid.model.units`).
        """
        kind, n = self._quantity(name)
        self.descriptions[name] = describe(kind, n, name, meaning, unit, components, group)

    def _quantity(self, name: str) -> tuple[str, int]:
        """The labels section ``name`` belongs to and its number of components."""
        G = self.groupoid
        controls = [n for n, _ in self.controls]
        constraints = {n: c.numel() for n, c in self.constraints}
        if not isinstance(name, str):
            raise ConfigError(f"describe: a name is a string, got {name!r}")
        if name == "t":
            return "time", 1
        if name in G.state_names:
            _, f = G.by_state(name)
            shape = f.matrix_shape  # a matrix: a group element, described in its tangent
            return "states", f.algebra_dim if len(shape) == 2 else int(np.prod(shape))
        if name in G.velocity_names:
            return "velocities", G.by_velocity(name)[1].algebra_dim
        if name in controls:
            return "controls", 1
        if name in self.inputs:  # a control of its own with several components (tau)
            return "controls", self.inputs[name].numel()
        if name == "u" and controls:
            return "controls", len(controls)
        if name in constraints:
            return "multipliers", constraints[name]
        raise ConfigError(
            f"describe: unknown name {name!r}; known: states {G.state_names}, velocities "
            f"{G.velocity_names}, controls {controls + (['u'] if controls else [])}, "
            f"constraints {list(constraints)}, and t (time). Controls and constraints exist "
            "once mechanics(), report_controls() or subject_to() declared them: describe "
            "them after")

    def labels(self, P: Any = None) -> dict[str, Any]:
        """Names and units of everything a Solution reports, JSON-ready (``Solution.labels``).

        ``time`` (meaning, unit, and ``free: [T_min, T_max]`` for a free horizon); the
        described ``states``, ``velocities`` and ``multipliers`` (name -> meaning, components,
        units); ``controls`` (one label and unit per control, in order); ``final``: which
        final states and velocities are prescribed (True, False, or per component);
        ``bounds``: one entry per bound row (name, component, the quantity it limits if it is
        a control, a velocity or a vector state component, and its sides at the parameter
        values P, default the declared ones; None where a side is open).
        """
        d = self.descriptions
        time = d.get("t")
        out: dict[str, Any] = {"time": {"meaning": time.meaning if time else "time",
                                        "unit": time.units[0] if time else "s"}}
        if self.T_free:
            out["time"]["free"] = [_finite(v) for v in self.T_bounds]
        for kind in ("states", "velocities", "multipliers"):
            out[kind] = {n: v.as_dict() for n, v in d.items() if v.kind == kind}
        for f in self.groupoid.factors:  # the defaults of what the model left undescribed
            for kind, n in (("states", f.state), ("velocities", f.velocity)):
                default = default_description(f, kind, out["time"]["unit"], d.get(f.state))
                if n not in d and default is not None:
                    out[kind][n] = default.as_dict()
        names = [n for n, _ in self.controls]
        if names:
            out["controls"] = control_labels(
                names, {n: sym.numel() for n, sym in self.inputs.items()}, d)
        out["final"] = {**{f.state: prescribed(self.end.states.get(f.state))
                           for f in self.groupoid.factors},
                        **{f.velocity: prescribed(self.end.velocities.get(f.velocity))
                           for f in self.groupoid.factors if self.end_velocities}}
        out["bounds"] = self._bound_labels(self.parameter_values() if P is None else P)
        return out

    def _bound_labels(self, P: Any) -> list[dict[str, Any]]:
        rows: list[dict[str, Any]] = []
        for b in self.inequalities:
            sides = ca.vertcat(b.lower, b.upper)
            lo, hi = np.split(np.array(ca.Function("sides", [self.P], [sides])(P)).ravel(), 2)
            for i, e in enumerate(ca.vertsplit(b.expr)):
                row = {"name": b.name, "component": i, "lower": _finite(lo[i]),
                       "upper": _finite(hi[i]), "parametric": False, **self._limited(e)}
                for key, side in (("lower", b.lower[i]), ("upper", b.upper[i])):
                    if self.P.numel() and ca.depends_on(side, self.P):
                        row["parametric"] = True
                        row[f"{key}_affine"] = self._affine(side)
                rows.append(row)
        return rows

    def _affine(self, side: ca.SX) -> dict[str, Any] | None:
        """``side = constant + sum over parameters of gradient . value`` when it is affine in
        the parameters (``-tau_max``), so that a reader evaluates it at other values; else
        None."""
        if not ca.is_linear(side, self.P):
            return None
        grad, c0 = ca.Function("affine", [self.P], [ca.jacobian(side, self.P), side])(
            np.zeros(self.P.numel()))
        g = np.array(grad).ravel()
        return {"constant": float(c0), "gradient": {
            name: g[sl].tolist() for name, sl in self.parameter_slices.items() if g[sl].any()}}

    def _limited(self, e: ca.SX) -> dict[str, Any]:
        """The reported quantity a bound row limits: a control, or a component of a velocity
        or of a vector state; ``quantity`` None for any other expression."""
        G = self.groupoid
        for j, (n, c) in enumerate(self.controls):
            if ca.is_equal(e, c, 64):
                return {"quantity": "controls", "of": n, "index": j}
        if e.is_symbolic():
            for f, vs in zip(G.factors, G.velocity_layout.slices):
                for k in range(vs.start, vs.stop):
                    if ca.is_equal(e, self.y[k]):
                        return {"quantity": "velocities", "of": f.velocity, "index": k - vs.start}
            for f, qs in zip(G.factors, G.base_layout.slices):
                for k in range(qs.start, qs.stop):
                    if f.componentwise and ca.is_equal(e, self.q[k]):
                        return {"quantity": "states", "of": f.state, "index": k - qs.start}
        return {"quantity": None, "of": None, "index": None}


def _finite(v: Any) -> float | None:
    """A JSON number, None for an infinite (open) side."""
    v = float(v)
    return v if np.isfinite(v) else None
