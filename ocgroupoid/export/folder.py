"""The folder of an export: new, empty, or an earlier export left as it was written.

What export_c wrote is recorded in :data:`MANIFEST` (file -> sha256): a folder holding it is
one export_c may overwrite; anything else in it, or a file edited since, is refused.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from ..errors import ExportError
from ..solve.outputs import check_folder

#: what export_c wrote (file -> the sha256 of every content accepted)
MANIFEST = ".ocgroupoid-export.json"


def digest(data: str | bytes) -> str:
    """The sha256 of a file's contents."""
    return hashlib.sha256(data.encode() if isinstance(data, str) else data).hexdigest()


def manifest(folder: Path) -> dict[str, list[str]] | None:
    """What an earlier export wrote in ``folder`` (file -> accepted digests), or None."""
    try:
        files = json.loads((folder / MANIFEST).read_text())["files"]
        return {str(k): [str(d) for d in v] for k, v in files.items()}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


def claim_folder(folder: str | Path, force: bool = False, what: str = "export folder") -> Path:
    """Check, before anything is compiled, that ``folder`` may receive an export: it is new,
    empty, or an earlier export whose files are unchanged (``MANIFEST`` records them).
    Anything else (a README.md, Makefile, main.c... that export_c did not write, or one that
    was edited since) is an ExportError unless ``force``. Returns the folder as a Path."""
    folder = check_folder(folder, what)
    if force or not folder.is_dir():
        return folder
    present = sorted(p.name for p in folder.iterdir() if p.name != MANIFEST)
    if not present and not (folder / MANIFEST).exists():
        return folder
    known = manifest(folder)
    if known is None:
        shown = ", ".join(present[:5]) + (", ..." if len(present) > 5 else "")
        raise ExportError(f"{what} {folder}: is not empty ({shown}) and was not written by "
                          "export-c; export into a new or empty folder, or pass --force "
                          "(force=True) to overwrite its files")
    for name in present:
        path = folder / name
        if name not in known:
            continue  # the user's own files and the build's products are left alone
        if not path.is_file() or digest(path.read_bytes()) not in known[name]:
            raise ExportError(f"{what} {folder}: {name} was changed since export-c wrote it; "
                              "move your edits "
                              "elsewhere (e.g. copy params.txt), or pass --force (force=True) "
                              "to overwrite it")
    return folder
