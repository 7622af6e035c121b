"""Products of factor groupoids: G_1 x ... x G_m => Q_1 x ... x Q_m.

The product is itself a groupoid (structure maps act factor by factor); it also lays out
the concatenated vectors the transcription works with: node states, velocities, base
coordinates and packed boundary targets, each as consecutive slices per factor.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import casadi as ca

from ..errors import ConfigError
from .base import Factor


@dataclass(frozen=True)
class Layout:
    """Start/stop of each factor's block inside a concatenated vector."""

    slices: tuple[slice, ...]

    @property
    def size(self) -> int:
        return self.slices[-1].stop if self.slices else 0

    @staticmethod
    def of(sizes: Sequence[int]) -> "Layout":
        out, start = [], 0
        for n in sizes:
            out.append(slice(start, start + n))
            start += n
        return Layout(tuple(out))


class Groupoid:
    """A product of factors; a single factor is a product of one."""

    def __init__(self, *factors: Factor) -> None:
        if not factors:
            raise ConfigError("a groupoid needs at least one factor")
        self.factors: tuple[Factor, ...] = tuple(factors)
        for attr in ("state", "velocity"):
            names = [getattr(f, attr) for f in factors]
            dupes = {n for n in names if names.count(n) > 1}
            if dupes:
                raise ConfigError(f"{attr} names must be distinct, repeated: {sorted(dupes)}")
        overlap = {f.state for f in factors} & {f.velocity for f in factors}
        if overlap:
            raise ConfigError(f"names used both for a state and a velocity: {sorted(overlap)}")
        self.state_layout = Layout.of([f.state_size for f in factors])
        self.velocity_layout = Layout.of([f.algebra_dim for f in factors])
        self.base_layout = Layout.of([f.base_size for f in factors])
        self.target_layout = Layout.of([f.target_size for f in factors])

    @property
    def state_size(self) -> int:
        return self.state_layout.size

    @property
    def algebra_dim(self) -> int:
        return self.velocity_layout.size

    @property
    def base_size(self) -> int:
        return self.base_layout.size

    @property
    def target_size(self) -> int:
        return self.target_layout.size

    def by_state(self, name: str) -> tuple[int, Factor]:
        """Index and factor whose node state is called ``name``."""
        for i, f in enumerate(self.factors):
            if f.state == name:
                return i, f
        raise ConfigError(f"no state called {name!r}; states are {self.state_names}")

    def by_velocity(self, name: str) -> tuple[int, Factor]:
        """Index and factor whose velocity is called ``name``."""
        for i, f in enumerate(self.factors):
            if f.velocity == name:
                return i, f
        raise ConfigError(f"no velocity called {name!r}; velocities are {self.velocity_names}")

    def base(self, s: Any) -> Any:
        """Base coordinates q (what the Lagrangian sees) of a product node state s."""
        parts = [f.base(s[ss]) for f, ss in zip(self.factors, self.state_layout.slices)]
        return ca.vertcat(*parts) if self.base_size else type(s)(0, 1)

    def step(self, s: Any, retractions: Sequence[Any], a: Any) -> Any:
        """The next product state: every factor stepped by its part of the increment a."""
        return ca.vertcat(*[f.step(s[ss], r, a[vs]) for f, r, ss, vs in
                            zip(self.factors, retractions, self.state_layout.slices,
                                self.velocity_layout.slices)])

    def coordinate_rate(self, retractions: Sequence[Any], theta: Any, y: Any) -> Any:
        """dTheta/dt of the product's step coordinates, factor by factor."""
        return ca.vertcat(*[f.coordinate_rate(r, theta[vs], y[vs]) for f, r, vs in
                            zip(self.factors, retractions, self.velocity_layout.slices)])

    def magnus(self, ya: Any, yb: Any, H: Any) -> Any:
        """The fourth-order Magnus step of every factor (:meth:`Factor.magnus`)."""
        return ca.vertcat(*[f.magnus(ya[vs], yb[vs], H) for f, vs in
                            zip(self.factors, self.velocity_layout.slices)])

    def magnus6(self, y1: Any, y2: Any, y3: Any, H: Any) -> Any:
        """The sixth-order Magnus step of every factor (:meth:`Factor.magnus6`)."""
        return ca.vertcat(*[f.magnus6(y1[vs], y2[vs], y3[vs], H) for f, vs in
                            zip(self.factors, self.velocity_layout.slices)])

    def velocity_of_rate(self, retractions: Sequence[Any], theta: Any, rate: Any) -> Any:
        """The product velocity of coordinate rates, factor by factor."""
        return ca.vertcat(*[f.velocity_of_rate(r, theta[vs], rate[vs]) for f, r, vs in
                            zip(self.factors, retractions, self.velocity_layout.slices)])

    def state_rate(self, s: Any, y: Any) -> Any:
        """ds/dt of a product state for the velocity y (the reconstruction equations)."""
        return ca.vertcat(*[f.state_rate(s[ss], y[vs]) for f, ss, vs in
                            zip(self.factors, self.state_layout.slices,
                                self.velocity_layout.slices)])

    def as_matrix(self, s: Any) -> Any:
        """A product state as users see it, factor by factor, flattened."""
        return ca.vertcat(*[f.as_matrix(s[ss]) for f, ss in
                            zip(self.factors, self.state_layout.slices)])

    @property
    def state_names(self) -> list[str]:
        return [f.state for f in self.factors]

    @property
    def velocity_names(self) -> list[str]:
        return [f.velocity for f in self.factors]

    # -- structure maps, factor by factor ---------------------------------------------

    def source(self, g: Sequence[Any]) -> tuple[Any, ...]:
        return tuple(f.source(x) for f, x in zip(self.factors, g))

    def target(self, g: Sequence[Any]) -> tuple[Any, ...]:
        return tuple(f.target(x) for f, x in zip(self.factors, g))

    def identity(self, x: Sequence[Any]) -> tuple[Any, ...]:
        return tuple(f.identity(v) for f, v in zip(self.factors, x))

    def inverse(self, g: Sequence[Any]) -> tuple[Any, ...]:
        return tuple(f.inverse(x) for f, x in zip(self.factors, g))

    def multiply(self, g: Sequence[Any], k: Sequence[Any]) -> tuple[Any, ...]:
        return tuple(f.multiply(a, b) for f, a, b in zip(self.factors, g, k))

    def __repr__(self) -> str:
        return " x ".join(repr(f) for f in self.factors)
