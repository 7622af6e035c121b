"""The names of earlier releases still answer, with a DeprecationWarning naming the new one."""

from __future__ import annotations

import pytest

import ocgroupoid as og


@pytest.mark.parametrize(("old", "new"), [("compile", "compile_problem"),
                                          ("Solver", "CompiledProblem")])
def test_old_name_warns_and_is_the_new_object(old: str, new: str) -> None:
    with pytest.warns(DeprecationWarning, match=f"og.{old} is now og.{new}"):
        assert getattr(og, old) is getattr(og, new)


def test_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'compiler'"):
        og.compiler  # noqa: B018
