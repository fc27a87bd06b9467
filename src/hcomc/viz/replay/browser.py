"""Headless Chromium driven over the DevTools protocol, to check and photograph a page.

:class:`Chromium` starts ``chromium --headless`` with ``--remote-debugging-pipe`` and speaks
the Chrome DevTools Protocol over that pipe (messages are JSON, each ended by a NUL byte), so
it needs no websocket client and no network port. It opens a page, evaluates JavaScript in
it, takes screenshots and collects the page's console errors and uncaught exceptions. The
tests read the replay page through it, and ``hcomc replay --screenshot`` uses it.
"""

from __future__ import annotations

import base64
import contextlib
import fcntl
import json
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

__all__ = ["BrowserError", "Chromium", "find_chromium", "replay_screenshot"]

EXECUTABLES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
"""Names under which Chromium is looked for on PATH, in order."""

FLAGS = (
    "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--disable-extensions", "--disable-default-apps", "--mute-audio", "--hide-scrollbars",
    "--force-device-scale-factor=1",
)  # fmt: skip
"""Chromium's flags: headless, offline, nothing that phones home."""

# Starts Chromium with the pipe's ends as fds 3 (commands in) and 4 (replies out).
_TRAMPOLINE = (
    "import os, sys; r, w = int(sys.argv[1]), int(sys.argv[2]); os.dup2(r, 3); os.dup2(w, 4); "
    "os.close(r); os.close(w); os.execvp(sys.argv[3], sys.argv[3:])"
)


class BrowserError(RuntimeError):
    """Chromium is missing, died, or a DevTools command failed."""


def find_chromium() -> str | None:
    """Path of a Chromium executable on PATH (:data:`EXECUTABLES`), or None."""
    for name in EXECUTABLES:
        path = shutil.which(name)
        if path:
            return path
    return None


def _high(fd: int) -> int:
    """``fd`` moved to a number of 5 or more (never 3 or 4, which the child needs)."""
    moved = fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 5)
    os.close(fd)
    return moved


