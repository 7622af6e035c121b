"""``ocgroupoid check FILE``: validate a problem file and print its dimensions and boundary
conditions, without solving."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer
from rich.table import Table

from ..console import SET_HELP, fail, out
from ..errors import OcgError


def check(
    file: Path = typer.Argument(..., help="problem file (YAML)"),
    set_: list[str] = typer.Option([], "--set", help=SET_HELP),
) -> None:
    """Validate a problem file and print its dimensions and boundary conditions, no solve.

    Exits 2 when the file is invalid or a boundary condition is redundant.
    """
    from .. import files
    from ..solve.accuracy import AUTO_BUILT
    from ..solve.checks import check as run_check

    try:
        cfg = files.load(file, set_)
        f = cfg.file
        d = f.discretization
        problem = files.build(cfg)
        # N: auto is checked on its first grid; scheme: auto with the scheme every problem has
        N = f.horizon.grids[0] if f.horizon.N == "auto" else f.horizon.N
        scheme = AUTO_BUILT if d.scheme == "auto" else d.scheme
        report = run_check(problem, N, d.retraction, d.rule, f.solver.ipopt, scheme, d.steps)
    except OcgError as e:
        fail(str(e))
        return
    # a retraction acts on group factors only: on R^n every retraction is the translation
    retraction = f", {d.retraction}" if _has_group_factor(problem) else ""
    t = Table(title=f"{cfg.name}: model {f.model}, N={N}, T={f.horizon.T}, "
                    f"{scheme}{retraction}" + (" (the first grid of N: auto)"
                                               if f.horizon.N == "auto" else ""),
              show_header=False)
    t.add_column(style="bold")
    t.add_column()
    t.add_row("variables", str(report.variables))
    t.add_row("constraints", f"{report.total_constraints} (" + ", ".join(
        f"{k} {v}" for k, v in report.constraints.items() if v) + ")")
    t.add_row("degrees of freedom", f"{report.degrees_of_freedom} (variables - equality rows)"
              + (f"; {report.inequalities} inequality rows" if report.inequalities else ""))
    t.add_row("prescribed", ", ".join(report.prescribed) or "-")
    t.add_row("free (natural boundary conditions)", ", ".join(report.free) or "-")
    t.add_row("redundant", ", ".join(report.redundant) or "none")
    out.print(t)
    if report.redundant:
        fail("redundant constraints (LICQ fails, IPOPT would stall): "
             + "; ".join(report.redundant) + ". Remove or free the boundary condition named.")


def _has_group_factor(problem: Any) -> bool:
    """Whether a factor of the problem moves on a group other than R^n (where the choice of
    retraction matters)."""
    from ..lie.rn import Rn

    return any(not isinstance(f.group, Rn) for f in problem.groupoid.factors)
