"""The ``ocgroupoid`` command line: solve YAML problem files.

Exit codes: 0 solved; 1 the solver failed (the solution file is still written, with
``success: false`` and IPOPT's status); 2 bad input (the message names the key, the line and
the fix, never a traceback); 3 a sweep could not write (a full disk); 130 Ctrl-C and 143
SIGTERM (a solve writes its best point so far, a sweep keeps its finished points).
"""

from __future__ import annotations

import os
import time
from contextlib import nullcontext
from pathlib import Path
from typing import Any, Optional

import typer
from rich.console import Console
from rich.table import Table

from ._startup import interrupt_exit_code, terminated
from .bench.commands import bench
from .errors import ConfigError, OcgError
from .mpc.command import mpc_command

app = typer.Typer(no_args_is_help=True, add_completion=False, pretty_exceptions_enable=False,
                  help="Optimal control on Lie groups and groupoids: solve YAML problem files.")
out = Console()
err = Console(stderr=True, soft_wrap=True)

app.add_typer(bench, name="bench")  # ocgroupoid bench work-precision | stability
app.command("mpc")(mpc_command)  # ocgroupoid mpc FILE --steps K: closed loop (ocgroupoid.mpc)
SET_HELP = "Override any key: KEY=VALUE, the value read as YAML (e.g. horizon.N=128)."
LONG_SOLVE = 10.0  # seconds: a solve estimated longer is announced with its estimate


def fail(message: str, code: int = 2) -> None:
    """Print an error (no traceback) and exit; the message is plain text (its brackets,
    such as ``[w, x, y, z]``, are not rich markup)."""
    from rich.markup import escape

    err.print(f"[bold red]error:[/] {escape(message)}", highlight=False, markup=True)
    raise typer.Exit(code)


def summary(sol: Any) -> Table:
    """The table printed after a solve."""
    d = sol.diagnostics
    disc = sol.discretization
    t = Table(title=f"{sol.problem}  (N={sol.N}, T={sol.T:g}, {disc.get('scheme', 'order2')}, "
                    f"{disc.get('retraction')}, rule {disc.get('rule')})", show_header=False)
    t.add_column(style="bold")
    t.add_column()
    t.add_row("status", f"[{'green' if sol.success else 'red'}]{sol.status}[/]"
              + ("" if sol.success or sol.status != "Solve_Succeeded" else " (not verified)"))
    t.add_row("cost", f"{sol.cost:.12g}")
    t.add_row("iterations", str(sol.iterations))
    if "T_range" in disc:
        lo, hi = disc["T_range"]
        t.add_row("final time (free)", f"{sol.T:.10g} in [{lo:g}, {hi:g}]"
                  + (f", {disc['steps']} steps" if disc.get("steps") == "adaptive" else ""))
    t.add_row("build time", f"{sol.build_seconds * 1e3:.1f} ms")
    t.add_row("solver time, this solution", f"{sol.solve_seconds * 1e3:.1f} ms ({sol.backend})")
    runs = [f"{sol.starts} starts" if sol.starts > 1 else "",
            "grids" if d.get("continuation") or "error_estimate" in d else "",
            "phases" if d.get("adaptive", {}).get("used") else ""]
    if sol.ipopt_seconds_total > sol.solve_seconds * (1 + 1e-9) or sol.starts > 1:
        t.add_row("solver time, every run", f"{sol.ipopt_seconds_total * 1e3:.1f} ms ("
                  + (", ".join(filter(None, runs)) or "retries") + ")")
    t.add_row("EL residual (max over nodes)", f"{d['euler_lagrange_residual_max']:.2e}"
              if "euler_lagrange_residual_max" in d else "none: the scheme is not variational")
    t.add_row("distance from manifold",
              ", ".join(f"{k} {v:.1e}" for k, v in d["manifold_distance"].items()))
    if d["final_residual"]:
        t.add_row("final residual", ", ".join(f"{k} {v:.1e}" for k, v in
                                              d["final_residual"].items()))
    if "bound_violation_max" in d:
        active = d["bounds_active"]
        t.add_row("bounds", f"max violation {d['bound_violation_max']:.1e}; active: " + (
            ", ".join(f"{k} ({', '.join(f'{s} at {n}' for s, n in v.items())} of "
                      f"{d['bound_points']} points)" for k, v in active.items()) or "none"))
    if d.get("conserved_drift"):
        t.add_row("conserved drift (max - min)", ", ".join(
            f"{k} {v:.2e}" for k, v in d["conserved_drift"].items()))
    rep = d.get("replay", {})
    if rep.get("available"):
        t.add_row("replay terminal error", ", ".join(f"{k} {v:.2e}" for k, v in
                                                     rep["terminal_error"].items()))
    elif rep.get("reason"):
        t.add_row("replay", rep["reason"])
    if "error_estimate" in d:
        e = d["error_estimate"]
        t.add_row("error estimate (cost)", f"{e['cost_relative']:.1e} relative ({e['cost']:.2e}"
                  f"), Richardson from N={e['N'][0]} and {e['N'][1]}, order {e['order']:.2g}")
    if "accuracy" in d:
        acc = d["accuracy"]
        t.add_row("N: auto", f"{acc['message']} ({acc['ipopt_seconds']:.2f} s in IPOPT)")
        if len(acc["schemes"]) > 1:
            t.add_row("schemes tried", ", ".join(
                f"{k} {'met' if v['met'] else v['stopped']} ({v['ipopt_seconds']:.2f} s IPOPT)"
                for k, v in acc["schemes"].items()))
    if len(sol.minima) > 1:
        where = " (of the starts, before the adaptive steps)" if \
            d.get("adaptive", {}).get("used") else ""
        t.add_row("local minima" + where, ", ".join(f"{m['cost']:.6g} ({m['label']})"
                                                    for m in sol.minima))
    if sol.hint:
        t.add_row("hint", sol.hint)
    return t


