"""A page opened in real headless Chromium (Debian's ``chromium``), driven through the
DevTools protocol over a pipe (``--remote-debugging-pipe``: JSON messages ended by a NUL byte
on file descriptors 3 and 4; no port, no extra package): what a person opening the page
would get, and what the browser said meanwhile.

:func:`open_page` loads a file, waits for its load event, and returns the console's errors
and warnings, the uncaught exceptions, the log's entries (failed loads among them), every
URL the page asked for, the DOM's text, the images' sizes and a screenshot (PNG bytes).

Chromium is needed: without it the tests that use this skip, unless
``MASONRY_DEM_REQUIRE_CHROMIUM=1`` (CI installs it and sets that), where they fail.
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

import pytest

#: the flags of a headless browser on a closed network, as root (docs of the machine)
FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-extensions",
    "--disable-dev-shm-usage",
    "--hide-scrollbars",
    "--remote-debugging-pipe",
)
TIMEOUT = 60.0


def chromium() -> str:
    """The browser's path; skips (fails under MASONRY_DEM_REQUIRE_CHROMIUM=1) without one."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    if os.environ.get("MASONRY_DEM_REQUIRE_CHROMIUM") == "1":
        pytest.fail("MASONRY_DEM_REQUIRE_CHROMIUM=1 but chromium is not on PATH")
    pytest.skip("the browser tests need chromium on PATH (Debian: apt-get install chromium)")


@dataclass
class Page:
    console: list[dict[str, Any]] = field(default_factory=list)  # Runtime.consoleAPICalled
    exceptions: list[dict[str, Any]] = field(default_factory=list)  # Runtime.exceptionThrown
    log: list[dict[str, Any]] = field(default_factory=list)  # Log.entryAdded
    requests: list[str] = field(default_factory=list)  # Network.requestWillBeSent URLs
    text: str = ""  # document.body.innerText
    images: list[dict[str, Any]] = field(default_factory=list)  # id, complete, natural size
    screenshot: bytes = b""  # the whole page, PNG
    rects: dict[str, list[float]] = field(default_factory=dict)  # id: x, y, width, height (px)

    @property
    def errors(self) -> list[str]:
        """Everything the browser reported as an error or a warning."""
        out = [
            f"console.{c.get('type')}: {c.get('args')}"
            for c in self.console
            if c.get("type") in ("error", "warning", "assert")
        ]
        out += [f"exception: {e.get('exceptionDetails')}" for e in self.exceptions]
        out += [
            f"log {e.get('entry', {}).get('level')}: {e.get('entry', {}).get('text')} "
            f"({e.get('entry', {}).get('url', '')})"
            for e in self.log
            if e.get("entry", {}).get("level") in ("error", "warning")
        ]
        return out


class _Pipe:
    """The DevTools protocol over Chromium's pipe."""

    def __init__(self, proc: subprocess.Popen[bytes], write_fd: int, read_fd: int) -> None:
        self.proc, self.write_fd, self.read_fd = proc, write_fd, read_fd
        self.next_id = 0
        self.buffer = b""
        self.events: list[dict[str, Any]] = []

    def send(self, method: str, params: dict[str, Any] | None = None, session: str = "") -> Any:
        self.next_id += 1
        message: dict[str, Any] = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(self.write_fd, json.dumps(message).encode() + b"\0")
        wanted = self.next_id
        while True:
            reply = self._read(TIMEOUT)
            if reply.get("id") == wanted:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            self.events.append(reply)

    def wait_for(self, method: str, timeout: float = TIMEOUT) -> dict[str, Any]:
        for event in self.events:
            if event.get("method") == method:
                return event
        end = time.monotonic() + timeout
        while True:
            event = self._read(end - time.monotonic())
            self.events.append(event)
            if event.get("method") == method:
                return event

    def _read(self, timeout: float) -> dict[str, Any]:
        end = time.monotonic() + timeout
        while b"\0" not in self.buffer:
            left = end - time.monotonic()
            ready, _, _ = select.select([self.read_fd], [], [], max(left, 0.0))
            if not ready:
                raise TimeoutError(f"Chromium said nothing for {timeout:.0f} s")
            chunk = os.read(self.read_fd, 1 << 20)
            if not chunk:
                raise RuntimeError(f"Chromium closed its pipe (exit code {self.proc.poll()})")
            self.buffer += chunk
        message, _, self.buffer = self.buffer.partition(b"\0")
        return json.loads(message)


