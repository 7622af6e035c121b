"""``ocgroupoid list``: the built-in models, the discretisation schemes, the retractions and
the problem files found."""

from __future__ import annotations

import os
from pathlib import Path

from rich.table import Table

from ..console import out

CUSTOM_SUMMARY = ("your own model, written in the problem file: a definition section (groupoid "
                  "factors, Lagrangian or controls, cost); e.g. custom_rigid_body.yaml")


def list_models() -> None:
    """Built-in models, discretisation schemes and the problem files shipped in problems/."""
    from ..lie.retraction import RETRACTION_NAMES
    from ..nlp.schemes import SCHEMES
    from ..systems import MODELS

    t = Table(title="models")
    t.add_column("model")
    t.add_column("what it is")
    for name, spec in sorted(MODELS.items()):
        t.add_row(name, spec.summary)
    t.add_row("custom", CUSTOM_SUMMARY)
    out.print(t)
    t = Table(title="schemes (discretization.scheme)")
    t.add_column("scheme")
    t.add_column("order")
    t.add_column("problems")
    t.add_column("what it is")
    for name, by_order in SCHEMES.items():
        for problem_order, cls in sorted(by_order.items(), reverse=True):
            t.add_row(name, str(cls.accuracy), f"order-{problem_order}", cls.summary)
    out.print(t)
    out.print("retractions (discretization.retraction): " + ", ".join(RETRACTION_NAMES))
    folders = problem_folders()
    for folder in folders:
        names = ", ".join(p.name for p in sorted(folder.glob("*.yaml")))
        out.print(f"problem files in {folder}: {names}", highlight=False, soft_wrap=True)
    if not folders:
        out.print("no problem files found (looked in ./problems and next to the package)")


def problem_folders() -> list[Path]:
    """The folders of problem files `list` shows, from any working directory: ./problems,
    the problems/ of a source checkout holding this package, and the copy installed under
    PREFIX/share/ocgroupoid/problems (pyproject.toml's data-files)."""
    import sysconfig

    here = Path(__file__).resolve().parent.parent  # the package ocgroupoid/
    candidates = [Path.cwd() / "problems", here.parent / "problems"]
    for scheme in (sysconfig.get_default_scheme(), f"{os.name}_user"):
        try:
            candidates.append(Path(sysconfig.get_path("data", scheme)) / "share" / "ocgroupoid"
                              / "problems")
        except KeyError:
            continue
    found: list[Path] = []
    for folder in candidates:
        if folder.is_dir() and any(folder.glob("*.yaml")) and \
                all(folder.resolve() != f.resolve() for f in found):
            found.append(folder)
    return found
