"""``ocgroupoid solve FILE``: build, solve and summarise a problem file; optionally write the
solution JSON and a figure."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Optional

import typer

from .._startup import interrupt_exit_code
from ..console import SET_HELP, err, fail, out, silent, status, stopped_by
from ..errors import ConfigError, OcgError
from .summary import grid_line, summary

LONG_SOLVE = 10.0  # seconds: a solve estimated longer is announced with its estimate


def solve(
    file: Path = typer.Argument(..., help="problem file (YAML)"),
    set_: list[str] = typer.Option([], "--set", help=SET_HELP),
    out_path: Optional[Path] = typer.Option(None, "--out", help="write the solution JSON here"),
    plot_path: Optional[Path] = typer.Option(None, "--plot", help="write a PNG plot here"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="print only errors"),
) -> None:
    """Build, solve and summarise a problem file; optionally write the solution JSON."""
    from .. import files
    from ..solve import compile_problem

    try:
        cfg = files.load(file, set_)
        f = cfg.file
        target, picture = _solve_outputs(out_path, plot_path, f.output)
        problem = files.build(cfg)
        est = files.estimate(cfg, problem)
        if est is not None and est.seconds > LONG_SOLVE and not quiet:
            err.print(f"N={f.horizon.N}: this solve takes {est}; solver.max_seconds = "
                      f"{f.solver.max_seconds:g}", highlight=False)
        t0 = time.perf_counter()
        if f.horizon.N == "auto":
            sol = _solve_to_accuracy(problem, f, quiet)
        else:
            with status("building the NLP...", quiet):
                solver = compile_problem(problem, files.method(cfg), files.options(cfg))
            with status("solving...", quiet) as spinner:
                sol = solver.solve(progress=spinner.update if spinner is not None else silent)
        if target is not None:
            sol.to_json(target)
        if picture is not None:
            from ..plotting import plot as plot_figure
            plot_figure(sol, picture)
    except OcgError as e:
        fail(str(e))
        return
    except OSError as e:  # checked before the solve, yet the disk may fill or a folder go
        fail(f"writing {e.filename or target}: {e.strerror or e}; free space or choose "
             "another --out/--plot")
        return
    if not quiet:
        out.print(summary(sol))
        grids = len(sol.diagnostics.get("accuracy", {}).get("levels", []))
        out.print(f"total {time.perf_counter() - t0:.2f} s (build, "
                  + (f"{grids} grids" if grids else f"{sol.starts} start"
                     f"{'s' if sol.starts > 1 else ''}") + ", diagnostics)"
                  + (f"; solution written to {target}" if target else ""))
    from rich.markup import escape
    if sol.status == "interrupted":
        err.print(f"[bold red]{stopped_by()}:[/] the best point so far is "
                  + (f"in {target} " if target else "") + "with success: false")
        raise typer.Exit(interrupt_exit_code())
    if not sol.success:
        what = "not verified" if sol.status == "Solve_Succeeded" else f"solver failed: {sol.status}"
        if sol.diagnostics.get("accuracy", {}).get("met") is False:
            what = "accuracy not reached"
        err.print(f"[bold red]{what}:[/] {escape(sol.hint)}")
        raise typer.Exit(1)


def _solve_to_accuracy(problem: Any, f: Any, quiet: bool) -> Any:
    """``horizon.N: auto``: the grid search of :mod:`ocgroupoid.solve.accuracy`, one line per
    grid on stderr as it is done."""
    from ..nlp.options import SolverOptions
    from ..solve import solve_to_accuracy

    d, s = f.discretization, f.solver
    with status("searching N...", quiet) as spinner:
        return solve_to_accuracy(
            problem, s.accuracy, s.replay_accuracy, d.scheme, d.retraction, d.rule, s.ipopt,
            s.multistart, *f.horizon.grids,
            progress=spinner.update if spinner is not None else silent,
            report=silent if quiet else lambda level: err.print(grid_line(level),
                                                                 highlight=False),
            jit=s.jit, backend=s.backend, max_seconds=s.max_seconds,
            options=SolverOptions(workers=s.workers, fatrop=dict(s.fatrop)))


def _solve_outputs(out_path: Optional[Path], plot_path: Optional[Path],
                   section: Any) -> tuple[Optional[Path], Optional[Path]]:
    """The solution and figure paths of `solve` (options first, then the file's ``output``
    section), checked before anything is built: ConfigError naming the option and the fix."""
    from ..solve.outputs import check_file

    target = picture = None
    if out_path is not None or section.file:
        target = check_file(out_path if out_path is not None else section.file,
                            "--out" if out_path is not None else "output.file")
    if plot_path is not None or section.plot:
        picture = check_file(plot_path if plot_path is not None else section.plot,
                             "--plot" if plot_path is not None else "output.plot",
                             "solution.png")
    if target is not None and picture is not None and target.resolve() == picture.resolve():
        raise ConfigError(f"--out and --plot are the same file {target}: the figure would "
                          "replace the solution; give two paths")
    return target, picture