def open_page(path: Path, width: int = 1280, height: int = 1600) -> Page:
    """Load ``path`` (a file) in headless Chromium and return what it showed and said."""
    browser = chromium()
    with tempfile.TemporaryDirectory(prefix="masonry-dem-chromium-") as profile:
        # the browser reads commands on its fd 3 and writes on its fd 4: the shell puts the
        # pipe's ends there (moved above 10 first, clear of 3 and 4)
        ends = os.pipe() + os.pipe()
        to_browser_r, to_browser_w, from_browser_r, from_browser_w = (
            fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 10) for fd in ends
        )
        for fd in ends:
            os.close(fd)
        proc = subprocess.Popen(
            [
                "/bin/bash",  # dash takes no file descriptor above 9
                "-c",
                f'exec "$0" "$@" 3<&{to_browser_r} 4>&{from_browser_w}',
                browser,
                *FLAGS,
                f"--user-data-dir={profile}",
                f"--window-size={width},{height}",
            ],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            pass_fds=(to_browser_r, from_browser_w),
        )
        os.close(to_browser_r)
        os.close(from_browser_w)
        pipe = _Pipe(proc, to_browser_w, from_browser_r)
        try:
            return _drive(pipe, path, width, height)
        finally:
            try:
                pipe.send("Browser.close")
            except (RuntimeError, TimeoutError, OSError):
                pass
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            os.close(to_browser_w)
            os.close(from_browser_r)


def _drive(pipe: _Pipe, path: Path, width: int, height: int) -> Page:
    target = pipe.send("Target.createTarget", {"url": "about:blank"})["targetId"]
    session = pipe.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
    for domain in ("Runtime", "Log", "Network", "Page"):
        pipe.send(f"{domain}.enable", session=session)
    pipe.send(
        "Emulation.setDeviceMetricsOverride",
        {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
        session=session,
    )
    pipe.events.clear()
    pipe.send("Page.navigate", {"url": path.resolve().as_uri()}, session=session)
    pipe.wait_for("Page.loadEventFired")
    time.sleep(0.5)  # late console messages

    def evaluate(expression: str) -> Any:
        result = pipe.send(
            "Runtime.evaluate", {"expression": expression, "returnByValue": True}, session=session
        )
        return result["result"].get("value")

    page = Page()
    page.text = evaluate("document.body.innerText")
    page.images = evaluate(
        "Array.from(document.images).map(i => ({id: i.id, complete: i.complete, "
        "width: i.naturalWidth, height: i.naturalHeight, src: i.src.slice(0, 30)}))"
    )
    page.rects = evaluate(
        "Object.fromEntries(Array.from(document.querySelectorAll('[id]')).map(e => {"
        "const r = e.getBoundingClientRect(); return [e.id, [r.x + window.scrollX, "
        "r.y + window.scrollY, r.width, r.height]]; }))"
    )
    size = pipe.send("Page.getLayoutMetrics", session=session)["cssContentSize"]
    shot = pipe.send(
        "Page.captureScreenshot",
        {
            "format": "png",
            "captureBeyondViewport": True,
            "clip": {"x": 0, "y": 0, "width": size["width"], "height": size["height"], "scale": 1},
        },
        session=session,
    )
    page.screenshot = base64.b64decode(shot["data"])
    for event in pipe.events:
        if event.get("sessionId") != session:
            continue
        method, params = event.get("method"), event.get("params", {})
        if method == "Runtime.consoleAPICalled":
            page.console.append(params)
        elif method == "Runtime.exceptionThrown":
            page.exceptions.append(params)
        elif method == "Log.entryAdded":
            page.log.append(params)
        elif method == "Network.requestWillBeSent":
            page.requests.append(params.get("request", {}).get("url", ""))
    return page
