"""Work that cannot hang the process: a forked helper, stopped at a deadline or on NaN.

fatrop (the build CasADi ships) has no time limit and no iteration callback, and it carries
on when a function it evaluates fails or returns NaN; its inertia correction then loops
without bound when the KKT matrix stays singular (``plate_ball.yaml`` with the first-order
retraction at N = 16: the "long way round" start ran for more than 600 s). Through fatrop's
own interface on Linux its driver leaves such a loop itself (``fatrop_guard.c``); elsewhere,
and for CasADi's fatrop ``nlpsol``, :class:`Isolated` runs the work in a helper process
forked from this one, which holds the same compiled objects: forked at the first call, it
serves every later one. A call costs the way there and back: 0.26 ms with an
empty task, 0.6-0.9 ms around a fatrop solve of so3 at N = 32 and 128 (2-core virtual
machine; the wait itself costs, not the data).
The caller waits for the answer until its deadline, reads what the helper prints on stderr
(counting CasADi's "NaN detected" warnings, passing anything else on), and kills the helper
past the deadline, after :data:`NAN_LIMIT` NaN evaluations, or when ``stop()`` says so
(Ctrl-C); the next call forks a new helper. Where no helper can be forked (Windows) the
work runs in-process, unguarded. A process forked from this one (a worker of a parallel
multi-start, :mod:`~ocgroupoid.solve.parallel`) leaves this process's helpers alone: its
copies forget them (:func:`_forget_helpers`) and fork their own on their first call.
"""

from __future__ import annotations

import os
import pickle
import select
import signal
import struct
import sys
import threading
import time
import warnings
import weakref
from dataclasses import dataclass
from typing import Any, Callable

#: NaN evaluations after which a solve is stopped: a line search that meets NaN backs off,
#: one that meets it this often is stuck at the edge of the functions' domain
NAN_LIMIT = 20
NAN_MARK = b"NaN detected"
_HEADER = struct.Struct("!Q")
POLL = 0.05  # seconds between two looks at the deadline and at stop()


@dataclass(frozen=True)
class Stopped:
    """Why a call gave no answer: ``time``, ``nan``, ``stop`` or ``died`` (with detail)."""

    reason: str
    detail: str = ""


def _send(fd: int, obj: Any) -> None:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    view = memoryview(_HEADER.pack(len(data)) + data)
    while view:
        view = view[os.write(fd, view):]


def _read_exact(fd: int, n: int) -> bytes | None:
    chunks = []
    while n:
        chunk = os.read(fd, min(n, 1 << 20))
        if not chunk:
            return None
        chunks.append(chunk)
        n -= len(chunk)
    return b"".join(chunks)


def _serve(work: Callable[[Any], Any], requests: int, answers: int, errors: int) -> None:
    """The helper's loop: answer each request with ``("ok", work(request))`` or the error;
    exit when the requests pipe closes (the caller is gone). Never returns."""
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the caller's to handle
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        null = os.open(os.devnull, os.O_RDWR)
        os.dup2(null, 0)
        os.dup2(null, 1)
        os.dup2(errors, 2)
        keep = {0, 1, 2, requests, answers}
        for fd in _open_fds():
            if fd not in keep:
                try:
                    os.close(fd)
                except OSError:
                    pass
        # Python's own streams write to descriptors 1 and 2 (a caller may have redirected
        # them elsewhere, to descriptors closed above)
        sys.stdout = open(1, "w", buffering=1, closefd=False)
        sys.stderr = open(2, "w", buffering=1, closefd=False)
        while True:
            header = _read_exact(requests, _HEADER.size)
            if header is None:
                break
            body = _read_exact(requests, _HEADER.unpack(header)[0])
            if body is None:
                break
            try:
                answer: Any = ("ok", work(pickle.loads(body)))
            except Exception as err:  # noqa: BLE001  (sent to the caller, which raises it)
                answer = ("error", f"{type(err).__name__}: {err}")
            _send(answers, answer)
    finally:
        os._exit(0)


def _open_fds() -> list[int]:
    try:
        return [int(name) for name in os.listdir("/proc/self/fd")]
    except OSError:
        return list(range(3, 1024))


def _kill(pid: int, *fds: int) -> None:
    """End a helper and close the caller's ends of its pipes."""
    for fd in fds:
        try:
            os.close(fd)
        except OSError:
            pass
    try:
        os.kill(pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    try:
        os.waitpid(pid, 0)
    except ChildProcessError:
        pass


#: every Isolated of this process, for :func:`_forget_helpers`
_INSTANCES: weakref.WeakSet[Isolated] = weakref.WeakSet()


def _forget_helpers() -> None:
    """In a child just forked: every Isolated copy drops the parent's helper (closes its
    copies of the pipes, never kills it) and forks its own on its next call."""
    for isolated in list(_INSTANCES):
        if isolated._finalizer is not None:
            isolated._finalizer.detach()
            isolated._finalizer = None
        if isolated.pid:  # the pipes are open while a helper runs (close() ends both)
            for fd in isolated.fds:
                try:
                    os.close(fd)
                except OSError:
                    pass
        isolated.pid, isolated.fds = 0, (-1, -1, -1)


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_helpers)


