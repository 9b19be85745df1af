"""Open pages in headless Chromium and say what a reader would see go wrong.

    python -m silbridge.tools.docs.page_check URL [URL ...] [--screenshot FILE.png]

For each page: its title, how many elements it has and how much text, every <img> with its
natural width (0: it did not load), and every console error, uncaught exception and failed
resource load the browser logged while the page loaded. `--screenshot` keeps the first
screen of the first page as PNG.

Chromium (Debian's `chromium`; tools/install_sysdeps.sh installs it) is driven through its
DevTools protocol over a WebSocket: `--remote-debugging-port=0` lets it pick a free port,
which it announces on stderr; the `websockets` package (test extras) speaks to it. The
browser gets a fresh profile in a temporary folder and is stopped when the session closes.
"""

from __future__ import annotations

import argparse
import base64
import contextlib
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
VIEWPORT = (1280, 800)           # the first screen of a laptop-sized window, CSS pixels
START_TIMEOUT_S = 30.0
LOAD_TIMEOUT_S = 30.0
SETTLE_MS = 300                  # after load: scripts that run on a timer get to fail too
_DEVTOOLS_LINE = re.compile(r"DevTools listening on (ws://\S+)")

# Every image, once the ones still loading have finished or failed.
_IMAGES_JS = """
(async () => {
  const imgs = Array.from(document.images);
  await Promise.all(imgs.map(i => i.complete ? null :
      new Promise(r => { i.addEventListener('load', r); i.addEventListener('error', r); })));
  return imgs.map(i => ({src: i.currentSrc || i.src, width: i.naturalWidth}));
})()
"""


class BrowserError(Exception):
    user_facing = True


def find_chromium() -> str | None:
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    return None


@dataclass
class PageReport:
    url: str
    title: str = ""
    elements: int = 0
    text_chars: int = 0
    images: list = field(default_factory=list)        # [{"src", "width"}]
    errors: list = field(default_factory=list)        # console errors, exceptions, failed loads

    @property
    def broken_images(self) -> list:
        return [i["src"] for i in self.images if not i["width"]]