@app.command()
def solve(
    file: Path = typer.Argument(..., help="problem file (YAML)"),
    set_: list[str] = typer.Option([], "--set", help=SET_HELP),
    out_path: Optional[Path] = typer.Option(None, "--out", help="write the solution JSON here"),
    plot_path: Optional[Path] = typer.Option(None, "--plot", help="write a PNG plot here"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="print only errors"),
) -> None:
    """Build, solve and summarise a problem file; optionally write the solution JSON."""
    from . import files
    from .solve import compile as compile_problem

    try:
        cfg = files.load(file, set_)
        f = cfg.file
        target, picture = _solve_outputs(out_path, plot_path, f.output)
        problem = files.build(cfg)
        d = f.discretization
        est = files.estimate(cfg, problem)
        if est is not None and est.seconds > LONG_SOLVE and not quiet:
            err.print(f"N={f.horizon.N}: this solve takes {est}; solver.max_seconds = "
                      f"{f.solver.max_seconds:g}", highlight=False)
        t0 = time.perf_counter()
        if f.horizon.N == "auto":
            sol = _solve_to_accuracy(problem, f, quiet)
        else:
            with _status("building the NLP...", quiet):
                solver = compile_problem(problem, f.horizon.N, d.retraction, d.rule,
                                         f.solver.ipopt, d.scheme, d.steps, f.solver.jit,
                                         f.solver.backend, f.solver.max_seconds,
                                         bound_points=d.bound_points)
            with _status("solving...", quiet) as status:
                sol = solver.solve(multistart=f.solver.multistart,
                                   continuation=f.solver.continuation or None,
                                   progress=status.update if status is not None else _silent)
        if target is not None:
            sol.to_json(target)
        if picture is not None:
            from .plotting import plot as plot_figure
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
        err.print(f"[bold red]{_stopped_by()}:[/] the best point so far is "
                  + (f"in {target} " if target else "") + "with success: false")
        raise typer.Exit(interrupt_exit_code())
    if not sol.success:
        what = "not verified" if sol.status == "Solve_Succeeded" else f"solver failed: {sol.status}"
        if sol.diagnostics.get("accuracy", {}).get("met") is False:
            what = "accuracy not reached"
        err.print(f"[bold red]{what}:[/] {escape(sol.hint)}")
        raise typer.Exit(1)


