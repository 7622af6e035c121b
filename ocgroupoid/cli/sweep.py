"""``ocgroupoid sweep FILE``: a problem file solved at every point of a grid or of random
samples, on Dask."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from .._startup import interrupt_exit_code
from ..console import SET_HELP, err, fail, out, stopped_by
from ..errors import OcgError


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
    from ..errors import STORAGE_EXIT, StorageError
    from ..solve.outputs import check_folder
    from ..sweep import sweep as run_sweep
    from ..sweep.progress import progress_bar, summary

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
        fail(f"{stopped_by()}; the finished points are kept: finish with --resume --out "
             f"{out_dir}", interrupt_exit_code())
        return
    if not quiet:
        out.print(summary(df) + f"\ntable written to {out_dir / 'table.parquet'}")
    if not df["success"].all():
        raise typer.Exit(1)
