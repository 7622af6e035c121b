"""The 3-D view of a Solution: the body moving along the solution (:mod:`.scene`), written as
a self-contained HTML page, a GIF or an MP4 (``ocgroupoid view SOLUTION.json --out FILE``).

The page is the template ``view.html`` (shipped with the package) with the scene's frames
inlined as JSON: a canvas renderer of ~250 lines, no library, nothing loaded from the network.
It plays, pauses, seeks with a slider, turns with the mouse, and stands still at the time the
URL names (``view.html#t=0.5`` or ``?t=0.5``), as a headless browser needs for screenshots.
"""

from __future__ import annotations

import html
import json
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigError
from ..solve.outputs import check_file
from ..solve.solution import Solution, write_atomic
from .scene import Scene, scene

#: what ``view`` writes, by the extension of its path
FORMATS = {".html": "html", ".htm": "html", ".gif": "gif", ".mp4": "mp4"}
DIGITS = 5  # significant digits of the frames in the page (1e-5 of the scene's size)


def view(solution: Solution | str | Path, path: str | Path, frames: int | None = None,
         fps: int | None = None) -> Path:
    """Write the 3-D view of ``solution`` (a Solution, or the path of a solution file) to
    ``path``, in the format its extension names:

    - ``.html``: a page that plays the motion (``frames`` samples of the trajectory, by
      default 60 a second of the horizon, 200 to 600), opened offline;
    - ``.gif``: an animation of ``frames`` images (default 80) at ``fps`` a second
      (default 20), by matplotlib's PillowWriter;
    - ``.mp4``: the same by matplotlib's FFMpegWriter (needs ``ffmpeg`` on PATH:
      :class:`~ocgroupoid.errors.DependencyError` otherwise).

    Returns the path written. ConfigError for another extension, a path that cannot be
    written, an unreadable solution file, or a solution with no body the view knows (see
    :func:`~ocgroupoid.plotting.scene.scene`)."""
    kind = FORMATS.get(Path(path).suffix.lower())
    if kind is None:
        raise ConfigError(f"{path}: cannot write a view as {Path(path).suffix or 'no extension'}"
                          f"; give a file ending in {', '.join(FORMATS)}")
    target = check_file(path, "view", f"view{Path(path).suffix}")
    sol = solution if isinstance(solution, Solution) else read_solution(solution)
    if kind == "html":
        write_atomic(target, page(scene(sol, frames)))
    else:
        from .movie import movie
        movie(scene(sol, frames or 80), target, kind, fps or 20, dense=scene(sol))
    return target


def read_solution(path: str | Path) -> Solution:
    """A Solution read from its file; ConfigError (one line with the fix) when the file is
    missing or is not a solution file."""
    p = Path(path)
    if not p.is_file():
        raise ConfigError(f"{p}: no such file; give the JSON written by `ocgroupoid solve "
                          "--out`")
    try:
        return Solution.from_json(p)
    except (json.JSONDecodeError, KeyError, TypeError, ValueError, UnicodeDecodeError,
            AttributeError, IndexError) as e:
        raise ConfigError(f"{p}: not a solution file ({type(e).__name__}: {e}); give the "
                          "JSON written by `ocgroupoid solve --out`") from None


def page(sc: Scene) -> str:
    """The HTML page of a Scene: the template with the scene's data inlined."""
    template = resources.files(__package__).joinpath("view.html").read_text(encoding="utf-8")
    data = json.dumps(scene_data(sc), separators=(",", ":"), allow_nan=False)
    data = data.replace("</", "<\\/")  # never closes the script element it sits in
    return template.replace("__TITLE__", html.escape(sc.title)).replace("__SCENE__", data)


def scene_data(sc: Scene) -> dict[str, Any]:
    """What the page draws, as JSON-ready lists: frames (``t``, ``R`` as 9 numbers row by
    row, ``p``), the traced paths, the body's shape and the scene's bounds."""
    lo, hi = sc.bounds()
    size = float(np.max(hi - lo)) or 1.0
    decimals = max(DIGITS - int(np.floor(np.log10(size))), 0)

    def r(a: Any) -> Any:
        return np.round(np.asarray(a, dtype=float), decimals).tolist()

    n = sc.t.size
    plate = None
    if sc.plate_angle is not None:
        plate = {"angle": np.round(sc.plate_angle, 6).tolist(), "half": sc.plate_half()}
    return {
        "kind": sc.kind, "title": sc.title, "unit": sc.time_unit,
        "t": np.round(sc.t, 9).tolist(), "R": np.round(sc.R.reshape(n, 9), 6).tolist(),
        "p": r(sc.p), "paths": [r(q) for q in sc.paths()],
        "traces": [{"label": tr.label, "color": tr.color, "body": list(tr.body),
                    "space": list(tr.space)} for tr in sc.traces],
        "shape": sc.shape, "size": list(sc.size), "centre": list(sc.centre),
        "axis": sc.axis_length, "pivot": sc.pivot, "plate": plate,
        "bounds": [r(lo), r(hi)], "elevation": 55 if sc.kind == "se2" else 25,
    }
