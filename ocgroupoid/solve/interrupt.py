"""Ctrl-C during a solve: finish cleanly with the best result so far.

While :func:`interruptible` is active (in the main thread), SIGINT only sets
:attr:`Interrupt.requested`; IPOPT's iteration callback sees it and stops at the end of its
iteration (status ``User_Requested_Stop``), the remaining starts are skipped, and the solver
returns the best point so far with ``status: interrupted`` and ``success: false`` — the CLI
writes it and exits 130. A second Ctrl-C raises KeyboardInterrupt at once. Outside the
main thread (a Dask worker) signals cannot be caught and nothing changes.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager
from types import FrameType
from typing import Any, Iterator


class Interrupt:
    """Whether Ctrl-C was pressed during the solve."""

    def __init__(self) -> None:
        self.requested = False

    def __call__(self, signum: int, frame: FrameType | None) -> Any:
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True


@contextmanager
def interruptible() -> Iterator[Interrupt]:
    """SIGINT sets the flag of the yielded :class:`Interrupt` (module docstring)."""
    flag = Interrupt()
    if threading.current_thread() is not threading.main_thread():
        yield flag
        return
    previous = signal.signal(signal.SIGINT, flag)
    try:
        yield flag
    finally:
        signal.signal(signal.SIGINT, previous)
