"""The explorer in a headless Chromium: what the browser tests and the
documentation's screenshots share.

Playwright for Python (``pip install playwright``, in the ``test`` extra)
drives the system's Chromium (``/usr/bin/chromium``, Debian's ``chromium``
package; ``$CHROMIUM`` names another) through ``executable_path``, with a
fresh profile each time. Nothing here downloads a browser: never run
``playwright install``.

    python -m mi_brdfs.tools.explore.browser -o docs/guide/explore   # the screenshots
"""
from __future__ import annotations

import argparse
import contextlib
import os
import re
import selectors
import shutil
import signal
import subprocess
import sys
import tempfile

from ...render.exr import atomic_path

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run",
         # WebGL in software (SwiftShader), which recent Chromium enables only when
         # asked: without it Plotly's 3-D lobe has no canvas to draw on.
         "--enable-unsafe-swiftshader"]
VIEWPORT = {"width": 1500, "height": 1000}
STARTUP_S = 120                 # the server's start: importing Mitsuba, loading the models


def chromium_path() -> str:
    path = os.environ.get("CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
    if not os.path.isfile(path):
        raise RuntimeError(f"no Chromium at {path}: apt-get install chromium, or set CHROMIUM")
    return path


class Server:
    """``mi-brdfs explore --no-browser`` in a process of its own (a context
    manager): ``url``, ``pid``; leaving stops it with SIGINT, as Ctrl-C does,
    and keeps its exit status and output in ``returncode``, ``stdout``,
    ``stderr``."""

    def __init__(self, *args: str):
        self.args = ["--port", "0", *args]
        self.url = self.pid = self.returncode = None
        self.stdout = self.stderr = ""

    def __enter__(self) -> "Server":
        env = {**os.environ, "PYTHONFAULTHANDLER": "1"}
        self.process = subprocess.Popen([sys.executable, "-m", "mi_brdfs", "explore",
                                         "--no-browser", *self.args], env=env,
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.pid = self.process.pid
        line = self._first_line()
        match = re.search(r"serving (http://\S+)", line)
        if not match:
            self.stop()
            raise RuntimeError(f"the explorer did not start: {line!r} {self.stderr[-2000:]}")
        self.url = match.group(1)
        return self

    def _first_line(self) -> str:
        with selectors.DefaultSelector() as sel:
            sel.register(self.process.stdout, selectors.EVENT_READ)
            if not sel.select(STARTUP_S):
                return ""
        return self.process.stdout.readline()

    def stop(self, timeout: float = 60.0) -> int:
        if self.returncode is None:
            if self.process.poll() is None:
                self.process.send_signal(signal.SIGINT)
            try:
                out, err = self.process.communicate(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.process.kill()
                out, err = self.process.communicate()
            self.stdout, self.stderr = self.stdout + out, self.stderr + err
            self.returncode = self.process.returncode
        return self.returncode

    def __exit__(self, *exc) -> None:
        self.stop()


@contextlib.contextmanager
def chromium(permissions: tuple[str, ...] = ("clipboard-read", "clipboard-write")):
    """A Playwright browser context on the system's Chromium, a fresh profile."""
    from playwright.sync_api import sync_playwright     # optional: the tests' extra
    with tempfile.TemporaryDirectory(prefix="explore-chromium-") as profile, \
            sync_playwright() as playwright:
        context = playwright.chromium.launch_persistent_context(
            profile, executable_path=chromium_path(), args=FLAGS, headless=True,
            viewport=VIEWPORT)
        try:
            context.grant_permissions(list(permissions))
            yield context
        finally:
            context.close()


def open_page(context, url: str, timeout_ms: float = 60_000, width: int | None = None):
    """The explorer's page, once both columns have drawn their plots and a
    preview image; ``width``: the window's, if not the context's."""
    page = context.new_page()
    if width:
        page.set_viewport_size({"width": width, "height": VIEWPORT["height"]})
    page.goto(url)
    for side in ("left", "right"):
        page.wait_for_selector(f".column[data-side={side}][data-plots]", timeout=timeout_ms)
        page.wait_for_function(f"document.querySelector('.column[data-side={side}] .preview')"
                               ".dataset.spp >= 64", timeout=timeout_ms)
    return page


def column(page, side: str):
    return page.locator(f".column[data-side={side}]")


def screenshot(target, path: str) -> None:
    """A screenshot of a page or a locator, written atomically."""
    with atomic_path(path) as tmp:
        target.screenshot(path=tmp)


# A drag as the slider reports it: an ``input`` event every 30 ms, the
# button held (no ``change``), the value swept to and fro.
DRAG = """() => { const s = document.querySelector(
      '.column[data-side=left] input[type=range][data-name=alpha]');
  let i = 0;
  window.__drag = setInterval(() => {
    s.value = 100 + 40 * Math.abs((i++ % 20) - 10);
    s.dispatchEvent(new Event('input', {bubbles: true}));
  }, 30); }"""


def screenshots(out_dir: str, width: int = 1280) -> list[str]:
    """The documentation's screenshots, in a window ``width`` px wide: the
    page as it opens (cook_torrance beside Mitsuba's gold roughconductor),
    in the middle of a drag of the left ``alpha`` slider, after "Fit left to
    right", and the left column in scan-line mode with a Phong model."""
    os.makedirs(out_dir, exist_ok=True)
    written = []

    def save(target, name):
        path = os.path.join(out_dir, name)
        screenshot(target, path)
        written.append(path)
    preview_done = ("document.querySelector('.column[data-side=left] .preview')"
                    ".dataset.spp >= 64")
    with Server() as server, chromium() as context:
        page = open_page(context, server.url, width=width)
        save(page, "page.png")
        drawn = column(page, "left").get_attribute("data-plots")
        page.evaluate(DRAG)
        page.wait_for_function("(n => document.querySelector('.column[data-side=left]')"
                               ".dataset.plots - n >= 20)", arg=int(drawn), timeout=120_000)
        save(page, "drag.png")                     # still moving
        page.evaluate("clearInterval(window.__drag)")
        page.wait_for_function(preview_done, timeout=60_000)
        page.click("#fit")
        page.wait_for_function("document.getElementById('status').textContent"
                               ".startsWith('fitted')", timeout=120_000)
        page.wait_for_function(preview_done, timeout=60_000)
        save(page, "fit.png")
        left = column(page, "left")
        left.locator("select.model").select_option("phong")
        left.locator("select.mode").select_option("scanline")
        page.wait_for_function("document.querySelector('.column[data-side=left] .title')"
                               ".textContent.startsWith('phong')")
        page.wait_for_function(preview_done, timeout=60_000)
        save(left, "scanline.png")
    return written


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m mi_brdfs.tools.explore.browser",
                                description="take the explore page's screenshots")
    p.add_argument("-o", "--output", required=True, help="the folder of the PNG files")
    args = p.parse_args(argv)
    for path in screenshots(args.output):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
