"""One entry of a custom model's ``definition.describe``: what a quantity means, its unit and
its quantity group, per component or for all of them (:meth:`Problem.describe`)."""

from __future__ import annotations

from typing import Annotated

from pydantic import AfterValidator, Field

from ..model.values import Strict


def _text(what: str, example: str) -> AfterValidator:
    """A check that a name is non-blank text (one string, or every string of a list)."""

    def check(value: str | list[str] | None) -> str | list[str] | None:
        items = [value] if isinstance(value, str) else value or []
        if any(not v.strip() for v in items):
            raise ValueError(f"a {what} is non-blank text such as {example}; leave the key "
                             "out where there is none")
        return value

    return AfterValidator(check)


UNIT = _text("unit", "'N m', or '1' when dimensionless")
UnitText = Annotated[str, UNIT]  # ``name: unit``, the short form of an entry
Unit = Annotated[str | list[str] | None, UNIT]
Group = Annotated[str | list[str] | None, _text("group", "'thrusters'")]
Components = Annotated[list[str] | None, _text("component label", "'about body x'")]


class Described(Strict):
    """One entry of ``definition.describe``: what a quantity means, its unit and group."""

    meaning: str | None = Field(None, description="what the quantity is (plot titles)")
    unit: Unit = Field(
        None, description="one unit for every component, or a list of one per component "
        "(a figure never draws two units in one panel)")
    components: Components = Field(None, description="one label per component (legend)")
    group: Group = Field(
        None, description="the quantity group, for every component or one per component: "
        "a figure draws one panel per (group, unit) of a quantity")
