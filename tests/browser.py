"""A headless Chromium driven over the DevTools protocol through a pipe (no extra Python package).

Chromium's ``--remote-debugging-pipe`` reads protocol commands (JSON, each ended by a NUL byte) on file
descriptor 3 and writes replies and events on descriptor 4.  :class:`Browser` opens one page, records its
console messages, uncaught exceptions, log entries (CSP violations, failed loads) and every request, and
can evaluate scripts, send input and take full-page screenshots.  Tests skip when Chromium is absent.
"""

from __future__ import annotations

import base64
import fcntl
import json
import os
import queue
import shutil
import subprocess
import tempfile
import threading
import time

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")

# Flags that keep a headless Chromium quiet on a machine without network (no background connections,
# no component updates) and runnable as root in a container.
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-default-apps", "--disable-extensions", "--mute-audio", "--hide-scrollbars")


def find_chromium() -> str | None:
    """Path of a Chromium/Chrome executable (``$PROCAM_CHROMIUM`` first), or None."""
    env = os.environ.get("PROCAM_CHROMIUM")
    if env and shutil.which(env):
        return shutil.which(env)
    for n in CHROMIUM_NAMES:
        p = shutil.which(n)
        if p:
            return p
    return None


class BrowserError(RuntimeError):
    pass


class Browser:
    """One headless Chromium with one page attached (use as a context manager)."""

    def __init__(self, executable: str, width: int = 1200, height: int = 900, timeout: float = 60.0):
        self.timeout = timeout
        self.width, self.height = width, height
        self._profile = tempfile.mkdtemp(prefix="procam-chromium-")
        cmd_r, cmd_w = os.pipe()      # we write commands -> chromium reads fd 3
        res_r, res_w = os.pipe()      # chromium writes fd 4 -> we read

        def child_fds():  # in the child, before exec: the pipe ends become fds 3 and 4 (inheritable)
            a, b = fcntl.fcntl(cmd_r, fcntl.F_DUPFD, 10), fcntl.fcntl(res_w, fcntl.F_DUPFD, 10)
            os.dup2(a, 3)
            os.dup2(b, 4)

        self.proc = subprocess.Popen(
            [executable, *FLAGS, f"--user-data-dir={self._profile}", "--remote-debugging-pipe",
             f"--window-size={width},{height}", "about:blank"],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
            preexec_fn=child_fds, close_fds=False)
        os.close(cmd_r)
        os.close(res_w)
        self._out = os.fdopen(cmd_w, "wb", buffering=0)
        self._in = os.fdopen(res_r, "rb", buffering=0)
        self._queue: queue.Queue = queue.Queue()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        self._next = 0
        self.events: list[dict] = []
        self.session = None
        try:
            targets = self.send("Target.getTargets")["targetInfos"]
            page = next((t for t in targets if t["type"] == "page"), None)
            tid = page["targetId"] if page else self.send("Target.createTarget", url="about:blank")["targetId"]
            self.session = self.send("Target.attachToTarget", targetId=tid, flatten=True)["sessionId"]
            for domain in ("Page", "Runtime", "Log", "Network"):
                self.send(f"{domain}.enable", session=True)
            self.send("Emulation.setDeviceMetricsOverride", session=True, width=width, height=height,
                      deviceScaleFactor=1, mobile=False)
        except Exception:
            self.close()
            raise

    # -- protocol --------------------------------------------------------------------------------
    def _read(self):
        buf = b""
        while True:
            try:
                chunk = self._in.read(65536)
            except OSError:
                chunk = b""
            if not chunk:
                self._queue.put(None)
                return
            buf += chunk
            while b"\0" in buf:
                msg, buf = buf.split(b"\0", 1)
                self._queue.put(json.loads(msg))

    def _pump(self, until: float):
        msg = self._queue.get(timeout=max(0.01, until - time.monotonic()))
        if msg is None:
            raise BrowserError("chromium closed the pipe: " + self._stderr())
        if "id" not in msg:
            self.events.append(msg)
        return msg

    def send(self, method: str, session: bool = False, **params):
        """Send a command and wait for its result (raises BrowserError on a protocol error)."""
        self._next += 1
        msg = {"id": self._next, "method": method, "params": params}
        if session:
            msg["sessionId"] = self.session
        self._out.write(json.dumps(msg).encode() + b"\0")
        until = time.monotonic() + self.timeout
        while True:
            try:
                reply = self._pump(until)
            except queue.Empty:
                raise BrowserError(f"no reply to {method} within {self.timeout} s") from None
            if reply.get("id") == self._next:
                if "error" in reply:
                    raise BrowserError(f"{method}: {reply['error']}")
                return reply.get("result", {})

    def wait_event(self, method: str):
        """Wait for the next event ``method`` (recorded events before this call count)."""
        until = time.monotonic() + self.timeout
        seen = len(self.events)
        for e in self.events[:seen]:
            if e.get("method") == method and not e.get("_used"):
                e["_used"] = True
                return e
        while True:
            try:
                e = self._pump(until)
            except queue.Empty:
                raise BrowserError(f"no {method} within {self.timeout} s") from None
            if e.get("method") == method:
                e["_used"] = True
                return e

    # -- page ------------------------------------------------------------------------------------
    def open(self, url: str):
        """Navigate and wait for the load event."""
        self.send("Page.navigate", session=True, url=url)
        self.wait_event("Page.loadEventFired")

    def evaluate(self, expression: str):
        """Value of a JavaScript expression (JSON-able) in the page."""
        r = self.send("Runtime.evaluate", session=True, expression=expression, returnByValue=True,
                      awaitPromise=True)
        if "exceptionDetails" in r:
            raise BrowserError(f"script failed: {r['exceptionDetails']}")
        return r["result"].get("value")

    def drag(self, x0, y0, x1, y1, steps: int = 8):
        """Press the left button at (x0, y0), move to (x1, y1), release (viewport CSS pixels)."""
        self.send("Input.dispatchMouseEvent", session=True, type="mouseMoved", x=x0, y=y0)
        self.send("Input.dispatchMouseEvent", session=True, type="mousePressed", x=x0, y=y0, button="left",
                  buttons=1, clickCount=1)
        for k in range(1, steps + 1):
            self.send("Input.dispatchMouseEvent", session=True, type="mouseMoved", x=x0 + (x1 - x0) * k / steps,
                      y=y0 + (y1 - y0) * k / steps, button="left", buttons=1)
        self.send("Input.dispatchMouseEvent", session=True, type="mouseReleased", x=x1, y=y1, button="left",
                  buttons=0, clickCount=1)

    def screenshot(self, path, full_page: bool = True) -> tuple[int, int]:
        """Write a PNG of the page (the whole page with ``full_page``); returns its (width, height) in px."""
        w, h = self.width, self.height
        if full_page:
            m = self.send("Page.getLayoutMetrics", session=True)
            size = m.get("cssContentSize") or m["contentSize"]
            w, h = self.width, int(size["height"]) + 1
            self.send("Emulation.setDeviceMetricsOverride", session=True, width=w, height=h, deviceScaleFactor=1,
                      mobile=False)
        data = self.send("Page.captureScreenshot", session=True, format="png", captureBeyondViewport=full_page)
        with open(path, "wb") as f:
            f.write(base64.b64decode(data["data"]))
        if full_page:
            self.send("Emulation.setDeviceMetricsOverride", session=True, width=self.width, height=self.height,
                      deviceScaleFactor=1, mobile=False)
        return w, h

    def drain(self, seconds: float = 0.3):
        """Collect the events that arrive within ``seconds`` (late console messages, requests)."""
        until = time.monotonic() + seconds
        while True:
            try:
                self._pump(until)
            except queue.Empty:
                return

    # -- what happened ---------------------------------------------------------------------------
    def console_problems(self) -> list[str]:
        """Console errors and warnings, uncaught exceptions and error/warning log entries (CSP violations,
        failed loads), one line each."""
        out = []
        for e in self.events:
            m, p = e.get("method"), e.get("params", {})
            if m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "warning", "assert"):
                out.append(f"console.{p['type']}: " + " ".join(str(a.get("value", a.get("description", "")))
                                                              for a in p.get("args", [])))
            elif m == "Runtime.exceptionThrown":
                d = p.get("exceptionDetails", {})
                out.append(f"exception: {d.get('text')} {d.get('exception', {}).get('description', '')}")
            elif m == "Log.entryAdded" and p.get("entry", {}).get("level") in ("error", "warning"):
                en = p["entry"]
                out.append(f"log {en.get('source')}/{en.get('level')}: {en.get('text')} {en.get('url', '')}")
        return out

    def requests(self) -> list[str]:
        """URL of every request the page made (``data:`` URLs included)."""
        return [e["params"]["request"]["url"] for e in self.events if e.get("method") == "Network.requestWillBeSent"]

    def _stderr(self) -> str:
        try:
            return (self.proc.stderr.read(4000) or b"").decode(errors="replace") if self.proc.poll() is not None else ""
        except Exception:  # noqa: BLE001
            return ""

    def close(self):
        try:
            if self.proc.poll() is None:
                try:
                    msg = {"id": self._next + 1, "method": "Browser.close", "params": {}}
                    self._out.write(json.dumps(msg).encode() + b"\0")
                except OSError:
                    pass
                try:
                    self.proc.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    self.proc.kill()
                    self.proc.wait(timeout=10)
        finally:
            for f in (self._out, self._in):
                try:
                    f.close()
                except OSError:
                    pass
            if self.proc.stderr:
                self.proc.stderr.close()
            shutil.rmtree(self._profile, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