def _solve_to_accuracy(problem: Any, f: Any, quiet: bool) -> Any:
    """``horizon.N: auto``: the grid search of :mod:`ocgroupoid.solve.auto`, one line per
    grid on stderr as it is done."""
    from .solve import solve_to_accuracy

    d, s = f.discretization, f.solver
    with _status("searching N...", quiet) as status:
        return solve_to_accuracy(
            problem, s.accuracy, s.replay_accuracy, d.scheme, d.retraction, d.rule, s.ipopt,
            s.multistart, *f.horizon.grids,
            progress=status.update if status is not None else _silent,
            report=_silent if quiet else lambda level: err.print(grid_line(level),
                                                                 highlight=False),
            jit=s.jit, backend=s.backend, max_seconds=s.max_seconds)


def grid_line(level: Any) -> str:
    """One grid of ``N: auto``: cost, error estimate, replay error, verdict and time."""
    est = "-" if level.estimate is None else f"{level.estimate:.1e} (order {level.order:.2g})"
    replay = "-" if level.replay_error is None else f"{level.replay_error:.1e}"
    verdict = "verified" if level.verified else level.status if \
        level.status != "Solve_Succeeded" else "not verified"
    return (f"{level.scheme} N={level.N}: cost {level.cost:.10g}, estimated error {est}, "
            f"replay error {replay}, {verdict}, {level.seconds:.2f} s"
            + (" — target met" if level.met else ""))


def _solve_outputs(out_path: Optional[Path], plot_path: Optional[Path],
                   section: Any) -> tuple[Optional[Path], Optional[Path]]:
    """The solution and figure paths of `solve` (options first, then the file's ``output``
    section), checked before anything is built: ConfigError naming the option and the fix."""
    from .solve.outputs import check_file

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


@app.command()
def check(
    file: Path = typer.Argument(..., help="problem file (YAML)"),
    set_: list[str] = typer.Option([], "--set", help=SET_HELP),
) -> None:
    """Validate a problem file and print its dimensions and boundary conditions, no solve.

    Exits 2 when the file is invalid or a boundary condition is redundant.
    """
    from . import files
    from .solve.auto import AUTO_SCHEMES
    from .solve.checks import check as run_check

    try:
        cfg = files.load(file, set_)
        f = cfg.file
        d = f.discretization
        problem = files.build(cfg)
        # N: auto is checked on its first grid, with the first scheme scheme: auto tries
        N = f.horizon.grids[0] if f.horizon.N == "auto" else f.horizon.N
        scheme = AUTO_SCHEMES[0] if d.scheme == "auto" else d.scheme
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
    from .lie.rn import Rn

    return any(not isinstance(f.group, Rn) for f in problem.groupoid.factors)


@app.command()
def plot(
    solution: Path = typer.Argument(..., help="solution JSON written by `solve --out`, or "
                                    "a sweep's folder (`sweep --out`)"),
    out_path: Path = typer.Option(..., "--out", help="PNG file to write"),
) -> None:
    """Plot a solution as `solve --plot` does (`og.plot`): every quantity with its unit, the
    attitude error to the target, x-y paths, bounds and targets. Given a sweep's folder
    (`sweep --out DIR`), plot cost and status against the swept keys."""
    import json

    from .plotting import plot as plot_figure
    from .solve.outputs import check_file
    from .solve.solution import Solution

    try:
        check_file(out_path, "--out", "figure.png")
    except OcgError as e:
        fail(str(e))
        return
    if solution.is_dir():
        from .sweep import plot_sweep
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


