"""A headless Chromium for the tests, driven through the DevTools protocol over a pipe
(``--remote-debugging-pipe``: no port, no websocket library, standard library only).

``Browser.open(url)`` loads a page in a fresh tab, waits for its load event and a moment of
drawing, takes a PNG screenshot and returns it with every error the page raised: uncaught
exceptions (``Runtime.exceptionThrown``), ``console.error``/``console.assert`` calls and the
browser's own error log entries (a resource that failed to load, a blocked request).
"""

from __future__ import annotations

import base64
import fcntl
import json
import os
import select
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run",
         "--disable-default-apps", "--hide-scrollbars", "--mute-audio"]
TIMEOUT = 30.0  # seconds for any one answer of the browser


def find_chromium() -> str | None:
    """The path of a Chromium or Chrome binary, or None."""
    if Path("/usr/bin/chromium").is_file():
        return "/usr/bin/chromium"
    return next((p for p in map(shutil.which, NAMES) if p), None)


@dataclass
class Page:
    """A loaded page: its screenshot (PNG bytes) and the errors it raised."""

    png: bytes
    errors: list[str] = field(default_factory=list)


class Browser:
    """One headless browser process; ``close()`` (or ``with``) ends it."""

    def __init__(self, binary: str, size: tuple[int, int] = (900, 700)) -> None:
        self.size = size
        # Chromium's helper processes may still write into the profile as the browser ends:
        # its removal must not fail a test that passed
        self.profile = tempfile.TemporaryDirectory(prefix="ocg-chromium-",
                                                   ignore_cleanup_errors=True)
        to_browser_r, self._write = os.pipe()
        self._read, from_browser_w = os.pipe()


        def onto_3_and_4() -> None:  # the browser reads commands on fd 3, answers on fd 4
            r, w = (fcntl.fcntl(fd, fcntl.F_DUPFD, 10) for fd in (to_browser_r, from_browser_w))
            os.dup2(r, 3)
            os.dup2(w, 4)

        self.proc = subprocess.Popen(  # preexec_fn: the test process starts no threads here
            [binary, *FLAGS, "--remote-debugging-pipe", f"--user-data-dir={self.profile.name}",
             "about:blank"],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            close_fds=False, preexec_fn=onto_3_and_4)
        os.close(to_browser_r)
        os.close(from_browser_w)
        self._id = 0
        self._buffer = b""
        self._events: list[dict[str, Any]] = []

    def __enter__(self) -> Browser:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """End the browser (this process only) and remove its profile."""
        for fd in (self._write, self._read):
            try:
                os.close(fd)
            except OSError:
                pass
        self.proc.terminate()
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.profile.cleanup()

    def _message(self, deadline: float) -> dict[str, Any]:
        """The next message of the browser (messages end with a NUL byte)."""
        while b"\0" not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self._read], [], [], left)[0]:
                raise TimeoutError("the browser did not answer within "
                                   f"{TIMEOUT:g} s")
            chunk = os.read(self._read, 1 << 20)
            if not chunk:
                raise RuntimeError("the browser closed its pipe (it exited)")
            self._buffer += chunk
        raw, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(raw)

    def send(self, method: str, session: str | None = None, **params: Any) -> dict[str, Any]:
        """Send a command and return its result; events that arrive meanwhile are kept."""
        self._id += 1
        msg: dict[str, Any] = {"id": self._id, "method": method, "params": params}
        if session:
            msg["sessionId"] = session
        os.write(self._write, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + TIMEOUT
        while True:
            m = self._message(deadline)
            if m.get("id") == self._id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m.get("result", {})
            self._events.append(m)

    def wait_for(self, method: str, session: str) -> None:
        """Wait for an event of the session (those seen before count)."""
        deadline = time.monotonic() + TIMEOUT
        while not any(e.get("method") == method and e.get("sessionId") == session
                      for e in self._events):
            self._events.append(self._message(deadline))

    def open(self, url: str, settle: float = 0.3) -> Page:
        """Load ``url`` in a new tab; its screenshot and errors once loaded and drawn."""
        target = self.send("Target.createTarget", url="about:blank")["targetId"]
        session = self.send("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        for domain in ("Page", "Runtime", "Log"):
            self.send(f"{domain}.enable", session)
        w, h = self.size
        self.send("Emulation.setDeviceMetricsOverride", session, width=w, height=h,
                  deviceScaleFactor=1, mobile=False)
        self._events.clear()
        self.send("Page.navigate", session, url=url)
        self.wait_for("Page.loadEventFired", session)
        time.sleep(settle)
        shot = self.send("Page.captureScreenshot", session, format="png")
        self.send("Target.closeTarget", targetId=target)
        return Page(base64.b64decode(shot["data"]), errors(self._events, session))


def errors(events: list[dict[str, Any]], session: str) -> list[str]:
    """The errors among the events of a session, one line each."""
    found = []
    for e in events:
        if e.get("sessionId") != session:
            continue
        p = e.get("params", {})
        if e.get("method") == "Runtime.exceptionThrown":
            d = p["exceptionDetails"]
            found.append(f"exception: {d.get('exception', {}).get('description') or d['text']}"
                         f" (line {d.get('lineNumber')})")
        elif e.get("method") == "Runtime.consoleAPICalled" and p.get("type") in ("error",
                                                                               "assert"):
            found.append("console.error: " + " ".join(str(a.get("value", a.get(
                "description", ""))) for a in p.get("args", [])))
        elif e.get("method") == "Log.entryAdded" and p["entry"].get("level") == "error":
            found.append(f"log: {p['entry'].get('text')} {p['entry'].get('url', '')}".strip())
    return found
