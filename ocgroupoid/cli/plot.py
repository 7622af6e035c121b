"""``ocgroupoid plot``: the figure of a solution file, or of a sweep's folder."""

from __future__ import annotations

from pathlib import Path

import typer

from ..console import fail, out
from ..errors import OcgError


def plot(
    solution: Path = typer.Argument(..., help="solution JSON written by `solve --out`, or "
                                    "a sweep's folder (`sweep --out`)"),
    out_path: Path = typer.Option(..., "--out", help="PNG file to write"),
) -> None:
    """Plot a solution as `solve --plot` does (`og.plot`): every quantity with its unit, the
    attitude error to the target, x-y paths, bounds and targets. Given a sweep's folder
    (`sweep --out DIR`), plot cost and status against the swept keys."""
    import json

    from ..plotting import plot as plot_figure
    from ..solve.outputs import check_file
    from ..solve.solution import Solution

    try:
        check_file(out_path, "--out", "figure.png")
    except OcgError as e:
        fail(str(e))
        return
    if solution.is_dir():
        from ..sweep import plot_sweep
        try:
            out.print(f"figure written to {plot_sweep(solution, out_path)}")
        except OcgError as e:
            fail(str(e))
        return
    try:
        sol = Solution.from_json(solution)
    except FileNotFoundError:
        fail(f"{solution}: no such file; give the JSON written by `ocgroupoid solve --out`")
        return
    except (json.JSONDecodeError, KeyError, TypeError, ValueError, UnicodeDecodeError) as e:
        fail(f"{solution}: not a solution file ({type(e).__name__}: {e}); give the JSON "
             "written by `ocgroupoid solve --out`")
        return
    plot_figure(sol, out_path)
    out.print(f"figure written to {out_path}")
