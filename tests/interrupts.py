"""Ctrl-C in a test: SIGINT to this process after a delay, from a timer thread."""

from __future__ import annotations

import os
import signal
import threading
from contextlib import contextmanager
from typing import Iterator


@contextmanager
def sigint_after(seconds: float) -> Iterator[None]:
    """SIGINT to this process ``seconds`` after entering (as a user's Ctrl-C), cancelled if
    the block ends first."""
    pid = os.getpid()
    timer = threading.Timer(seconds, lambda: os.kill(pid, signal.SIGINT))
    timer.start()
    try:
        yield
    finally:
        timer.cancel()
