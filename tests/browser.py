"""Headless Chromium driven over the DevTools protocol, for the tests of web pages.

The protocol runs over a pair of pipes (``--remote-debugging-pipe``: the
browser reads commands from its fd 3 and writes replies and events to its
fd 4, each message JSON ended by a NUL byte), so no port, no websocket
library and no network are needed.  :class:`Browser` loads a page, waits
for a condition in it, takes a screenshot and collects every console
error, uncaught exception and failed load the page had.

WebGL runs on SwiftShader (software), which headless Chromium offers with
``--use-angle=swiftshader --enable-unsafe-swiftshader``.
"""

from __future__ import annotations

import base64
import io
import json
import os
import shutil
import subprocess
import tempfile
import time

import numpy as np


def find_chromium() -> str | None:
    """The Chromium binary, or None when there is none."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return "/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else None


class BrowserError(RuntimeError):
    """The browser did not answer, or answered a command with an error."""


class Browser:
    """One headless Chromium with one page; use as a context manager.

    Parameters
    ----------
    binary : str
        Chromium's path (:func:`find_chromium`).
    width, height : int
        The window (and screenshot) size in CSS pixels.
    timeout : float
        Seconds to wait for any one answer of the browser.
    """

    def __init__(self, binary: str, width: int = 900, height: int = 700, timeout: float = 60.0):
        self.timeout = timeout
        self.profile = tempfile.mkdtemp(prefix="singmesh-chromium-")
        cmd_r, self._cmd_w = os.pipe()   # we write commands, the browser reads them on its fd 3
        self._evt_r, evt_w = os.pipe()   # the browser writes on its fd 4, we read

        def child_fds():
            # Through fresh copies: cmd_r or evt_w may themselves be 3 or 4.
            a, b = os.dup(cmd_r), os.dup(evt_w)
            os.dup2(a, 3)
            os.dup2(b, 4)

        args = [binary, "--headless=new", "--no-sandbox", "--remote-debugging-pipe",
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist",
                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                "--no-first-run", "--no-default-browser-check", "--disable-dev-shm-usage",
                "--hide-scrollbars", "--mute-audio", f"--window-size={width},{height}",
                f"--user-data-dir={self.profile}", "about:blank"]
        self.proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=subprocess.DEVNULL, preexec_fn=child_fds, pass_fds=(3, 4))
        os.close(cmd_r)
        os.close(evt_w)
        self._buffer = b""
        self._next_id = 0
        self.events: list[dict] = []
        self.session: str | None = None
        self.width, self.height = width, height

    # ------------------------------------------------------------ protocol
    def _read_message(self, deadline: float) -> dict:
        import select

        while b"\0" not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0:
                raise BrowserError("the browser did not answer in time")
            ready, _, _ = select.select([self._evt_r], [], [], left)
            if ready:
                chunk = os.read(self._evt_r, 1 << 20)
                if not chunk:
                    raise BrowserError("the browser closed the DevTools pipe (it exited)")
                self._buffer += chunk
        message, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(message)

    def send(self, method: str, params: dict | None = None, session: bool = True) -> dict:
        """Send one command and wait for its answer; events that arrive meanwhile are kept in ``events``."""
        self._next_id += 1
        message = {"id": self._next_id, "method": method, "params": params or {}}
        if session and self.session:
            message["sessionId"] = self.session
        os.write(self._cmd_w, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + self.timeout
        while True:
            reply = self._read_message(deadline)
            if reply.get("id") == self._next_id:
                if "error" in reply:
                    raise BrowserError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            if "method" in reply:
                self.events.append(reply)

    def wait_event(self, method: str, timeout: float | None = None) -> dict:
        """Wait for an event named ``method`` (kept ones first)."""
        for e in self.events:
            if e["method"] == method and e.get("sessionId") == self.session:
                return e
        deadline = time.monotonic() + (timeout or self.timeout)
        while True:
            reply = self._read_message(deadline)
            if "method" in reply:
                self.events.append(reply)
                if reply["method"] == method and reply.get("sessionId") == self.session:
                    return reply

    # ------------------------------------------------------------ page
    def open(self, url: str) -> None:
        """Open a page in a new tab and wait for its load event (the events of earlier pages are dropped)."""
        self.events = []
        target = self.send("Target.createTarget", {"url": "about:blank"}, session=False)["targetId"]
        self.session = self.send("Target.attachToTarget", {"targetId": target, "flatten": True},
                                 session=False)["sessionId"]
        for domain in ("Page", "Runtime", "Log"):
            self.send(f"{domain}.enable")
        self.send("Emulation.setDeviceMetricsOverride",
                  {"width": self.width, "height": self.height, "deviceScaleFactor": 1, "mobile": False})
        self.send("Page.navigate", {"url": url})
        self.wait_event("Page.loadEventFired")

    def evaluate(self, expression: str):
        """The value of a JavaScript expression in the page (awaited if it is a promise)."""
        result = self.send("Runtime.evaluate", {"expression": expression, "returnByValue": True,
                                                "awaitPromise": True})
        if "exceptionDetails" in result:
            raise BrowserError(f"{expression}: {result['exceptionDetails'].get('text')}")
        return result["result"].get("value")

    def wait_for(self, expression: str, timeout: float = 20.0):
        """Poll a JavaScript expression until it is truthy; its value, or None on timeout."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            value = self.evaluate(expression)
            if value:
                return value
            time.sleep(0.1)
        return None

    def screenshot(self) -> np.ndarray:
        """The page as an (h, w, 3) float RGB image in [0, 1]."""
        import matplotlib.image as mpimg

        data = self.send("Page.captureScreenshot", {"format": "png"})["data"]
        return mpimg.imread(io.BytesIO(base64.b64decode(data)), format="png")[..., :3].astype(float)

    def problems(self) -> list[str]:
        """Console errors, uncaught exceptions and failed loads of the page so far, one line each."""
        out = []
        for e in self.events:
            if e.get("sessionId") != self.session:
                continue
            p = e.get("params", {})
            if e["method"] == "Runtime.exceptionThrown":
                d = p.get("exceptionDetails", {})
                out.append(f"exception: {d.get('text')} {(d.get('exception') or {}).get('description', '')}".strip())
            elif e["method"] == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
                out.append("console.error: " + " ".join(str(a.get("value", a.get("description")))
                                                        for a in p.get("args", [])))
            elif e["method"] == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
                entry = p["entry"]
                out.append(f"log error: {entry.get('text')} {entry.get('url', '')}".strip())
        return out

    def warnings(self) -> list[str]:
        """Console warnings of the page so far."""
        return [" ".join(str(a.get("value", a.get("description"))) for a in e["params"].get("args", []))
                for e in self.events if e.get("sessionId") == self.session
                and e["method"] == "Runtime.consoleAPICalled" and e["params"].get("type") == "warning"]

    def close(self) -> None:
        try:
            self.send("Browser.close", session=False)
        except (BrowserError, OSError):
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()   # only the browser this object started
            self.proc.wait()
        for fd in (self._cmd_w, self._evt_r):
            try:
                os.close(fd)
            except OSError:
                pass
        shutil.rmtree(self.profile, ignore_errors=True)

    def __enter__(self) -> "Browser":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def region(img: np.ndarray, rect: dict) -> np.ndarray:
    """The part of a screenshot inside a DOMRect-like dict (x, y, width, height in CSS pixels)."""
    x0, y0 = max(0, int(rect["x"])), max(0, int(rect["y"]))
    return img[y0:y0 + int(rect["height"]), x0:x0 + int(rect["width"])]


def colour_facts(img: np.ndarray) -> dict[str, float]:
    """What a picture of a mesh shows: distinct colours, and the shares of orange and of blue pixels.

    Orange is red well over blue with green between (the grad F side),
    blue is blue well over red (the other side); distinct colours are
    counted at 32 levels per channel.
    """
    rgb = img[..., :3].reshape(-1, 3)
    r, g, b = rgb[:, 0], rgb[:, 1], rgb[:, 2]
    orange = (r - b > 0.25) & (g > b) & (r > g)
    blue = (b - r > 0.2) & (b > g)
    q = np.round(rgb * 31).astype(np.int64)
    distinct = len(np.unique((q[:, 0] << 10) | (q[:, 1] << 5) | q[:, 2]))
    return {"distinct": float(distinct), "orange": float(orange.mean()), "blue": float(blue.mean())}
