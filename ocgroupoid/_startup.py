"""Ctrl-C (or SIGTERM) while the command line starts (importing CasADi, NumPy, ... takes a
second): one line on stderr and exit code 130 (143), not a traceback.

``import ocgroupoid`` imports this module first, which calls :func:`guard`; it acts only
when the process is the ``ocgroupoid`` command or ``python -m ocgroupoid`` (a library import
keeps Python's KeyboardInterrupt). :func:`release` (the CLI's ``main``) restores the default
handler, so a Ctrl-C during a solve is a KeyboardInterrupt the command handles, and from then
on SIGTERM is handled as Ctrl-C is (:func:`terminated` tells them apart, for the exit code
128 + 15).
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


_terminated = False


def _interrupted(signum: int, frame: FrameType | None) -> None:
    what = "terminated" if signum == signal.SIGTERM else "interrupted"
    sys.stderr.write(f"ocgroupoid: {what} while starting\n")
    sys.stderr.flush()
    raise SystemExit(128 + signum)


def _terminate(signum: int, frame: FrameType | None) -> None:
    """SIGTERM: whatever Ctrl-C does now (stop a solve at its next iteration with the best
    point so far, or a KeyboardInterrupt), remembered for the exit code."""
    global _terminated
    _terminated = True
    handler = signal.getsignal(signal.SIGINT)
    if not callable(handler):
        raise KeyboardInterrupt
    handler(signal.SIGINT, frame)


def terminated() -> bool:
    """Whether SIGTERM (rather than Ctrl-C) stopped the command."""
    return _terminated


def interrupt_exit_code() -> int:
    """The exit code of a command stopped by Ctrl-C (130) or SIGTERM (143)."""
    return 128 + (signal.SIGTERM if _terminated else signal.SIGINT)


def guard() -> None:
    """Turn Ctrl-C and SIGTERM into one line and exit 130 (143) until :func:`release`
    (command line only)."""
    try:
        if started_as_cli() and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            signal.signal(signal.SIGINT, _interrupted)
            if signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
                signal.signal(signal.SIGTERM, _interrupted)
    except ValueError:  # not the main thread: leave signals alone
        pass


def release() -> None:
    """Back to Python's KeyboardInterrupt (if :func:`guard` changed the handler); SIGTERM
    from now on acts as Ctrl-C (:func:`_terminate`)."""
    try:
        if signal.getsignal(signal.SIGINT) is _interrupted:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        if signal.getsignal(signal.SIGTERM) in (_interrupted, signal.SIG_DFL):
            signal.signal(signal.SIGTERM, _terminate)
    except ValueError:
        pass


guard()
