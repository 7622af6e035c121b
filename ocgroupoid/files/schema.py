"""The top-level sections of a problem file, as pydantic models (unknown keys are errors).

The model-specific sections (``parameters``, ``initial``, ``final``) are each model's own
schemas (:class:`~ocgroupoid.models.registry.ModelSpec`).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field

from ..lie.retraction import RETRACTION_NAMES
from ..model.values import Horizon as HorizonT
from ..model.values import Strict
from ..nlp.schemes import SCHEME_NAMES


class Horizon(Strict):
    """Final time and number of intervals."""

    T: HorizonT = Field(description="final time (> 0)")
    N: Annotated[int, Field(strict=True, ge=2, description="number of intervals (>= 2)")]


class DiscretizationSection(Strict):
    """Scheme, retraction of the group factors and rule of the constraints."""

    scheme: Literal[SCHEME_NAMES] = Field(  # type: ignore[valid-type]
        "order2", description="discretisation scheme (ocgroupoid list shows them)")
    retraction: Literal[RETRACTION_NAMES] = Field(  # type: ignore[valid-type]
        "cayley", description="cayley (default), exp, or first_order (the seeds' rule)")
    rule: str = Field("midpoint", description="discretisation rule of the constraints")


class SolverSection(Strict):
    """IPOPT options and the globalisation strategy."""

    ipopt: dict[str, str | int | float] = Field(
        default_factory=dict, description="options passed to IPOPT (e.g. tol, max_iter)")
    multistart: bool | Annotated[int, Field(strict=True, ge=0)] = Field(
        False, description="true, or the number of perturbed starts on top of the geodesics")
    continuation: list[Annotated[int, Field(strict=True, ge=2)]] = Field(
        default_factory=list, description="coarser N solved first, e.g. [16, 32]")


class OutputSection(Strict):
    """Where the CLI writes its results (overridden by --out/--plot)."""

    file: str | None = Field(None, description="solution JSON path")
    plot: str | None = Field(None, description="PNG path for the plot")


class ProblemFile(Strict):
    """The top level of a problem file."""

    model: str = Field(description="a built-in model (see `ocgroupoid list`) or custom")
    name: str | None = Field(None, description="problem name (default: the file's stem)")
    definition: dict[str, Any] | None = Field(
        None, description="model: custom only — groupoid, Lagrangian, cost, constraints")
    parameters: dict[str, Any] = Field(default_factory=dict, description="model parameters")
    horizon: Horizon
    initial: dict[str, Any] = Field(default_factory=dict, description="initial conditions")
    final: dict[str, Any] = Field(default_factory=dict, description="final conditions")
    discretization: DiscretizationSection = Field(default_factory=DiscretizationSection)
    solver: SolverSection = Field(default_factory=SolverSection)
    output: OutputSection = Field(default_factory=OutputSection)