class Chromium:
    """One headless Chromium with one page, as a context manager.

    Parameters
    ----------
    width, height : int
        The page's viewport [CSS px].
    executable : str, optional
        Chromium's path; default :func:`find_chromium`.
    timeout : float
        How long one command may take before :class:`BrowserError` [s] (a guard against a
        hung browser, not a performance limit).
    """

    def __init__(self, width: int = 1280, height: int = 900, *, executable: str | None = None,
                 timeout: float = 120.0) -> None:  # fmt: skip
        exe = executable or find_chromium()
        if exe is None:
            raise BrowserError(f"Chromium is not installed (looked for {', '.join(EXECUTABLES)})")
        self.timeout = timeout
        self.console_errors: list[str] = []
        self._profile = tempfile.mkdtemp(prefix="hcomc-chromium-")
        to_child, self._out = (_high(fd) for fd in os.pipe())
        self._in, from_child = (_high(fd) for fd in os.pipe())
        args = [*FLAGS, f"--user-data-dir={self._profile}", "--remote-debugging-pipe",
                f"--window-size={width},{height}", "about:blank"]  # fmt: skip
        self._proc = subprocess.Popen(
            [sys.executable, "-c", _TRAMPOLINE, str(to_child), str(from_child), exe, *args],
            pass_fds=(to_child, from_child), stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )  # fmt: skip
        os.close(to_child)
        os.close(from_child)
        self._buffer = b""
        self._next_id = 0
        self._loaded = False
        try:
            target = self._call("Target.createTarget", {"url": "about:blank"})["targetId"]
            attach = {"targetId": target, "flatten": True}
            self._session = self._call("Target.attachToTarget", attach)["sessionId"]
            for domain in ("Page", "Runtime", "Log"):
                self.call(f"{domain}.enable")
            metrics = {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}
            self.call("Emulation.setDeviceMetricsOverride", metrics)
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------ protocol
    def _send(self, method: str, params: dict[str, Any] | None, session: str | None) -> int:
        self._next_id += 1
        message: dict[str, Any] = {"id": self._next_id, "method": method, "params": params or {}}
        if session is not None:
            message["sessionId"] = session
        data = json.dumps(message).encode() + b"\0"
        while data:
            data = data[os.write(self._out, data) :]
        return self._next_id

    def _receive(self, deadline: float) -> dict[str, Any]:
        """The next message from Chromium (events are handled on the way)."""
        while b"\0" not in self._buffer:
            remaining = deadline - time.monotonic()
            ready, _, _ = select.select([self._in], [], [], max(0.0, remaining))
            if not ready:
                raise BrowserError(f"Chromium did not answer within {self.timeout:g} s")
            chunk = os.read(self._in, 1 << 20)
            if not chunk:
                raise BrowserError("Chromium closed its DevTools pipe (it crashed or exited)")
            self._buffer += chunk
        raw, _, self._buffer = self._buffer.partition(b"\0")
        message: dict[str, Any] = json.loads(raw)
        self._event(message)
        return message

    def _event(self, message: dict[str, Any]) -> None:
        method, params = message.get("method"), message.get("params") or {}
        if method == "Page.loadEventFired":
            self._loaded = True
        elif method == "Runtime.exceptionThrown":
            details = params.get("exceptionDetails") or {}
            exception = details.get("exception") or {}
            self.console_errors.append(str(exception.get("description") or details.get("text")))
        elif method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
            args = [str(a.get("value", a.get("description"))) for a in params.get("args") or []]
            self.console_errors.append(" ".join(args))
        elif method == "Log.entryAdded" and (params.get("entry") or {}).get("level") == "error":
            self.console_errors.append(str(params["entry"].get("text")))

    def _call(self, method: str, params: dict[str, Any] | None = None,
              session: str | None = None) -> dict[str, Any]:  # fmt: skip
        ident = self._send(method, params, session)
        deadline = time.monotonic() + self.timeout
        while True:
            message = self._receive(deadline)
            if message.get("id") == ident:
                if "error" in message:
                    raise BrowserError(f"{method}: {message['error'].get('message')}")
                result: dict[str, Any] = message.get("result") or {}
                return result

    def call(self, method: str, params: dict[str, Any] | None = None) -> dict[str, Any]:
        """Send one DevTools command to the page and return its result."""
        return self._call(method, params, self._session)

    # ------------------------------------------------------------------ page
    def open(self, url: str) -> None:
        """Navigate to ``url`` and wait for its load event."""
        self._loaded = False
        result = self.call("Page.navigate", {"url": url})
        if result.get("errorText"):
            raise BrowserError(f"cannot open {url}: {result['errorText']}")
        deadline = time.monotonic() + self.timeout
        while not self._loaded:
            self._receive(deadline)

    def evaluate(self, expression: str) -> Any:
        """The value of a JavaScript expression in the page (promises are awaited)."""
        params = {"expression": expression, "returnByValue": True, "awaitPromise": True}
        result = self.call("Runtime.evaluate", params)
        if "exceptionDetails" in result:
            details = result["exceptionDetails"]
            text = (details.get("exception") or {}).get("description") or details.get("text")
            raise BrowserError(f"JavaScript error: {text}")
        return (result.get("result") or {}).get("value")

    def screenshot(self, path: str | os.PathLike[str]) -> Path:
        """Write a PNG of the whole page (not only the viewport) to ``path``."""
        layout = self.call("Page.getLayoutMetrics")
        size = layout.get("cssContentSize") or layout["contentSize"]
        clip = {"x": 0, "y": 0, "width": size["width"], "height": size["height"], "scale": 1}
        params = {"format": "png", "clip": clip, "captureBeyondViewport": True}
        data = self.call("Page.captureScreenshot", params)["data"]
        target = Path(path)
        target.write_bytes(base64.b64decode(data))
        return target

    # ------------------------------------------------------------------ lifetime
    def close(self) -> None:
        """End Chromium and remove its profile."""
        if self._proc.poll() is None:
            try:
                self._send("Browser.close", None, None)
                self._proc.wait(timeout=10)
            except (OSError, subprocess.TimeoutExpired):
                self._proc.kill()
                self._proc.wait()
        for fd in (self._in, self._out):
            with contextlib.suppress(OSError):
                os.close(fd)
        shutil.rmtree(self._profile, ignore_errors=True)

    def __enter__(self) -> Chromium:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def replay_screenshot(
    page: str | os.PathLike[str], png: str | os.PathLike[str], *, t: float, width: int = 1280,
    height: int = 900,
) -> Path:  # fmt: skip
    """A PNG of the replay page ``page`` at time ``t`` [s] with the first ramp vehicle
    selected (its chart shown); :class:`BrowserError` if the page reports an error."""
    with Chromium(width, height) as browser:
        browser.open(Path(page).resolve().as_uri())
        browser.evaluate(f"hcomcReplay.select(hcomcReplay.keyVehicle()); hcomcReplay.seek({t!r})")
        if browser.console_errors:
            raise BrowserError("the page reported errors: " + "; ".join(browser.console_errors))
        return browser.screenshot(png)
