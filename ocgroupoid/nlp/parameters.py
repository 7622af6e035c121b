"""The numbers that describe one instance, and the packing that turns them into p.

An instance is written as a vector of *values*: the physical parameters, every boundary
state once (a rotation as its quaternion, a pose as its quaternion and position, a
direction as its unit vector, a point of R^n
as its components), the boundary velocities and T. :meth:`ParameterValues.pack_function`
turns values into the NLP parameters p (quaternions normalised, tangent bases of the
directions completed: each factor's :meth:`~ocgroupoid.groupoid.base.Factor.pack_target`)
and flags values outside their domain. Python packs through this Function and exported C
calls the same one: the packing is written once.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import casadi as ca
import numpy as np

from ..errors import ConfigError
from ..model.problem import Problem
from .layout import Layout, Masks


@dataclass(frozen=True)
class ValueBlock:
    """One key of an instance: its numbers and where they go in p."""

    key: str  # "inertia", "initial.R", "final.Omega", "T", ...
    kind: str  # "vector", "rotation", "pose", "direction" (a factor's value_kind), "horizon"
    values: slice  # slot in the values vector
    p: slice  # slot in p (a direction's slot also holds its tangent basis)
    prescribed: tuple[bool, ...]  # per number: False = free, the number is ignored
    meaning: str
    factor: int | None = None  # index of the factor of a boundary state

    @property
    def size(self) -> int:
        return self.values.stop - self.values.start

    @property
    def note(self) -> str:
        """Which numbers are free here (read and ignored), or ''."""
        free = [i for i, on in enumerate(self.prescribed) if not on]
        if not free:
            return ""
        return "free: ignored" if len(free) == self.size else f"components {free} free: ignored"


class ParameterValues:
    """The values of an instance and their map to p (module docstring)."""

    def __init__(self, problem: Problem, masks: Masks, layout: Layout) -> None:
        self.problem, self.layout = problem, layout
        G, lay = problem.groupoid, layout.p_slices
        blocks: list[ValueBlock] = []
        n = 0

        def add(key: str, kind: str, size: int, p0: int, psize: int,
                prescribed: Sequence[bool], meaning: str, factor: int | None = None) -> None:
            nonlocal n
            blocks.append(ValueBlock(key, kind, slice(n, n + size), slice(p0, p0 + psize),
                                     tuple(bool(b) for b in prescribed), meaning, factor))
            n += size

        P0 = lay["P"].start
        for name, sl in problem.parameter_slices.items():
            size = sl.stop - sl.start
            add(name, "vector", size, P0 + sl.start, size, [True] * size,
                problem.params[name].doc or "physical parameter")
        for end, key_s, key_v, masks_s, masks_v in (
                ("initial", "start", "V0", masks.start_state, masks.start_velocity),
                ("final", "end", "VN", masks.end_state, masks.end_velocity)):
            for i, (f, ts, m) in enumerate(zip(G.factors, G.target_layout.slices, masks_s)):
                flags = list(m) if f.componentwise else [bool(np.all(m))] * f.state_size
                add(f"{end}.{f.state}", f.value_kind, f.state_size, lay[key_s].start + ts.start,
                    f.target_size, flags, f.value_meaning, i)
            if problem.end_velocities:
                for f, vs in zip(G.factors, G.velocity_layout.slices):
                    add(f"{end}.{f.velocity}", "vector", f.algebra_dim,
                        lay[key_v].start + vs.start, f.algebra_dim, list(masks_v[vs]),
                        "velocity")
        add("T", "horizon", 1, lay["T"].start, 1, [True], "horizon T > 0")
        self.blocks = blocks
        self.size = n
        self.pack_function = self._pack_function()

    def _pack_function(self) -> ca.Function:
        """``pack(values) -> (p, bad)``: bad[i] = 1 when block i is outside its domain (a
        zero quaternion, a direction whose length differs from 1 by more than 1e-6, T <= 0)."""
        G = self.problem.groupoid
        v = ca.SX.sym("values", self.size)
        p = ca.SX.zeros(self.layout.np)
        bad = []
        for b in self.blocks:
            x = ca.vertcat(*[v[b.values][i] if on else 0 for i, on in enumerate(b.prescribed)])
            flag = ca.SX(0)
            if not any(b.prescribed):
                bad.append(flag)
                continue
            if b.factor is not None:
                f = G.factors[b.factor]
                packed, flag = f.pack_target(x), f.invalid(x)
            elif b.kind == "horizon":
                packed, flag = x, ca.logic_not(x > 0)
            else:
                packed = x
            p[b.p] = packed
            bad.append(flag)
        return ca.Function("pack", [v], [p, ca.vertcat(*bad)], ["values"], ["p", "bad"])

    def values_of(self, p: np.ndarray) -> np.ndarray:
        """The values of a numeric p (the inverse of packing on packed vectors)."""
        p = np.asarray(p, dtype=float)
        out = np.zeros(self.size)
        for b in self.blocks:
            out[b.values] = p[b.p][: b.size]
        return out

    def pack(self, values: np.ndarray) -> np.ndarray:
        """Numeric p of numeric values; a value outside its domain is a ConfigError."""
        p, bad = (np.array(a).ravel() for a in self.pack_function(values))
        wrong = [b.key for b, flag in zip(self.blocks, bad) if flag]
        if wrong:
            raise ConfigError(f"values outside their domain: {', '.join(wrong)} (a zero "
                              "quaternion, a direction that is not of unit length, T <= 0)")
        return p
