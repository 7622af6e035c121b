"""Built-in models by name: what a problem file's ``model:`` key selects.

A model module registers a :class:`ModelSpec`: pydantic schemas for its ``parameters``,
``initial`` and ``final`` sections, and a builder that turns validated sections into a
:class:`~ocgroupoid.model.problem.Problem` using only the public API.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

from pydantic import BaseModel

if TYPE_CHECKING:
    from ..model.problem import Problem


@dataclass(frozen=True)
class ModelSpec:
    """How a problem file describes one model."""

    name: str
    summary: str
    parameters: type[BaseModel]
    initial: type[BaseModel]
    final: type[BaseModel]
    build: Callable[[BaseModel, BaseModel, BaseModel, float, str], "Problem"]


MODELS: dict[str, ModelSpec] = {}


def register(spec: ModelSpec) -> ModelSpec:
    """Add a model under its name (once)."""
    if spec.name in MODELS:
        raise ValueError(f"model {spec.name!r} registered twice")
    MODELS[spec.name] = spec
    return spec