@app.command()
def view(
    solution: Path = typer.Argument(..., help="solution JSON written by `solve --out`"),
    out_path: Path = typer.Option(..., "--out", help="file to write: .html (a page that "
                                  "plays offline), .gif or .mp4 (needs ffmpeg)"),
    frames: Optional[int] = typer.Option(None, "--frames", min=2, help="samples of the "
                                         "trajectory (default: html 60 a second of the "
                                         "horizon, 200 to 600; gif/mp4 80)"),
) -> None:
    """A 3-D view of the body moving along a solution (`og.view`): a box with its axes and
    the path of its position (SO(3), SE(3), SE(2)), the plate-ball rolling on its plate, the
    heavy top on its pivot. The page plays, pauses and seeks; `PAGE.html#t=0.5` opens it
    standing at t = 0.5."""
    from .plotting import view as write_view

    try:
        written = write_view(solution, out_path, frames)
    except OcgError as e:
        fail(str(e))
        return
    out.print(f"view written to {written}")


@app.command("list")
def list_models() -> None:
    """Built-in models, discretisation schemes and the problem files shipped in problems/."""
    from .lie.retraction import RETRACTION_NAMES
    from .models import MODELS
    from .nlp.schemes import SCHEMES

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


CUSTOM_SUMMARY = ("your own model, written in the problem file: a definition section (groupoid "
                  "factors, Lagrangian or controls, cost); e.g. custom_rigid_body.yaml")


def problem_folders() -> list[Path]:
    """The folders of problem files `list` shows, from any working directory: ./problems,
    the problems/ of a source checkout holding this package, and the copy installed under
    PREFIX/share/ocgroupoid/problems (pyproject.toml's data-files)."""
    import sysconfig

    here = Path(__file__).resolve().parent
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


def _status(message: str, quiet: bool) -> Any:
    """A spinner on stderr with a message, or nothing in quiet mode."""
    return nullcontext() if quiet else err.status(message, spinner="dots")


def _silent(_: object) -> None:
    return None


@app.command("export-c")
def export_c_command(
    file: Path = typer.Argument(..., help="problem file (YAML)"),
    out_dir: Path = typer.Option(..., "--out", help="folder to write the C project into"),
    build: bool = typer.Option(False, "--build", help="run make right after exporting"),
    set_: list[str] = typer.Option([], "--set", help=SET_HELP),
    cflags: str = typer.Option("", "--cflags", help="extra CFLAGS for --build"),
    force: bool = typer.Option(False, "--force", help="write into --out even if it holds "
                               "files export-c did not write (they are overwritten)"),
    prefix: Optional[str] = typer.Option(None, "--prefix", help="start of every C name and "
                                         "file of the export (e.g. so3_; default ocg_): "
                                         "exports with different prefixes link into one "
                                         "program"),
) -> None:
    """Export the compiled problem as a C project (IPOPT via CasADi codegen): `make -C OUT`
    builds OUT/solve, which prints the solution JSON; OUT/README.md tells the rest. Needs a
    C compiler and make to build. OUT must be new, empty or an earlier export (--force)."""
    from . import files
    from .export import DEFAULT_PREFIX, claim_folder, export_c, make, positive_parameters

    try:
        cfg = files.load(file, set_)
        N = files.fixed_grid(cfg, "export-c")
        claim_folder(out_dir, force, "--out")
        f = cfg.file
        d = f.discretization
        with _status("exporting C code...", False):
            done = export_c(files.build(cfg), out_dir, N, d.retraction, d.rule,
                            f.solver.ipopt, scheme=d.scheme, steps=d.steps, force=force,
                            backend=f.solver.backend, max_seconds=f.solver.max_seconds,
                            positive=positive_parameters(cfg.spec.parameters),
                            prefix=prefix or DEFAULT_PREFIX)
        if build:
            with _status("building with make...", False):
                binary = make(done.folder, cflags)
    except OcgError as e:
        fail(str(e))
        return
    out.print(f"{done.problem} (N={done.N}: {done.n_x} variables, {done.n_p} parameters) "
              f"exported to {done.folder}")
    if build:
        out.print(f"built {binary}; run it (prints the solution JSON) or `{binary} PARAMS`")
    else:
        out.print(f"build with `make -C {done.folder}`; see {done.folder / 'README.md'}")
    if f.solver.multistart or f.solver.continuation:
        err.print("note: the C solver starts from the geodesic guess; multistart and "
                  "continuation of the problem file stay in Python", highlight=False)


