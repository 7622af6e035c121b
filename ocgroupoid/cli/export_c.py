"""``ocgroupoid export-c FILE --out DIR``: the compiled problem as a C project."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ..console import SET_HELP, err, fail, out, status
from ..errors import OcgError


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
    mpc: Optional[bool] = typer.Option(None, "--mpc/--no-mpc", help="the closed loop in C "
                                       "(OUT/mpc); default: written when the problem has "
                                       "one (a fixed T, second-order dynamics)"),
) -> None:
    """Export the compiled problem as a C project (IPOPT via CasADi codegen): `make -C OUT`
    builds OUT/solve, which prints the solution JSON; OUT/README.md tells the rest. Needs a
    C compiler and make to build. OUT must be new, empty or an earlier export (--force)."""
    from .. import files
    from ..export import DEFAULT_PREFIX, claim_folder, export_c, make, positive_parameters

    try:
        cfg = files.load(file, set_)
        files.fixed_grid(cfg, "export-c")  # one grid: N: auto is refused with the fix
        claim_folder(out_dir, force, "--out")
        with status("exporting C code...", False):
            done = export_c(files.build(cfg), out_dir, force=force,
                            positive=positive_parameters(cfg.spec.parameters),
                            prefix=prefix or DEFAULT_PREFIX, method=files.method(cfg),
                            options=files.options(cfg), mpc=mpc)
        if build:
            with status("building with make...", False):
                binary = make(done.folder, cflags)
                if done.mpc is not None:
                    make(done.folder, cflags, "mpc")
    except OcgError as e:
        fail(str(e))
        return
    out.print(f"{done.problem} (N={done.N}: {done.n_x} variables, {done.n_p} parameters) "
              f"exported to {done.folder}")
    if build:
        out.print(f"built {binary}; run it (prints the solution JSON) or `{binary} PARAMS`")
    else:
        out.print(f"build with `make -C {done.folder}`; see {done.folder / 'README.md'}")
    if cfg.file.solver.multistart or cfg.file.solver.continuation:
        err.print("note: the C solver starts from the geodesic guess; multistart and "
                  "continuation of the problem file stay in Python", highlight=False)
