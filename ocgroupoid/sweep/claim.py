"""Who may write into a sweep's folder: one running sweep, and only the sweep it holds.

A sweep claims its folder before it validates a point or starts a cluster:

1. it takes an exclusive lock on ``DIR/.sweep.lock`` (``flock``: held while the sweep runs,
   released by the system when the process ends, even by ``kill -9``); a second sweep into
   the folder meanwhile is refused;
2. under the lock it creates ``DIR/sweep.json`` exclusively (written in full to a temporary
   file, then linked into place: a reader never sees half of it) with the digest of what is
   swept (:func:`grid_digest`), or, when the folder holds a sweep already, checks that this
   is a ``--resume`` of the same grid and names what differs otherwise.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator

from ..errors import ConfigError

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: the exclusive manifest alone claims
    fcntl = None  # type: ignore[assignment]

LOCK = ".sweep.lock"
#: the manifest entries that define what is swept (their digest is the grid's)
GRID_KEYS = ("source", "keys", "grid", "random", "samples", "seed")


def grid_digest(manifest: dict[str, Any]) -> str:
    """The digest of what a manifest sweeps: the problem (file data and ``--set``, as
    :attr:`~ocgroupoid.sweep.source.Source.digest`), the axes, the draws and their seed."""
    text = json.dumps({k: manifest.get(k) for k in GRID_KEYS}, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def _values(values: list[Any]) -> str:
    shown = ", ".join(json.dumps(v) for v in values[:3])
    return f"{len(values)} value{'s' if len(values) != 1 else ''} ({shown}" + \
        (", ...)" if len(values) > 3 else ")")


def difference(old: dict[str, Any], new: dict[str, Any]) -> str:
    """What differs between the sweep in a folder (``old``) and this one (``new``), in words."""
    if old.get("source") != new.get("source"):
        if old.get("problem") != new.get("problem"):
            return f"the problem file is {new.get('problem')} here, {old.get('problem')} there"
        if old.get("overrides") != new.get("overrides"):
            return (f"--set is {' '.join(new.get('overrides') or []) or 'empty'} here, "
                    f"{' '.join(old.get('overrides') or []) or 'empty'} there")
        return f"{new.get('problem') or 'the problem'} has changed since that sweep started"
    out = []
    old_grid, new_grid = old.get("grid") or {}, new.get("grid") or {}
    for key in [*new_grid, *[k for k in old_grid if k not in new_grid]]:
        if key not in old_grid:
            out.append(f"--grid {key} is swept here, not there")
        elif key not in new_grid:
            out.append(f"--grid {key} is swept there, not here")
        elif old_grid[key] != new_grid[key]:
            out.append(f"--grid {key} has {_values(new_grid[key])} here, "
                       f"{_values(old_grid[key])} there")
    for key in ("random", "samples", "seed"):
        if old.get(key) != new.get(key):
            out.append(f"--{key} is {json.dumps(new.get(key))} here, "
                       f"{json.dumps(old.get(key))} there")
    if not out and old.get("keys") != new.get("keys"):
        out.append(f"the keys are swept in the order {', '.join(new.get('keys') or [])} here, "
                   f"{', '.join(old.get('keys') or [])} there")
    return "; ".join(out) or "the grid's digest differs"


def _write_exclusive(path: Path, text: str) -> bool:
    """Create ``path`` holding ``text`` unless it exists (False then): the text goes to a
    temporary file first and is linked into place, so the file is whole or absent."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.claim")
    try:
        with open(tmp, "w") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        try:
            os.link(tmp, path)
        except FileExistsError:
            return False
    finally:
        tmp.unlink(missing_ok=True)
    return True


@contextmanager
def _lock(root: Path) -> Iterator[None]:
    """Hold the folder's lock (module docstring) or refuse: another sweep runs there."""
    if fcntl is None:  # pragma: no cover
        yield
        return
    fd = os.open(root / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 200, 0).decode(errors="replace").strip() or "another process"
            raise ConfigError(f"{root}: another sweep is running in this folder ({holder}); "
                              "wait for it to finish (then add --resume to continue it), or "
                              "give another --out folder") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"pid {os.getpid()}, started {time.strftime('%Y-%m-%d %H:%M:%S')}"
                  .encode(), 0)
        yield
    finally:
        os.close(fd)  # releases the lock


@contextmanager
def claim(root: str | Path, manifest_path: str | Path, manifest: dict[str, Any],
          resume: bool) -> Iterator[dict[str, Any]]:
    """Claim ``root`` for the sweep ``manifest`` while the block runs (module docstring);
    yield the manifest in the folder (``manifest`` with its digest, or the one a resumed
    sweep wrote). ConfigError when another sweep runs there, when the folder holds a sweep
    and ``resume`` is off, or when it holds another grid. A new claim whose block raises
    ConfigError (the sweep was refused before it ran a point) is withdrawn."""
    root, path = Path(root), Path(manifest_path)
    created = not root.exists()
    root.mkdir(parents=True, exist_ok=True)
    new = {**manifest, "grid_hash": grid_digest(manifest)}
    with _lock(root):
        if not path.exists() and _write_exclusive(path, json.dumps(new, indent=1) + "\n"):
            try:
                yield new
            except ConfigError:  # refused before any point ran: leave no sweep behind
                path.unlink(missing_ok=True)
                (root / LOCK).unlink(missing_ok=True)
                if created and not any(root.iterdir()):
                    root.rmdir()
                raise
            return
        if not resume:
            raise ConfigError(f"{root} holds a sweep already: add --resume (resume=True) to "
                              "finish it without redoing finished points, or give another "
                              "--out folder")
        try:
            old = json.loads(path.read_text())
        except (OSError, ValueError) as err:
            raise ConfigError(f"{path}: not a sweep manifest ({err}); give another --out "
                              "folder") from None
        if old.get("grid_hash", grid_digest(old)) != new["grid_hash"]:
            raise ConfigError(f"--resume: {root} holds another sweep: {difference(old, new)}; "
                              "resume with the --grid, --random, --samples, --seed and --set "
                              "of the first run, or give another --out folder")
        yield old
