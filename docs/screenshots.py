"""The site's screenshots shown in the guide "What the site looks like"
(docs/guide/site.md): the site built as the README says, three pages opened in
the system's Chromium (Debian's ``chromium``, through Playwright's
``executable_path``: nothing downloads a browser) in a window 1280 px wide,
the network off, MathJax done; each a window's height (1280 × 900) from
its top or from what it shows (the energy guide's residual map, the trade
report's first material),
written as a PNG of 256 colours, about 100 KB::

    python docs/screenshots.py              # writes docs/guide/site/*.png

The explorer's screenshots (at rest and mid-drag) are the explorer's own:
``python -m mi_brdfs.tools.explore.browser -o docs/guide/explore``.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile

DOCS = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(DOCS)
OUT = os.path.join(DOCS, "guide", "site")
WIDTH, HEIGHT = 1280, 900
# name: the page, and what to scroll to (a CSS selector) before the picture
SHOTS = {
    "energy": ("guide/energy.html", "figure:has(img[src$='groundtruth_residuals.png'])"),
    "plugin": ("plugins/cook_torrance.html", None),
    "trade": ("reports/trade/index.html", "h2[id]:not(#contents h2)"),
}


def build(out: str) -> None:
    """The site into ``out``, as the README builds it (warnings are errors)."""
    subprocess.run([sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html", DOCS, out],
                   check=True)


def small_png(source: str, path: str) -> None:
    """``source`` (a screenshot) as a PNG of at most 256 colours at ``path``,
    written atomically."""
    from PIL import Image
    image = Image.open(source).convert("RGB").quantize(256, method=Image.Quantize.MEDIANCUT)
    tmp = path + ".tmp"
    image.save(tmp, format="PNG", optimize=True)
    os.replace(tmp, path)


def screenshots(site: str, out_dir: str = OUT) -> list[str]:
    """The pages of :data:`SHOTS` of the site built in ``site``, into ``out_dir``."""
    sys.path.insert(0, ROOT)
    from mi_brdfs.tools.explore.browser import chromium
    os.makedirs(out_dir, exist_ok=True)
    written = []
    with tempfile.TemporaryDirectory() as tmp, chromium(permissions=()) as context:
        context.route("**/*", lambda r: r.continue_() if r.request.url.startswith(
            ("file://", "data:")) else r.abort())
        page = context.new_page()
        page.set_viewport_size({"width": WIDTH, "height": HEIGHT})
        for name, (target, anchor) in SHOTS.items():
            page.goto("file://" + os.path.join(site, target), wait_until="load")
            page.evaluate("() => window.MathJax && MathJax.startup && MathJax.startup.promise")
            page.wait_for_function("[...document.images].every(i => i.complete)")
            if anchor:
                page.evaluate("el => el.scrollIntoView({block: 'start', behavior: 'instant'})",
                              page.locator(anchor).first.element_handle())
            shot = os.path.join(tmp, f"{name}.png")
            page.screenshot(path=shot)
            path = os.path.join(out_dir, f"{name}.png")
            small_png(shot, path)
            written.append(path)
    return written


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python docs/screenshots.py",
                                     description="take the site's screenshots for its guide")
    parser.add_argument("-o", "--output", default=OUT, help="folder (default: docs/guide/site)")
    parser.add_argument("--site", default=None,
                        help="a site already built (default: build one in a temporary folder)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="mi-brdfs-site-") as tmp:
        site = args.site or tmp
        if not args.site:
            build(site)
        for path in screenshots(site, args.output):
            print(f"{path}: {os.path.getsize(path) // 1024} KB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