class Browser:
    """One headless Chromium and a DevTools connection to its first tab."""

    def __init__(self, binary: str | None = None):
        from websockets.sync.client import connect

        binary = binary or find_chromium()
        if binary is None:
            raise BrowserError("no Chromium found: install Debian's `chromium` package "
                               "(tools/install_sysdeps.sh does, as root)")
        self._profile = tempfile.mkdtemp(prefix="silbridge-chromium-")
        self._stack = contextlib.ExitStack()        # the WebSocket, once open
        argv = [binary, "--headless=new", "--remote-debugging-port=0",
                f"--user-data-dir={self._profile}", "--no-first-run",
                "--no-default-browser-check", "--disable-gpu", "--disable-extensions",
                "--disable-dev-shm-usage", "--hide-scrollbars",
                f"--window-size={VIEWPORT[0]},{VIEWPORT[1]}",
                "about:blank"]
        if os.geteuid() == 0:
            argv.insert(1, "--no-sandbox")     # Chromium refuses to start as root otherwise
        self._proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                      text=True)
        try:
            browser_ws = self._devtools_url()
            self._ws = self._stack.enter_context(
                connect(self._page_ws(browser_ws), max_size=None, open_timeout=10))
        except BaseException:
            self.close()
            raise
        self._next_id = 0
        self._events: list[dict] = []
        for domain in ("Page", "Runtime", "Log"):
            self.call(f"{domain}.enable")
        self.call("Emulation.setDeviceMetricsOverride", width=VIEWPORT[0], height=VIEWPORT[1],
                  deviceScaleFactor=1, mobile=False)

    def _devtools_url(self) -> str:
        """The browser's WebSocket address, as Chromium prints it on stderr at start."""
        found: list[str] = []
        seen: list[str] = []

        def read() -> None:
            for line in self._proc.stderr:
                seen.append(line)
                m = _DEVTOOLS_LINE.search(line)
                if m:
                    found.append(m.group(1))
                    break
            # keep draining so Chromium never blocks on a full pipe
            for _line in self._proc.stderr:
                pass

        threading.Thread(target=read, daemon=True).start()
        end = time.monotonic() + START_TIMEOUT_S
        while not found and time.monotonic() < end and self._proc.poll() is None:
            time.sleep(0.05)
        if not found:
            raise BrowserError("Chromium did not announce its DevTools port: "
                               + " | ".join(s.strip() for s in seen[-5:]))
        return found[0]

    @staticmethod
    def _page_ws(browser_ws: str) -> str:
        """The first tab's WebSocket, from the browser's /json/list on the same port."""
        import urllib.request

        host = browser_ws.split("/")[2]
        end = time.monotonic() + START_TIMEOUT_S
        while True:
            with urllib.request.urlopen(f"http://{host}/json/list", timeout=5) as r:
                pages = [t for t in json.load(r) if t.get("type") == "page"]
            if pages:
                return pages[0]["webSocketDebuggerUrl"]
            if time.monotonic() > end:
                raise BrowserError("Chromium opened no tab")
            time.sleep(0.1)

    def call(self, method: str, **params) -> dict:
        """One DevTools command; events that arrive meanwhile are kept for check()."""
        self._next_id += 1
        my_id = self._next_id
        self._ws.send(json.dumps({"id": my_id, "method": method, "params": params}))
        while True:
            msg = json.loads(self._ws.recv(timeout=LOAD_TIMEOUT_S))
            if msg.get("id") == my_id:
                if "error" in msg:
                    raise BrowserError(f"{method}: {msg['error'].get('message')}")
                return msg.get("result", {})
            if "method" in msg:
                self._events.append(msg)

    def _wait_event(self, method: str) -> None:
        end = time.monotonic() + LOAD_TIMEOUT_S
        while not any(e["method"] == method for e in self._events):
            left = end - time.monotonic()
            if left <= 0:
                raise BrowserError(f"no {method} within {LOAD_TIMEOUT_S:g} s")
            msg = json.loads(self._ws.recv(timeout=left))
            if "method" in msg:
                self._events.append(msg)

    def evaluate(self, expression: str):
        r = self.call("Runtime.evaluate", expression=expression, awaitPromise=True,
                      returnByValue=True)
        if "exceptionDetails" in r:
            raise BrowserError(f"page script failed: {r['exceptionDetails'].get('text')}")
        return r["result"].get("value")

    def check(self, url: str) -> PageReport:
        """Load url, wait for its load event and its images, and report."""
        self._events.clear()
        nav = self.call("Page.navigate", url=url)
        if nav.get("errorText"):
            return PageReport(url, errors=[f"navigation failed: {nav['errorText']}"])
        self._wait_event("Page.loadEventFired")
        rep = PageReport(url)
        rep.images = self.evaluate(_IMAGES_JS) or []
        rep.title = self.evaluate("document.title") or ""
        rep.elements = int(self.evaluate("document.getElementsByTagName('*').length") or 0)
        rep.text_chars = len(self.evaluate("document.body ? document.body.innerText : ''")
                             or "")
        self.evaluate(f"new Promise(r => setTimeout(r, {SETTLE_MS}))")
        rep.errors = _errors(self._events)
        return rep

    def screenshot(self, path: str) -> str:
        """The current page's first screen (the viewport), as PNG."""
        data = self.call("Page.captureScreenshot", format="png")["data"]
        with open(path, "wb") as fh:
            fh.write(base64.b64decode(data))
        return path

    def close(self) -> None:
        self._stack.close()
        if self._proc.poll() is None:
            self._proc.terminate()
            try:
                self._proc.wait(10)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        shutil.rmtree(self._profile, ignore_errors=True)

    def __enter__(self) -> Browser:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _errors(events: list[dict]) -> list[str]:
    """Console errors, uncaught exceptions and the browser's own error log lines (a 404 image,
    a blocked script) among the DevTools events."""
    out = []
    for e in events:
        p = e.get("params", {})
        if e["method"] == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            out.append("console: " + " ".join(str(a.get("value", a.get("description", "")))
                                              for a in p.get("args", [])))
        elif e["method"] == "Runtime.exceptionThrown":
            d = p.get("exceptionDetails", {})
            out.append("exception: " + str((d.get("exception") or {}).get("description")
                                           or d.get("text")))
        elif e["method"] == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
            entry = p["entry"]
            out.append(f"{entry.get('source')}: {entry.get('text')} {entry.get('url', '')}"
                       .strip())
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m silbridge.tools.docs.page_check",
                                description=__doc__.split("\n\n")[0])
    p.add_argument("urls", nargs="+", metavar="URL")
    p.add_argument("--screenshot", default=None, metavar="FILE.png",
                   help="keep the first page's first screen here")
    args = p.parse_args(argv)
    bad = 0
    with Browser() as browser:
        for i, url in enumerate(args.urls):
            rep = browser.check(url)
            if i == 0 and args.screenshot:
                browser.screenshot(args.screenshot)
            problems = rep.errors + [f"image not loaded: {s}" for s in rep.broken_images]
            bad += bool(problems) or not rep.title
            print(f"{url}: {rep.title!r}, {rep.elements} elements, {len(rep.images)} images"
                  + "".join(f"\n  {x}" for x in problems))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
