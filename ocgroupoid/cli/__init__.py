"""The ``ocgroupoid`` command line: solve YAML problem files.

Exit codes: 0 solved; 1 the solver failed (the solution file is still written, with
``success: false`` and IPOPT's status); 2 bad input (the message names the key, the line and
the fix, never a traceback); 3 a sweep could not write (a full disk); 130 Ctrl-C and 143
SIGTERM (a solve writes its best point so far, a sweep keeps its finished points).
"""

from __future__ import annotations

import typer

from .._startup import interrupt_exit_code
from ..bench.commands import bench
from ..console import err, stopped_by
from ..mpc.command import mpc_command
from . import check, export_c, listing, plot, solve, sweep, view

app = typer.Typer(no_args_is_help=True, add_completion=False, pretty_exceptions_enable=False,
                  help="Optimal control on Lie groups and groupoids: solve YAML problem files.")

# one module a command; the order here is the order of `ocgroupoid --help`
app.add_typer(bench, name="bench")  # ocgroupoid bench work-precision | stability
app.command("mpc")(mpc_command)  # ocgroupoid mpc FILE --steps K: closed loop (ocgroupoid.mpc)
app.command()(solve.solve)
app.command()(check.check)
app.command()(plot.plot)
app.command()(view.view)
app.command("list")(listing.list_models)
app.command("export-c")(export_c.export_c_command)
app.command()(sweep.sweep)


def main() -> None:
    """Entry point of the ``ocgroupoid`` command (Ctrl-C: one line, exit 130; SIGTERM is
    handled as Ctrl-C, exit 143)."""
    from .._startup import release

    release()  # from here on Ctrl-C (and SIGTERM) is a KeyboardInterrupt the commands handle
    try:
        app()
    except KeyboardInterrupt:
        err.print(stopped_by(), highlight=False)
        raise SystemExit(interrupt_exit_code()) from None
