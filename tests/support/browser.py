"""Headless Chromium for the tests: load a page, collect its console errors, take a screenshot.

Chromium (Debian's ``chromium``) is driven through the DevTools protocol over a pipe
(``--remote-debugging-pipe``: commands on the browser's fd 3, answers and events on its fd 4,
JSON messages ended by a NUL byte), so no websocket client and no network port are needed. Every
host name resolves to nothing (``--host-resolver-rules``): a page that tries to fetch anything
logs a network error.

Run as a script, it takes the screenshots of the 3-D view in ``docs/figures/``:
``python tests/support/browser.py out/walk.html docs/figures/own_robot_walk.png --frame 149`` shows
animation frame 149 of the page written by ``uvms-qp run ... --view out/walk.html``.
"""

from __future__ import annotations

import argparse
import base64
import contextlib
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

#: The flags this machine's Chromium needs headless as root, plus software WebGL and no network.
FLAGS = (
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--enable-unsafe-swiftshader", "--host-resolver-rules=MAP * ~NOTFOUND",
    "--remote-debugging-pipe",
)


def chromium() -> str | None:
    """Path of the Chromium executable, or None."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


@dataclass
class PageReport:
    """What loading a page gave.

    Attributes:
        png: Screenshot once the page is ready (PNG bytes).
        shots: Screenshot after each of the ``steps`` given to :func:`load_page`.
        values: What each step evaluated to (JSON values).
        errors: Console errors, uncaught exceptions and error log entries (network included).
        messages: Every console message and log entry as ``(level, text)``.
    """

    png: bytes
    shots: list[bytes] = field(default_factory=list)
    values: list[Any] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    messages: list[tuple[str, str]] = field(default_factory=list)


class _Pipe:
    def __init__(self, write_fd: int, read_fd: int) -> None:
        self.write_fd = write_fd
        self.read_fd = read_fd
        self.buffer = b""
        self.next_id = 0
        self.events: list[dict[str, Any]] = []

    def send(self, method: str, params: dict[str, Any] | None = None,
             session: str | None = None) -> int:
        self.next_id += 1
        message: dict[str, Any] = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(self.write_fd, json.dumps(message).encode() + b"\0")
        return self.next_id

    def _read(self, deadline: float) -> dict[str, Any]:
        while b"\0" not in self.buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.read_fd], [], [], left)[0]:
                raise TimeoutError("chromium did not answer in time")
            chunk = os.read(self.read_fd, 1 << 20)
            if not chunk:
                raise RuntimeError("chromium closed its DevTools pipe")
            self.buffer += chunk
        raw, self.buffer = self.buffer.split(b"\0", 1)
        return json.loads(raw)  # type: ignore[no-any-return]

    def call(self, method: str, params: dict[str, Any] | None = None,
             session: str | None = None, timeout: float = 30.0) -> dict[str, Any]:
        ident = self.send(method, params, session)
        deadline = time.monotonic() + timeout
        while True:
            message = self._read(deadline)
            if message.get("id") == ident:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                return message.get("result", {})  # type: ignore[no-any-return]
            self.events.append(message)

    def wait(self, method: str, timeout: float) -> dict[str, Any]:
        deadline = time.monotonic() + timeout
        for event in self.events:
            if event.get("method") == method:
                return event
        while True:
            message = self._read(deadline)
            self.events.append(message)
            if message.get("method") == method:
                return message

    def drain(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        try:
            while True:
                self.events.append(self._read(deadline))
        except TimeoutError:
            pass


def _collect(events: list[dict[str, Any]], report: PageReport) -> None:
    for event in events:
        method, params = event.get("method"), event.get("params", {})
        if method == "Runtime.consoleAPICalled":
            text = " ".join(str(a.get("value", a.get("description", ""))) for a in params["args"])
            report.messages.append((params["type"], text))
            if params["type"] in ("error", "assert"):
                report.errors.append(f"console.{params['type']}: {text}")
        elif method == "Runtime.exceptionThrown":
            details = params["exceptionDetails"]
            text = details.get("exception", {}).get("description", details.get("text", ""))
            report.messages.append(("exception", text))
            report.errors.append(f"uncaught: {text}")
        elif method == "Log.entryAdded":
            entry = params["entry"]
            report.messages.append((entry["level"], entry["text"]))
            if entry["level"] == "error":
                report.errors.append(f"{entry.get('source', 'log')}: {entry['text']}")


def load_page(path: Path, *, width: int = 1000, height: int = 750, ready: str = "true",
              steps: tuple[str, ...] = (), settle: float = 1.5,
              timeout: float = 60.0) -> PageReport:
    """Open ``path`` in headless Chromium and report its console errors and a screenshot.

    Args:
        path: Local HTML file.
        width: Viewport width [px].
        height: Viewport height [px].
        ready: JavaScript expression that is true once the page has drawn.
        steps: JavaScript run one after the other once the page is ready (a promise is
            awaited); each is followed by ``settle`` and a screenshot.
        settle: Time given to the page after ``ready`` and after each step [s] (events keep
            being collected).
        timeout: Limit on the whole load [s].
    """
    exe = chromium()
    if exe is None:
        raise RuntimeError("chromium is not installed")
    commands_r, commands_w = os.pipe()
    answers_r, answers_w = os.pipe()

    def child_fds() -> None:  # the browser reads fd 3 and writes fd 4
        os.dup2(commands_r, 100)
        os.dup2(answers_w, 101)
        os.dup2(100, 3)
        os.dup2(101, 4)

    profile = tempfile.mkdtemp(prefix="uvms-qp-chromium-")
    process = subprocess.Popen(
        [exe, *FLAGS, f"--user-data-dir={profile}", f"--window-size={width},{height}",
         "about:blank"],
        stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        preexec_fn=child_fds, close_fds=False,
    )
    os.close(commands_r)
    os.close(answers_w)
    pipe = _Pipe(commands_w, answers_r)
    try:
        target = pipe.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = pipe.call("Target.attachToTarget", {"targetId": target, "flatten": True})[
            "sessionId"]
        for method in ("Runtime.enable", "Log.enable", "Page.enable"):
            pipe.call(method, session=session)
        pipe.call("Emulation.setDeviceMetricsOverride", {
            "width": width, "height": height, "deviceScaleFactor": 1, "mobile": False,
        }, session=session)
        pipe.call("Page.navigate", {"url": path.resolve().as_uri()}, session=session)
        pipe.wait("Page.loadEventFired", timeout)
        deadline = time.monotonic() + timeout
        while not pipe.call("Runtime.evaluate", {"expression": f"Boolean({ready})",
                                                 "returnByValue": True},
                            session=session)["result"].get("value"):
            if time.monotonic() > deadline:
                raise TimeoutError(f"page not ready ({ready}) after {timeout} s")
            time.sleep(0.2)
        pipe.drain(settle)

        def screenshot() -> bytes:
            shot = pipe.call("Page.captureScreenshot", {"format": "png"}, session=session)
            return base64.b64decode(shot["data"])

        report = PageReport(screenshot())
        for step in steps:
            answer = pipe.call("Runtime.evaluate", {"expression": step, "awaitPromise": True,
                                                    "returnByValue": True},
                               session=session, timeout=timeout)
            if "exceptionDetails" in answer:
                raise RuntimeError(f"step {step!r}: {answer['exceptionDetails']}")
            report.values.append(answer["result"].get("value"))
            pipe.drain(settle)
            report.shots.append(screenshot())
        _collect(pipe.events, report)
        return report
    finally:
        with contextlib.suppress(OSError):
            pipe.send("Browser.close")
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
        os.close(commands_w)
        os.close(answers_r)
        shutil.rmtree(profile, ignore_errors=True)


def view_screenshot(page: Path, png: Path, frame: int, *, width: int = 1000,
                    height: int = 700) -> list[str]:
    """Write a screenshot of frame ``frame`` of a 3-D view page; return the console errors."""
    div = "document.getElementById('uvms-qp-view')"
    still = "{frame: {duration: 0, redraw: true}, mode: 'immediate'}"
    report = load_page(
        page, width=width, height=height, settle=0.5,
        ready=f"{div} && {div}.querySelector('.gl-container canvas') !== null",
        steps=(f"Plotly.animate({div}, ['{frame}'], {still}).then(() => null)",),
    )
    png.write_bytes(report.shots[0])
    return report.errors


def main() -> int:
    parser = argparse.ArgumentParser(description="screenshot of a frame of a 3-D view page")
    parser.add_argument("page", type=Path, help="HTML file written by uvms-qp run --view")
    parser.add_argument("png", type=Path, help="PNG file to write")
    parser.add_argument("--frame", type=int, default=0, help="animation frame to show")
    args = parser.parse_args()
    errors = view_screenshot(args.page, args.png, args.frame)
    for error in errors:
        print(f"console error: {error}")
    return 1 if errors else 0


if __name__ == "__main__":
    raise SystemExit(main())
