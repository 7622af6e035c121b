"""Ctrl-C while the command line starts (importing CasADi, NumPy, ... takes a second): one
line on stderr and exit code 130, not a traceback.

``import ocgroupoid`` imports this module first, which calls :func:`guard`; it acts only
when the process is the ``ocgroupoid`` command or ``python -m ocgroupoid`` (a library import
keeps Python's KeyboardInterrupt). :func:`release` (the CLI's ``main``) restores the default
handler, so a Ctrl-C during a solve is a KeyboardInterrupt the command handles.
"""

from __future__ import annotations

import os
import signal
import sys
from types import FrameType


def started_as_cli() -> bool:
    """Whether this process runs the command line: the ``ocgroupoid`` script, or ``python -m
    ocgroupoid`` while the package is being imported (``sys.argv[0]`` is then ``-m``)."""
    argv0 = os.path.basename(sys.argv[0]) if sys.argv else ""
    if argv0 in ("ocgroupoid", "ocgroupoid.exe"):
        return True
    orig = list(getattr(sys, "orig_argv", []))
    return argv0 == "-m" and ("-mocgroupoid" in orig or any(
        a == "-m" and b == "ocgroupoid" for a, b in zip(orig, orig[1:])))


def _interrupted(signum: int, frame: FrameType | None) -> None:
    sys.stderr.write("ocgroupoid: interrupted while starting\n")
    sys.stderr.flush()
    raise SystemExit(130)


def guard() -> None:
    """Turn Ctrl-C into one line and exit 130 until :func:`release` (command line only)."""
    try:
        if started_as_cli() and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            signal.signal(signal.SIGINT, _interrupted)
    except ValueError:  # not the main thread: leave signals alone
        pass


def release() -> None:
    """Back to Python's KeyboardInterrupt (if :func:`guard` changed the handler)."""
    try:
        if signal.getsignal(signal.SIGINT) is _interrupted:
            signal.signal(signal.SIGINT, signal.default_int_handler)
    except ValueError:
        pass


guard()
