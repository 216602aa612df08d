"""Sphinx configuration of the mi_brdfs documentation.

Build (the ``docs`` extra: ``pip install -e '.[docs]'``)::

    python -m sphinx -W -b html docs docs/_build/html

The plugin reference, the command-line reference and the benchmark results
are generated from the code and the committed results at every build
(``docs/_ext/mi_brdfs_docs.py``, into ``docs/_generated``).
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "_ext"))

from importlib import metadata  # noqa: E402

import mi_brdfs  # noqa: E402,F401  (LLVM set-up before drjit, as for every user)

project = "mi_brdfs"
author = "the mi_brdfs developers"
copyright = "2026, the mi_brdfs developers"
version = release = metadata.version("mi_brdfs")

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "mi_brdfs_docs",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3
exclude_patterns = ["_build", "benchmarks/**", "validation/**", "notebooks/**",
                    "Thumbs.db", ".DS_Store"]

autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "undoc-members": False}
autodoc_typehints = "description"
nitpicky = False

html_theme = "furo"
html_title = "mi_brdfs"
html_static_path = []
