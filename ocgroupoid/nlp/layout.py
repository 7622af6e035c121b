"""Where every quantity of the discrete problem lives in ``w = [x; p]``.

The decision variables are

    x = [the scheme's stage variables | free initial-state components | free V_0 | free V_N
         | one local horizon N h per phase (adaptive steps) | T (a free horizon)],

(end velocities exist in second-order problems only), and the runtime parameters

    p = [physical parameters P | initial targets | V_0 | final targets | V_N | T],

where T is the horizon, or the initial guess of a free one.

Every quantity is addressed by integer indices into w: a prescribed boundary component
points into p, a free one into x, so that stage functions read both alike. Which
components are prescribed (:class:`Masks`) is the NLP's structure, fixed at build time.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ..errors import BoundaryError
from ..groupoid.base import BoundaryMask
from ..groupoid.product import Groupoid
from ..model.problem import Boundary, Problem

PARAMETER_KEYS = ("P", "start", "V0", "end", "VN", "T")


@dataclass(frozen=True)
class Masks:
    """Which boundary components are prescribed (True) — structural, fixed at build time."""

    start_state: tuple[np.ndarray, ...]  # per factor, one flag per state component
    end_state: tuple[np.ndarray, ...]  # per factor, one flag per chart row
    start_velocity: np.ndarray
    end_velocity: np.ndarray

    @staticmethod
    def of(groupoid: Groupoid, end_velocities: bool, start_bc: Boundary, end_bc: Boundary
           ) -> "Masks":
        G = groupoid
        start, end = [], []
        for f in G.factors:
            v0 = start_bc.states.get(f.state)
            if not f.componentwise:
                if v0 is None:
                    raise BoundaryError(
                        f"initial.{f.state} is required: the initial {f.state} of "
                        f"{type(f).__name__} cannot be left free"
                    )
                start.append(np.ones(f.state_size, dtype=bool))
            else:
                start.append(np.array([c is not None for c in (v0 or [None] * f.state_size)]))
            vT = end_bc.states.get(f.state)
            if f.componentwise:
                end.append(np.array([c is not None for c in (vT or [None] * f.state_dim)]))
            else:
                end.append(np.full(f.state_dim, vT is not None))

        def vel(b: dict[str, Any]) -> np.ndarray:
            out = np.zeros(G.algebra_dim, dtype=bool)
            if not end_velocities:
                return out
            for f, vs in zip(G.factors, G.velocity_layout.slices):
                v = b.get(f.velocity)
                if v is not None:
                    out[vs] = [c is not None for c in v]
            return out

        return Masks(tuple(start), tuple(end), vel(start_bc.velocities),
                     vel(end_bc.velocities))

    def factor(self, G: Groupoid, i: int) -> BoundaryMask:
        """The flags of factor i, as its guesses read them."""
        vs = G.velocity_layout.slices[i]
        return BoundaryMask(self.end_state[i], self.start_velocity[vs], self.end_velocity[vs])

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Masks):
            return NotImplemented
        same = lambda a, b: all(np.array_equal(x, y) for x, y in zip(a, b))  # noqa: E731
        return (same(self.start_state, other.start_state)
                and same(self.end_state, other.end_state)
                and same((self.start_velocity, self.end_velocity),
                         (other.start_velocity, other.end_velocity)))


class Layout:
    """Indices into ``w = [x; p]`` of the boundary quantities and the scheme's variables
    (module docstring). ``n_stage`` is the number of the scheme's own variables, which come
    first in x; the scheme arranges them itself (:attr:`stage`)."""

    def __init__(self, problem: Problem, masks: Masks, n_stage: int, N: int,
                 phases: tuple[int, ...] = ()) -> None:
        G = problem.groupoid
        ds, dg, nt = G.state_size, G.algebra_dim, G.target_size
        self.masks = masks
        self.stage = np.arange(n_stage)
        nx = n_stage
        free_s0 = np.concatenate([~m for m in masks.start_state])
        x_s0 = nx + np.arange(int(free_s0.sum()))
        nx += x_s0.size
        free_V0 = ~masks.start_velocity if problem.end_velocities else np.zeros(dg, bool)
        free_VN = ~masks.end_velocity if problem.end_velocities else np.zeros(dg, bool)
        x_V0 = nx + np.arange(int(free_V0.sum()))
        nx += x_V0.size
        x_VN = nx + np.arange(int(free_VN.sum()))
        nx += x_VN.size
        x_phases = nx + np.arange(len(phases))
        nx += x_phases.size
        x_T = np.array([nx]) if problem.T_free else np.zeros(0, dtype=np.int64)
        nx += x_T.size
        self.nx = nx
        sizes = dict(zip(PARAMETER_KEYS, (problem.P.numel(), nt, dg, nt, dg, 1)))
        self.p_slices: dict[str, slice] = {}
        k = 0
        for key in PARAMETER_KEYS:
            self.p_slices[key] = slice(k, k + sizes[key])
            k += sizes[key]
        self.np = k
        pw = {key: nx + np.arange(s.start, s.stop) for key, s in self.p_slices.items()}
        #: w-indices of the initial node state: prescribed components from p, free ones in x
        self.s0 = np.zeros(ds, dtype=np.int64)
        k = 0
        for f, ss, ts, m in zip(G.factors, G.state_layout.slices, G.target_layout.slices,
                                masks.start_state):
            for j in range(f.state_size):
                if m[j]:
                    self.s0[ss.start + j] = pw["start"][ts.start + j]
                else:
                    self.s0[ss.start + j] = x_s0[k]
                    k += 1
        self.V0, self.VN = pw["V0"].copy(), pw["VN"].copy()
        self.V0[free_V0] = x_V0
        self.VN[free_VN] = x_VN
        #: the horizon: in x when free (then p's T slot holds its initial guess), else in p
        self.T = x_T if problem.T_free else pw["T"]
        self.T_guess = pw["T"]
        #: adaptive steps: the number of intervals of each phase, and each phase's local
        #: horizon ``N h`` (uniform steps within a phase, its duration free)
        self.phases, self.phase_steps = tuple(phases), x_phases
        #: w-index of each interval's local horizon ``N h_k`` (the stage functions' "T"): the
        #: horizon itself for uniform steps, its phase's for adaptive ones
        self.steps = np.repeat(x_phases, phases) if phases else np.full(N, self.T[0])
        self.P, self.start, self.end = pw["P"], pw["start"], pw["end"]

    def gather(self, w: ca.MX, idx: np.ndarray) -> ca.MX:
        """``w[idx]`` shaped like idx (a matrix gathered column-major)."""
        idx = np.asarray(idx)
        flat = w[idx.ravel(order="F").tolist()]
        return ca.reshape(flat, idx.shape[0], idx.shape[1]) if idx.ndim == 2 else flat

    def compose(self, parts: list[tuple[np.ndarray, ca.MX]]) -> ca.MX:
        """The point x whose entries at the w-indices of each part hold its values (later
        parts win; indices into p are ignored; untouched entries are zero)."""
        values = [ca.vec(v) for _, v in parts]
        source = ca.vertcat(*values, ca.MX.zeros(1))
        index = np.full(self.nx, source.numel() - 1)
        offset = 0
        for (idx, _), v in zip(parts, values):
            flat = np.asarray(idx).ravel(order="F")
            here = flat < self.nx
            index[flat[here]] = offset + np.flatnonzero(here)
            offset += v.numel()
        return source[index.tolist()]
