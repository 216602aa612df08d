"""The documentation site, built once per test process as the README says
(``python -m sphinx -W -b html docs OUT``, warnings are errors), for the tests
that read it (test_docs.py) and the ones that open it in Chromium
(test_site_browser.py): whichever runs first builds it, the other reuses it.
The folder is removed when the process ends."""
from __future__ import annotations

import atexit
import functools
import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOCS = os.path.join(ROOT, "docs")
UNTRACKED = {".git", ".venv", "__pycache__", ".pytest_cache", "mi_brdfs.egg-info"}


@dataclass
class Build:
    out: str
    changed: list[str]          # files of the source tree the build created or modified
    error: str = ""             # the build's stderr when it failed


def tree_state() -> dict[str, tuple[int, int]]:
    """Every file of the checkout (but Git's, the venv's and caches): mtime, size."""
    state = {}
    for folder, subfolders, files in os.walk(ROOT):
        subfolders[:] = [d for d in subfolders if d not in UNTRACKED]
        for name in files:
            path = os.path.join(folder, name)
            st = os.stat(path)
            state[path] = (st.st_mtime_ns, st.st_size)
    return state


@functools.cache
def build() -> Build:
    out = tempfile.mkdtemp(prefix="mi-brdfs-site-")
    atexit.register(shutil.rmtree, out, ignore_errors=True)
    before = tree_state()
    run = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html", DOCS, out],
                         capture_output=True, text=True)
    after = tree_state()
    return Build(out, sorted(p for p in after if before.get(p) != after[p]),
                 "" if run.returncode == 0 else run.stderr[-4000:] or f"status {run.returncode}")


def pages(site: str) -> list[str]:
    """Every HTML page of the site, the copied reports included."""
    import glob
    return sorted(os.path.relpath(p, site) for p in glob.glob(os.path.join(site, "**", "*.html"),
                                                              recursive=True)
                  if "/_sources/" not in p)
