"""Sphinx configuration of the mi_brdfs documentation.

Build (the ``docs`` extra: ``pip install -e '.[docs]'``)::

    python -m sphinx -W -b html docs OUT

The plugin reference (with its renders), the command-line reference and the
results pages are generated from the code and the committed results at every
build (``docs/_ext``), into Sphinx's cache folder in OUT: the build writes
nothing into the source tree. Formulas are rendered by the MathJax that
``sphinx-mathjax-offline`` ships, copied into the site: no page loads anything
from the network.
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
    "sphinx-mathjax-offline",      # MathJax from the site itself (sets mathjax_path)
    "mi_brdfs_docs",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3
exclude_patterns = ["_build", "_generated", "benchmarks/**", "validation/**", "notebooks/**",
                    "Thumbs.db", ".DS_Store"]

# The API page lists what it names (docs/api.rst), nothing more: no default
# "members" that would add every helper of a module.
autodoc_member_order = "bysource"
autodoc_default_options = {}
autodoc_typehints = "description"
nitpicky = False

html_theme = "furo"
html_title = "mi_brdfs"
html_static_path = ["_static"]

# ``\text{brdf\_error}`` reads "brdf_error": MathJax's textmacros (shipped
# with the offline copy, loaded from the site like the rest of MathJax) lets
# text inside a formula take LaTeX's text-mode escapes.
mathjax3_config = {"loader": {"load": ["[tex]/textmacros"]},
                   "tex": {"packages": {"[+]": ["textmacros"]}}}
