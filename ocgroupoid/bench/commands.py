"""``ocgroupoid bench``: the work-precision chart and the stability map of a problem file.

Registered on the main command line (``ocgroupoid.cli``) as the ``bench`` group; heavy
imports happen inside the commands. Exit codes as ``solve``: 0 done, 1 a reference did not
solve, 2 bad input (one line, no traceback), 130 interrupted (the finished rows are kept).
"""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Iterator, Optional

import typer

from ..console import err, fail, out, stopped_by

bench = typer.Typer(no_args_is_help=True, add_completion=False,
                    help="Benchmarks: our schemes against RK4 shooting baselines.")

SET_HELP = "Override any key of the file: KEY=VALUE, the value read as YAML."
OUT_HELP = ("results folder: rows and summary in OUT/{what}/NAME.jsonl|json, the chart in "
            "OUT/figures/{what}_NAME.png")


@contextmanager
def _failures(rows: Callable[[], Path]) -> Iterator[None]:
    """Errors as exit codes: a solver failure 1, bad input 2 (one line each), Ctrl-C 130
    (SIGTERM 143) naming where the finished ``rows()`` are kept."""
    from .._startup import interrupt_exit_code
    from ..errors import OcgError, SolverError

    try:
        yield
    except SolverError as e:
        fail(str(e), 1)
    except OcgError as e:
        fail(str(e))
    except KeyboardInterrupt:
        fail(f"{stopped_by()}; the finished rows are kept in {rows()}", interrupt_exit_code())


@bench.command("work-precision")
def work_precision_command(
    file: Path = typer.Argument(..., help="problem file (YAML)"),
    out_dir: Path = typer.Option(Path("results"), "--out",
                                 help=OUT_HELP.format(what="work_precision")),
    schemes: Optional[str] = typer.Option(None, "--schemes", help="comma-separated "
                                          "methods: a scheme, then optionally :RETRACTION, "
                                          "@BACKEND, +jit, +coarse (solved on N/4 first), "
                                          "e.g. order4@fatrop+jit+coarse (default order2, "
                                          "order4, order6, order2:exp, rk4_quat, "
                                          "rk4_matrix, rk4_euler)"),
    grids: Optional[str] = typer.Option(None, "--N", help="comma-separated N (default "
                                        "8,16,32,64,128)"),
    repeats: int = typer.Option(3, "--repeats", help="timed IPOPT runs per N (at least; "
                                "fast solves are repeated more, the median is kept)"),
    reference_N: int = typer.Option(256, "--reference-N", help="finest grid of the "
                                    "reference (a power of two >= 16)"),
    name: Optional[str] = typer.Option(None, "--name", help="name of the outputs (default "
                                       "the file's stem)"),
    set_: list[str] = typer.Option([], "--set", help=SET_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="print only errors"),
) -> None:
    """IPOPT time against cost and landing accuracy, every method on every N.

    Median IPOPT time, iterations, relative cost error against a reference and replay
    terminal error for every method and N: a JSONL row per solve as it goes, a summary JSON
    (with the time ratios at equal accuracy) and a log-log work-precision chart. Each run
    is held to the file's solver.max_seconds (e.g. --set solver.max_seconds=20 for a start
    that diverges slowly); an unsuccessful run is not repeated."""
    from ..errors import ConfigError
    from ..progress import progress_bar
    from ..solve.outputs import check_folder
    from .equal_accuracy import report
    from .methods import WORK_PRECISION, parse_grids, parse_methods
    from .workprecision import DEFAULT_NS, outputs, work_precision

    where = None
    with _failures(lambda: where.rows if where else out_dir):
        check_folder(out_dir, "--out")
        methods = parse_methods(schemes, WORK_PRECISION)
        Ns = parse_grids(grids, DEFAULT_NS)
        if repeats < 1:
            raise ConfigError(f"--repeats must be at least 1, got {repeats}")
        where = outputs(out_dir, name or file.stem)
        with progress_bar(err, quiet) as bar:
            summary, where = work_precision(file, set_, out_dir, methods, Ns, repeats,
                                            reference_N, name, bar)
    if not quiet:
        out.print(report(summary))
        out.print(f"rows {where.rows}, summary {where.summary}, chart {where.chart}")


@bench.command("stability")
def stability_command(
    file: Path = typer.Argument(..., help="problem file (YAML) with an SO(3) state"),
    out_dir: Path = typer.Option(Path("results"), "--out",
                                 help=OUT_HELP.format(what="stability")),
    schemes: Optional[str] = typer.Option(None, "--schemes", help="comma-separated "
                                          "methods: a scheme, then optionally :RETRACTION, "
                                          "@BACKEND, +jit, +coarse (default order2, order4, "
                                          "order6, order2:exp, order2:first_order and the "
                                          "three baselines)"),
    grids: Optional[str] = typer.Option(None, "--N", help="comma-separated N (default "
                                        "2,4,8,16,32,64)"),
    angles: Optional[str] = typer.Option(None, "--angles", help="comma-separated slew "
                                         "angles in rad (default 0.5,1,1.5,2,2.6,3,3.5)"),
    axis: str = typer.Option("0,1,0", "--axis", help="axis of the slews (body y: the pitch)"),
    state: str = typer.Option("R", "--state", help="the SO(3) state slewed (final.STATE)"),
    multistart: bool = typer.Option(False, "--multistart", help="solve with the file's "
                                    "multi-start (default: from the first geodesic guess)"),
    name: Optional[str] = typer.Option(None, "--name", help="name of the outputs (default "
                                       "the file's stem)"),
    set_: list[str] = typer.Option([], "--set", help=SET_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="print only errors"),
) -> None:
    """Where each method fails, over slew angles and grids: a map.

    Slews of every angle on every N, each cell converged, unverified, off group, off target,
    other minimum or failed, with the message a user gets; a JSONL row per solve as it goes,
    a summary JSON and a map (PNG)."""
    from ..progress import progress_bar
    from ..solve.outputs import check_folder
    from .methods import STABILITY, parse_floats, parse_grids, parse_methods
    from .stability import DEFAULT_ANGLES, DEFAULT_NS, outputs, stability

    where = None
    with _failures(lambda: where.rows if where else out_dir):
        check_folder(out_dir, "--out")
        methods = parse_methods(schemes, STABILITY)
        Ns = parse_grids(grids, DEFAULT_NS)
        slews = parse_floats(angles, DEFAULT_ANGLES, "--angles")
        direction = tuple(parse_floats(axis, (), "--axis"))
        where = outputs(out_dir, name or file.stem)
        with progress_bar(err, quiet) as bar:
            summary, where = stability(file, set_, out_dir, methods, Ns, slews, direction,
                                       state, multistart, name, bar)
    if not quiet:
        counts: dict[str, int] = {}
        for c in summary["cells"]:
            counts[c["outcome"]] = counts.get(c["outcome"], 0) + 1
        out.print(f"{len(summary['cells'])} solves: " + ", ".join(
            f"{n} {o}" for o, n in counts.items()))
        out.print(f"rows {where.rows}, summary {where.summary}, map {where.chart}")