class Isolated:
    """``work(request)`` in a helper process (module docstring)."""

    def __init__(self, work: Callable[[Any], Any]) -> None:
        _INSTANCES.add(self)
        self.work = work
        self.pid = 0
        self.fds = (-1, -1, -1)  # the caller's ends: requests, answers, the helper's stderr
        self._lock = threading.Lock()  # one call at a time through the pipes
        self._finalizer: weakref.finalize | None = None
        self.nans = 0  # NaN evaluations of the last call
        self._pending = b""  # the helper's last line on stderr, not yet complete

    def _start(self) -> None:
        requests_r, requests_w = os.pipe()
        answers_r, answers_w = os.pipe()
        errors_r, errors_w = os.pipe()
        sys.stdout.flush()
        sys.stderr.flush()
        try:
            with warnings.catch_warnings():  # a multi-threaded caller (a Dask worker): the
                warnings.simplefilter("ignore", DeprecationWarning)  # helper has one thread
                pid = os.fork()
        except BaseException:
            for fd in (requests_r, requests_w, answers_r, answers_w, errors_r, errors_w):
                os.close(fd)
            raise
        if pid == 0:
            _serve(self.work, requests_r, answers_w, errors_w)
        for fd in (requests_r, answers_w, errors_w):
            os.close(fd)
        self.pid, self.fds = pid, (requests_w, answers_r, errors_r)
        self._finalizer = weakref.finalize(self, _kill, pid, *self.fds)

    def close(self) -> None:
        """End the helper (the next call forks a new one)."""
        if self._finalizer is not None:
            self._finalizer()
            self._finalizer = None
        self.pid = 0

    def call(self, request: Any, seconds: float, stop: Callable[[], bool] = lambda: False
             ) -> Any:
        """``work(request)``, or :class:`Stopped` when it did not answer within ``seconds``,
        evaluated NaN :data:`NAN_LIMIT` times, ``stop()`` became true, or the helper died.
        An exception of ``work`` is raised here as RuntimeError. Where no helper can be
        forked (no ``os.fork``, or the system refuses one), the work runs here, unguarded."""
        with self._lock:
            self.nans = 0
            if not self.pid:
                try:
                    self._start()
                except (AttributeError, OSError):  # Windows, or no process to spare
                    return self.work(request)
            return self._call(request, seconds, stop)

    def _call(self, request: Any, seconds: float, stop: Callable[[], bool]) -> Any:
        requests_w, answers_r, errors_r = self.fds
        deadline = time.monotonic() + seconds
        try:
            _send(requests_w, request)
        except OSError:
            return self._ended()
        answer, need = bytearray(), _HEADER.size
        header_done = False
        while True:  # woken at the deadline itself, not up to POLL after it
            wait = min(POLL, max(0.0, deadline - time.monotonic()))
            ready, _, _ = select.select([answers_r, errors_r], [], [], wait)
            if errors_r in ready:
                self._relay(errors_r)
            if answers_r in ready:
                chunk = os.read(answers_r, 1 << 20)
                if not chunk:
                    return self._ended()
                answer += chunk
                if not header_done and len(answer) >= _HEADER.size:
                    need = _HEADER.size + _HEADER.unpack(bytes(answer[:_HEADER.size]))[0]
                    header_done = True
                if header_done and len(answer) >= need:
                    while select.select([errors_r], [], [], 0)[0] and self._relay(errors_r):
                        pass  # what the helper printed before it answered
                    kind, value = pickle.loads(bytes(answer[_HEADER.size:need]))
                    if kind == "error":
                        raise RuntimeError(value)
                    return value
            if answer:  # the work is done and its answer on the way
                continue
            reason = "nan" if self.nans >= NAN_LIMIT else "time" if \
                time.monotonic() >= deadline else "stop" if stop() else None
            if reason is not None:
                self.close()
                return Stopped(reason)

    def _relay(self, fd: int) -> bool:
        """Read what the helper printed on stderr: count the lines with CasADi's NaN
        warnings, pass the others on; False at the end of the stream."""
        chunk = os.read(fd, 1 << 16)
        lines = (self._pending + chunk).split(b"\n")
        self._pending = lines.pop() if chunk else b""
        for line in lines:
            if NAN_MARK in line:
                self.nans += 1
            elif line:
                sys.stderr.write(line.decode(errors="replace") + "\n")
        return bool(chunk)

    def _ended(self) -> Stopped:
        """The helper is gone: say how it ended."""
        pid = self.pid
        detail = ""
        try:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done and os.WIFSIGNALED(status):
                detail = f"killed by signal {os.WTERMSIG(status)}"
        except ChildProcessError:
            pass
        self.close()
        return Stopped("died", detail)
