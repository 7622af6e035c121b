"""``ocgroupoid view``: a 3-D view of the body moving along a solution."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from ..console import fail, out
from ..errors import OcgError


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
    from ..plotting import view as write_view

    try:
        written = write_view(solution, out_path, frames)
    except OcgError as e:
        fail(str(e))
        return
    out.print(f"view written to {written}")
