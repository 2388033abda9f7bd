"""A minimal headless-Chromium driver for the report's browser check (no package beyond the stdlib).

Chromium is started with ``--remote-debugging-pipe``: it reads Chrome DevTools Protocol commands
(JSON, each ended by a NUL byte) from file descriptor 3 and writes replies and events to fd 4.
:class:`Chromium` opens one page, evaluates JavaScript in it and takes screenshots. Nothing is
downloaded; the browser is the system's (Debian package ``chromium``), with networking and
background services off and a fresh profile in a temporary folder.
"""

from __future__ import annotations

import base64
import fcntl
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

# Executables tried in order; STUDY_CHROMIUM overrides them.
CANDIDATES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-extensions",
         "--disable-default-apps", "--mute-audio", "--hide-scrollbars", "--remote-debugging-pipe")
# [s] for one command: a hang guard, not a judgement of the host (loading a 2 MB page with MathML takes ~1 s; a
# browser that sends no reply for a minute is stuck, and the test would otherwise hang)
TIMEOUT = 60.0


def find_chromium() -> str | None:
    """The path of a Chromium executable, or None."""
    override = os.environ.get("STUDY_CHROMIUM")
    if override:
        return shutil.which(override) or (override if Path(override).is_file() else None)
    return next((p for p in map(shutil.which, CANDIDATES) if p), None)


class Chromium:
    """One headless browser with one page; use as a context manager.

    Parameters
    ----------
    executable : path of the browser
    width, height : the viewport [CSS px]
    """

    def __init__(self, executable: str, width: int = 1280, height: int = 900):
        self._profile = tempfile.TemporaryDirectory(prefix="study-chromium-")
        to_browser_r, self._to_browser = os.pipe()
        self._from_browser, from_browser_w = os.pipe()

        def plumb():  # in the child: the command pipe on fd 3, the reply pipe on fd 4 (dup2 makes them inheritable)
            high_r = fcntl.fcntl(to_browser_r, fcntl.F_DUPFD, 10)  # out of the way of 3 and 4 first
            high_w = fcntl.fcntl(from_browser_w, fcntl.F_DUPFD, 10)
            os.dup2(high_r, 3)
            os.dup2(high_w, 4)

        self._proc = subprocess.Popen(
            [executable, *FLAGS, f"--user-data-dir={self._profile.name}", f"--window-size={width},{height}",
             "about:blank"],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            preexec_fn=plumb, close_fds=False)  # the parent's other descriptors are close-on-exec
        os.close(to_browser_r)
        os.close(from_browser_w)
        self._buffer = b""
        self._next_id = 0
        self._events: list[dict] = []
        target = self._call("Target.createTarget", {"url": "about:blank"})["targetId"]
        self._session = self._call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        self.call("Page.enable")
        self.call("Emulation.setDeviceMetricsOverride",
                  {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False})

    # --- protocol ----------------------------------------------------------------------------
    def _send(self, message: dict) -> None:
        os.write(self._to_browser, json.dumps(message).encode() + b"\0")

    def _receive(self, deadline: float) -> dict:
        while b"\0" not in self._buffer:
            if time.monotonic() > deadline:  # hang guard: TIMEOUT, a browser that stopped replying
                raise TimeoutError("no reply from Chromium")
            chunk = os.read(self._from_browser, 1 << 16)
            if not chunk:
                raise RuntimeError(f"Chromium closed its pipe (exit code {self._proc.poll()})")
            self._buffer += chunk
        message, _, self._buffer = self._buffer.partition(b"\0")
        return json.loads(message)

    def _call(self, method: str, params: dict | None = None, session: str | None = None) -> dict:
        self._next_id += 1
        message = {"id": self._next_id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        self._send(message)
        deadline = time.monotonic() + TIMEOUT  # hang guard: see TIMEOUT
        while True:
            reply = self._receive(deadline)
            if reply.get("id") == self._next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            self._events.append(reply)

    def call(self, method: str, params: dict | None = None) -> dict:
        """One DevTools command on the page; returns its result."""
        return self._call(method, params, self._session)

    def wait_for(self, event: str) -> dict:
        """Wait for (and consume) the page's next ``event``."""
        deadline = time.monotonic() + TIMEOUT  # hang guard: see TIMEOUT
        while True:
            for k, e in enumerate(self._events):
                if e.get("method") == event and e.get("sessionId") == self._session:
                    return self._events.pop(k)
            self._events.append(self._receive(deadline))

    # --- page ----------------------------------------------------------------------------------
    def open(self, url: str) -> None:
        """Navigate and wait for the load event (images decoded, layout done)."""
        self._events.clear()
        self.call("Page.navigate", {"url": url})
        self.wait_for("Page.loadEventFired")

    def evaluate(self, expression: str):
        """The value of a JavaScript expression in the page (JSON-serializable)."""
        result = self.call("Runtime.evaluate", {"expression": expression, "returnByValue": True,
                                                "awaitPromise": True})
        if "exceptionDetails" in result:
            raise RuntimeError(f"JavaScript error: {result['exceptionDetails']}")
        return result["result"].get("value")

    def screenshot(self, path: Path, clip: dict | None = None) -> Path:
        """Save a PNG of the viewport, or of ``clip`` = {x, y, width, height} in page coordinates."""
        params = {"format": "png"}
        if clip:
            params.update(clip={**clip, "scale": 1}, captureBeyondViewport=True)
        data = self.call("Page.captureScreenshot", params)["data"]
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(base64.b64decode(data))
        return path

    # --- lifetime ------------------------------------------------------------------------------
    def close(self) -> None:
        try:
            self._call("Browser.close")
        except (OSError, RuntimeError, TimeoutError):
            pass
        try:
            self._proc.wait(timeout=10)  # hang guard: a browser that does not close is killed
        except subprocess.TimeoutExpired:
            self._proc.kill()
            self._proc.wait()
        for fd in (self._to_browser, self._from_browser):
            try:
                os.close(fd)
            except OSError:
                pass
        self._profile.cleanup()

    def __enter__(self) -> "Chromium":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
