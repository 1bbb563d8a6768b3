"""Debian's Chromium, headless, driven through the DevTools protocol over its pipe
(--remote-debugging-pipe: commands on fd 3, replies and events on fd 4, each a JSON text ended by
a NUL byte), with the network off. Shared by the viewer's tests (tests/cli/view_*.py).
"""
import base64
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

SKIP = 77  # ctest's SKIP_RETURN_CODE for these tests


def chromium_or_skip():
    """Chromium's path; exits with SKIP and one line where it is not installed."""
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    print("SKIP: Chromium is not installed (apt-get install -y chromium; "
          "scripts/install-deps.sh installs it)")
    sys.exit(SKIP)


class Browser:
    """One headless Chromium with one page, the network off; every console error, uncaught
    exception and request that is not file:, data: or blob: is recorded."""

    def __init__(self, width, height, extra_args=()):
        self.profile = tempfile.mkdtemp(prefix="fd-chromium-")
        to_chrome_r, self.to_chrome = os.pipe()
        self.from_chrome, from_chrome_w = os.pipe()

        def pipes():  # the child's fds 3 and 4 (through fresh copies: a pipe may be 3 or 4)
            reader, writer = os.dup(to_chrome_r), os.dup(from_chrome_w)
            os.dup2(reader, 3)
            os.dup2(writer, 4)

        args = [chromium_or_skip(), "--headless", "--remote-debugging-pipe",
                f"--user-data-dir={self.profile}", "--no-first-run", "--no-default-browser-check",
                "--disable-extensions", "--disable-background-networking", "--disable-sync",
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                "--host-resolver-rules=MAP * ~NOTFOUND", "--proxy-server=127.0.0.1:9",
                "--hide-scrollbars", *extra_args, "about:blank"]
        if os.geteuid() == 0:
            args.insert(2, "--no-sandbox")  # Chromium's sandbox refuses to run as root
        self.process = subprocess.Popen(args, preexec_fn=pipes, close_fds=False,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_chrome_r)
        os.close(from_chrome_w)
        self.buffer = b""
        self.next_id = 0
        self.errors, self.requests = [], []
        self.events = []
        targets = self.call("Target.getTargets")["targetInfos"]
        page = next(t for t in targets if t["type"] == "page")
        self.session = self.call("Target.attachToTarget", targetId=page["targetId"],
                                 flatten=True)["sessionId"]
        for domain in ("Runtime", "Log", "Page", "Network"):
            self.call(f"{domain}.enable", session=True)
        self.resize(width, height)

    def resize(self, width, height):
        """The page's size in CSS pixels (a browser can serve several pages of several sizes:
        starting Chromium costs more than a page)."""
        self.call("Emulation.setDeviceMetricsOverride", session=True, width=width,
                  height=height, deviceScaleFactor=1, mobile=False)

    def _read(self, timeout):
        deadline = time.monotonic() + timeout
        while b"\0" not in self.buffer:
            if time.monotonic() > deadline:
                raise TimeoutError("Chromium did not answer")
            chunk = os.read(self.from_chrome, 1 << 20)
            if not chunk:
                raise RuntimeError("Chromium closed its pipe")
            self.buffer += chunk
        message, _, self.buffer = self.buffer.partition(b"\0")
        return json.loads(message)

    def _record(self, message):
        method, params = message.get("method"), message.get("params", {})
        if method == "Runtime.consoleAPICalled" and params["type"] in ("error", "assert"):
            self.errors.append(" ".join(str(a.get("value", a.get("description")))
                                        for a in params["args"]))
        elif method == "Runtime.exceptionThrown":
            d = params["exceptionDetails"]
            self.errors.append(d.get("exception", {}).get("description", d.get("text")))
        elif method == "Log.entryAdded" and params["entry"]["level"] == "error":
            self.errors.append(params["entry"]["text"])
        elif method == "Network.requestWillBeSent":
            self.requests.append(params["request"]["url"])
        self.events.append(method)

    def offline_problem(self):
        """Why the page is not a self-contained offline page (a console error, a request beyond
        file:, data: and blob:), or None."""
        if self.errors:
            return f"console errors: {self.errors}"
        foreign = [u for u in self.requests if not u.startswith(("file:", "data:", "blob:"))]
        if foreign:
            return f"the page asked the network for {foreign}"
        return None

    def call(self, method, session=False, timeout=30, **params):
        self.next_id += 1
        message = {"id": self.next_id, "method": method, "params": params}
        if session:
            message["sessionId"] = self.session
        os.write(self.to_chrome, json.dumps(message).encode() + b"\0")
        while True:
            reply = self._read(timeout)
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply["result"]
            self._record(reply)

    def evaluate(self, expression):
        result = self.call("Runtime.evaluate", session=True, expression=expression,
                           returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression}: {result['exceptionDetails']}")
        return result["result"].get("value")

    def open(self, path, timeout=30):
        """Loads a file and waits until the page says it is ready. The document being left is
        marked first: a page opened before in this browser says it is ready too."""
        self.evaluate("window.fdLeft = true")
        self.call("Page.navigate", session=True, url="file://" + os.path.abspath(path))
        deadline = time.monotonic() + timeout
        while not self._ready():
            if time.monotonic() > deadline:
                raise TimeoutError(f"{path}: the page never became ready; errors: {self.errors}")
            time.sleep(0.05)

    def _ready(self):
        try:
            return self.evaluate("!window.fdLeft && !!(window.featherdrive && "
                                 "window.featherdrive.ready)")
        except RuntimeError:  # the context went away under the call: the navigation's commit
            return False

    def screenshot(self):
        """The page as it is now: an (H, W, 3) uint8 array."""
        from PIL import Image
        # Two animation frames, so that the compositor shows what the last call drew.
        self.evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
        png = base64.b64decode(self.call("Page.captureScreenshot", session=True,
                                         format="png")["data"])
        return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))

    def close(self):
        try:
            self.call("Browser.close", timeout=5)
        except (RuntimeError, TimeoutError, OSError):
            pass
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        os.close(self.to_chrome)
        os.close(self.from_chrome)
        shutil.rmtree(self.profile, ignore_errors=True)


def project(point, view, projection, viewport):
    """Where three.js draws a world point: column-major 4x4 view and projection matrices (the
    page's), viewport [left, top, width, height] in CSS pixels; returns (x, y) page pixels."""
    V = np.asarray(view, dtype=float).reshape(4, 4).T
    P = np.asarray(projection, dtype=float).reshape(4, 4).T
    clip = P @ V @ np.append(np.asarray(point, dtype=float), 1.0)
    ndc = clip[:3] / clip[3]
    left, top, width, height = viewport
    return left + (ndc[0] + 1) / 2 * width, top + (1 - ndc[1]) / 2 * height


def pixels_of(image, rgb, tolerance=8):
    """(x, y) of the pixels within `tolerance` of the colour rgb in every channel."""
    mask = np.all(np.abs(image.astype(int) - np.array(rgb)) <= tolerance, axis=2)
    ys, xs = np.nonzero(mask)
    return xs, ys
