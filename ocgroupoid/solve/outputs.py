"""Where results go: output paths checked before any work, files written atomically.

:func:`check_file` and :func:`check_folder` are called by every command that writes (``solve
--out/--plot``, ``sweep --out``, ``export-c --out``) before it builds or solves anything: a
path that cannot be written is a :class:`~ocgroupoid.errors.ConfigError` naming the option
and the fix, not a traceback after a long solve.

:func:`write_atomic` writes through a temporary file ``.NAME.PID.XXXXXXXX`` in the target's
folder and an atomic rename: a reader sees the old file or the new one, never half of one.
The new file gets the mode a plain ``open(path, "w")`` would give it (the umask's, or the
mode of the file it replaces); temporary files of this naming left by a killed writer (its
process is gone) are removed by the next write to the same path.
"""

from __future__ import annotations

import os
import re
import stat
import tempfile
import threading
from pathlib import Path

from ..errors import ConfigError

_UMASK_LOCK = threading.Lock()


def _nearest_existing(path: Path) -> Path:
    """``path`` or its closest ancestor that exists (``.`` for a relative path)."""
    while not os.path.lexists(path) and path != path.parent:
        path = path.parent
    return path


def _probe(folder: Path, what: str, path: Path) -> None:
    """A file can be created in ``folder`` (tried, then removed: ``os.access`` says yes to
    root on read-only file systems and to /proc)."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=".ocgroupoid-probe.", dir=folder)
    except OSError as e:
        raise ConfigError(f"{what} {path}: cannot write in the folder {folder} "
                          f"({e.strerror or e}); choose a folder you can write to") from None
    os.close(fd)
    os.unlink(tmp)


def _check_parent(path: Path, what: str) -> None:
    """Every existing ancestor of ``path`` is a folder, and the nearest one is writable (the
    missing ones are created when the file is written)."""
    base = _nearest_existing(path.parent)
    if not base.is_dir():
        raise ConfigError(f"{what} {path}: {base} is a file, not a folder; choose a path "
                          "whose folders are folders")
    _probe(base, what, path)


def check_file(path: str | Path, what: str = "output", example: str = "solution.json") -> Path:
    """``path`` as a file that can be written: not empty, not a folder, not a device or a
    pipe, in a folder that exists or can be made and that can be written. Returns the Path;
    raises ConfigError naming ``what`` (e.g. ``--out``) and the fix."""
    if str(path).strip() == "":
        raise ConfigError(f"{what} is empty; give a file path, e.g. {example}")
    p = Path(path)
    if p == Path("."):  # also what an empty argument becomes on the way to a Path
        raise ConfigError(f"{what} is empty (or '.'); give a file path, e.g. {example}")
    if p.is_dir():
        raise ConfigError(f"{what} {p}: is a folder; give a file path, e.g. {p / example}")
    if os.path.lexists(p) and not (p.is_file() or p.is_symlink()):
        raise ConfigError(f"{what} {p}: exists and is not a regular file; give a file path, "
                          f"e.g. {example}")
    _check_parent(p, what)
    return p


def check_folder(path: str | Path, what: str = "output folder") -> Path:
    """``path`` as a folder that can be written: a folder, or a path where one can be made.
    Returns the Path; raises ConfigError naming ``what`` and the fix."""
    if str(path).strip() == "":
        raise ConfigError(f"{what} is empty; give a folder, e.g. results")
    p = Path(path)
    if os.path.lexists(p) and not p.is_dir():
        raise ConfigError(f"{what} {p}: is a file, not a folder; give a new or empty folder")
    if p.is_dir():
        _probe(p, what, p)
    else:
        _check_parent(p, what)
    return p


# ------------------------------------------------------------------ atomic writes


def _umask() -> int:
    """The process umask, without changing it where /proc says it (Linux)."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    with _UMASK_LOCK:  # set and restore: the only portable way to read it
        mask = os.umask(0o22)
        os.umask(mask)
    return mask


def _new_mode(path: Path) -> int:
    """The mode ``open(path, "w")`` would leave: the replaced file's, or 0o666 & ~umask."""
    try:
        st = os.stat(path)
        if stat.S_ISREG(st.st_mode):
            return stat.S_IMODE(st.st_mode)
    except OSError:
        pass
    return 0o666 & ~_umask()


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True  # another thread of this process may be writing the same path
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, OSError):
        return True  # someone else's process (or unknowable): leave its file alone
    return True


def _temp_pattern(name: str) -> re.Pattern[str]:
    """``.NAME.PID.XXXXXXXX`` (this version) or ``.NAME.XXXXXXXX`` (before: no PID), the
    random part as :func:`tempfile.mkstemp` draws it."""
    return re.compile(r"\." + re.escape(name[:200]) + r"\.(?:(\d+)\.)?[a-z0-9_]{8}")


def remove_stale_temporaries(path: str | Path) -> list[Path]:
    """Remove the temporary files of :func:`write_atomic` for ``path`` whose writer is gone
    (killed mid-write); the removed paths."""
    path = Path(path)
    pattern = _temp_pattern(path.name)
    removed: list[Path] = []
    try:
        entries = list(os.scandir(path.parent))
    except OSError:
        return removed
    for entry in entries:
        m = pattern.fullmatch(entry.name)
        if m is None or not entry.is_file(follow_symlinks=False):
            continue
        if m.group(1) is not None and _alive(int(m.group(1))):
            continue
        try:
            os.unlink(entry.path)
            removed.append(Path(entry.path))
        except OSError:
            pass  # removed by another writer meanwhile, or not ours to remove
    return removed


def _sync_folder(folder: Path) -> None:
    """Make the rename durable (best effort: not every system opens folders)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def write_atomic(path: str | Path, data: bytes | str) -> None:
    """Write a file via a temporary file in the same folder and an atomic rename.

    An interrupted write leaves the previous file untouched, never a half-written one; the
    file gets the umask's mode (or keeps the mode of the file it replaces); temporary files
    that killed writers left for this path are removed first.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    raw = data.encode() if isinstance(data, str) else data
    remove_stale_temporaries(path)
    mode = _new_mode(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name[:200]}.{os.getpid()}.", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(raw)
            fh.flush()
            if hasattr(os, "fchmod"):
                os.fchmod(fh.fileno(), mode)
            else:  # pragma: no cover - Windows
                os.chmod(tmp, mode)
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    _sync_folder(path.parent)


__all__ = ["check_file", "check_folder", "write_atomic", "remove_stale_temporaries"]
