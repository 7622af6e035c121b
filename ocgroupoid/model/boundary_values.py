"""Boundary values: the one parser of prescribed initial and final states and velocities.

A problem's ``initial(...)``/``final(...)``, the overrides of one instance
(``Transcription.pack``) and the initial values of a simulation all read
``{name: value}`` through :func:`prescribe`, so that a value is checked, and a mistake named,
the same way everywhere: ``end.name`` (``initial.R``, ``final.Omega``) and the fix.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

from ..errors import ConfigError
from ..groupoid.product import Groupoid
from .values import check_vector


@dataclass
class Boundary:
    """Prescribed values at one end: ``states[name]``, ``velocities[name]``.

    A value of None leaves the whole quantity free; for vector states and velocities a
    list may hold None in single components (``[0, 0, None]``).
    """

    states: dict[str, Any] = field(default_factory=dict)
    velocities: dict[str, Any] = field(default_factory=dict)

    def copy(self) -> Boundary:
        """A copy whose values can be overridden without changing this one."""
        return Boundary(dict(self.states), dict(self.velocities))


def state_value(groupoid: Groupoid, name: str, value: Any, end: str) -> Any:
    """A state value checked: None (free), or numeric (componentwise None for R^n); ``end``
    (``initial``, ``final``) names it in messages."""
    _, f = groupoid.by_state(name)
    if value is None:
        return None
    if f.componentwise:
        return check_vector(value, f.state_size, allow_none=True, what=f"{end}.{name}")
    return f.parse_state(value)


def velocity_value(groupoid: Groupoid, name: str, value: Any,
                   end: str) -> list[float | None] | None:
    """A velocity value checked: None (free) or a vector with optional None components."""
    _, f = groupoid.by_velocity(name)
    if value is None:
        return None
    return check_vector(value, f.algebra_dim, allow_none=True, what=f"{end}.{name}")


def prescribe(where: Boundary, values: Mapping[str, Any], end: str, groupoid: Groupoid,
              velocities: bool) -> None:
    """Write ``values`` (state and velocity names to values) into ``where``, each checked.

    ``velocities``: whether velocities take boundary values (second-order problems; in a
    first-order one they are the controls). A name that is neither a state nor a velocity of
    ``groupoid`` is refused with the names it has.
    """
    for name, value in values.items():
        if name in groupoid.state_names:
            where.states[name] = state_value(groupoid, name, value, end)
        elif name in groupoid.velocity_names:
            if not velocities:
                raise ConfigError(
                    f"{end}.{name}: a first-order problem takes no velocity conditions"
                )
            where.velocities[name] = velocity_value(groupoid, name, value, end)
        else:
            raise ConfigError(
                f"{end}.{name}: unknown; states are {groupoid.state_names}, "
                f"velocities {groupoid.velocity_names}"
            )


def prescribed(value: Any) -> bool | list[bool]:
    """Whether a boundary value prescribes its state: wholly, not at all, or per component."""
    if value is None:
        return False
    if isinstance(value, (list, tuple)) and any(v is None for v in value):
        return [v is not None for v in value]
    return True
