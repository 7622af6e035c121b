"""What every command of the ``ocgroupoid`` command line shares (``cli``, and the ``bench``
and ``mpc`` commands registered on it): the two consoles, the one-line failure, the spinner
and the word for how a run was stopped."""

from __future__ import annotations

from contextlib import nullcontext
from typing import Any

import typer
from rich.console import Console

from ._startup import terminated

out = Console()
err = Console(stderr=True, soft_wrap=True)

SET_HELP = "Override any key: KEY=VALUE, the value read as YAML (e.g. horizon.N=128)."


def fail(message: str, code: int = 2) -> None:
    """Print an error (no traceback) and exit; the message is plain text (its brackets,
    such as ``[w, x, y, z]``, are not rich markup)."""
    from rich.markup import escape

    err.print(f"[bold red]error:[/] {escape(message)}", highlight=False, markup=True)
    raise typer.Exit(code)


def status(message: str, quiet: bool) -> Any:
    """A spinner on stderr with a message, or nothing in quiet mode."""
    return nullcontext() if quiet else err.status(message, spinner="dots")


def silent(_: object) -> None:
    """A progress or report callback that shows nothing (quiet mode)."""
    return None


def stopped_by() -> str:
    """How the command was stopped: ``interrupted`` (Ctrl-C) or ``terminated (SIGTERM)``."""
    return "terminated (SIGTERM)" if terminated() else "interrupted"