@app.command()
def sweep(
    file: Path = typer.Argument(..., help="problem file (YAML)"),
    grid: list[str] = typer.Option([], "--grid", help="KEY=START:STOP:COUNT (linspace) or "
                                   "KEY=[v1, v2, ...] (YAML); several: the cartesian product"),
    random: list[str] = typer.Option([], "--random", help="KEY=normal(mu, sigma) or "
                                     "KEY=uniform(a, b), drawn --samples times"),
    samples: Optional[int] = typer.Option(None, "--samples", help="number of random draws"),
    seed: int = typer.Option(0, "--seed", help="seed of the random draws"),
    set_: list[str] = typer.Option([], "--set", help=SET_HELP),
    out_dir: Path = typer.Option(..., "--out", help="folder for the table (table.parquet), "
                                 "the points' records and their solutions; one sweep at a "
                                 "time"),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="tcp://HOST:PORT of a "
                                            "running Dask scheduler (default: a local cluster)"),
    workers: Optional[int] = typer.Option(None, "--workers", help="local worker processes "
                                          "(default: one per core)"),
    resume: bool = typer.Option(False, "--resume", help="finish the sweep in --out (same "
                                "grid) without redoing finished points; points whose worker "
                                "was lost or that raised an error are solved again"),
    retry_failed: bool = typer.Option(False, "--retry-failed", help="with --resume: solve "
                                      "again every point that did not succeed"),
    warm: str = typer.Option("fallback", "--warm", help="neighbour warm starts: fallback (when "
                             "the cold start fails), first, or off"),
    timeout: float = typer.Option(10.0, "--timeout", help="seconds --scheduler has to answer"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="print only errors"),
) -> None:
    """Solve a problem file at every point of a grid or random samples of --set overrides, on
    Dask; one row per point in OUT/table.parquet.

    Before the work starts it prints the number of points and the disk they take (about
    35 kB a point: a record and a solution), and once the first chunk is back the time the
    rest will take. Exit codes: 0 every point solved, 1 some failed (all are in the table),
    2 bad input (or another sweep running in OUT, or --resume of another grid), 3 a write
    failed (a full disk: the finished points and their table are kept; --resume finishes),
    130 interrupted (143 SIGTERM)."""
    from .errors import STORAGE_EXIT, StorageError
    from .solve.outputs import check_folder
    from .sweep import sweep as run_sweep
    from .sweep.progress import progress_bar, summary

    def report(line: str) -> None:
        if not quiet:
            err.print(line, highlight=False)

    try:
        check_folder(out_dir, "--out")
        with progress_bar(err, quiet) as bar:
            df = run_sweep(file, grid, random=random, samples=samples, seed=seed,
                           overrides=set_, out=out_dir, scheduler=scheduler, workers=workers,
                           resume=resume, retry_failed=retry_failed,
                           warm=warm, timeout=timeout,  # type: ignore[arg-type]
                           progress=bar, report=report)
    except StorageError as e:
        fail(str(e), STORAGE_EXIT)
        return
    except OcgError as e:
        fail(str(e))
        return
    except KeyboardInterrupt:
        fail(f"{_stopped_by()}; the finished points are kept: finish with --resume --out "
             f"{out_dir}", interrupt_exit_code())
        return
    if not quiet:
        out.print(summary(df) + f"\ntable written to {out_dir / 'table.parquet'}")
    if not df["success"].all():
        raise typer.Exit(1)


def _stopped_by() -> str:
    """How the command was stopped: ``interrupted`` (Ctrl-C) or ``terminated (SIGTERM)``."""
    return "terminated (SIGTERM)" if terminated() else "interrupted"


def main() -> None:
    """Entry point of the ``ocgroupoid`` command (Ctrl-C: one line, exit 130; SIGTERM is
    handled as Ctrl-C, exit 143)."""
    from ._startup import release

    release()  # from here on Ctrl-C (and SIGTERM) is a KeyboardInterrupt the commands handle
    try:
        app()
    except KeyboardInterrupt:
        err.print(_stopped_by(), highlight=False)
        raise SystemExit(interrupt_exit_code()) from None


if __name__ == "__main__":  # pragma: no cover
    main()
