"""The pages of the documentation that are generated from the code and the
committed results, never written by hand (a Sphinx extension).

- one page per BSDF plugin (``plugins/<name>``, :mod:`docs_plugins`): its
  module docstring with the parameter table made from its declarations, a
  Python example made from its XML example, notes, renders that vary its main
  parameter (made by this build, :mod:`docs_previews`), links to the related
  Mitsuba plugins, its lobe plot and its bundled scene;
- the command-line reference (``cli``, :mod:`docs_cli`), from the argparse
  parsers of :mod:`mi_brdfs.tools.cli`;
- the results (``results/...``, :mod:`docs_results`): the benchmark results,
  the validation report and the fit report, read from the committed results;
  the two reports' own HTML pages and pictures are copied into the site.

The build writes nothing into the source tree: the generated pages and the
renders go to ``mi_brdfs/`` in Sphinx's cache folder (``.doctrees`` of the
output folder), and Sphinx reads them from there as if they were source files
(:class:`GeneratedProject`). The renders are kept there between builds.
"""
from __future__ import annotations

import os
import shutil
from pathlib import Path

from sphinx.project import Project
from sphinx.util._pathlib import _StrPath

import docs_cli
import docs_plugins
import docs_results

DOCS = Path(__file__).resolve().parent.parent
ROOT = DOCS.parent
REPORTS = {"validation": DOCS / "validation",          # site folder -> committed report
           "trade": DOCS / "benchmarks" / "trade",
           "scene-fit": DOCS / "scene-fit"}       # fit --scene: one per scene


def write_if_changed(path: Path, text: str) -> None:
    """Write ``text`` unless the file holds it already (Sphinx re-reads a page
    whose file changed)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.exists() and path.read_text(encoding="utf-8") == text:
        return
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


class GeneratedProject(Project):
    """Sphinx's project (the documents it finds in the source folder) plus the
    generated pages, which live outside it (``generated``: docname -> file)."""

    generated: dict[str, Path] = {}

    def discover(self, exclude_paths=(), include_paths=("**",)) -> set[str]:
        docnames = super().discover(exclude_paths, include_paths)
        docnames.update(self.generated)
        return docnames

    def doc2path(self, docname: str, absolute: bool) -> _StrPath:
        if docname in self.generated:
            path = self.generated[docname]
            return _StrPath(path if absolute else f"{docname}{path.suffix}")
        return super().doc2path(docname, absolute)

    def path2doc(self, filename) -> str | None:
        for docname, path in self.generated.items():
            if Path(filename) == path:
                return docname
        return super().path2doc(filename)


def generate(app) -> None:
    """Write every generated page into the build's cache folder and let Sphinx
    find them there."""
    import mi_brdfs  # noqa: F401  (LLVM set-up, the variant, the plugins)
    work = Path(app.doctreedir) / "mi_brdfs"
    srcdir = Path(app.srcdir)
    pages = {**docs_plugins.pages(work, srcdir), "cli": (".rst", docs_cli.page()),
             **docs_results.pages(DOCS)}
    generated = {}
    for docname, (suffix, text) in pages.items():
        path = work / "pages" / f"{docname}{suffix}"
        write_if_changed(path, text)
        generated[docname] = path
    GeneratedProject.generated = generated
    app.project.__class__ = GeneratedProject


# the site's page that introduces a copied report: the report links back to it
# (the trade report's page is the fit helper's: it makes its own links)
BACK = {"validation": ("results/validation.html", "Validation report")}


def back_link(page_html: str, name: str) -> str:
    """A copied report's page with a line of links back into the site at its top."""
    target, title = BACK[name]
    line = (f"<p class='site-links' style='font-size: 0.9em'><a href='../../index.html'>"
            f"mi_brdfs documentation</a> › <a href='../../{target}'>{title}</a></p>\n")
    return page_html.replace("<body>\n", "<body>\n" + line, 1)


def copy_reports(app, error) -> None:
    """The committed reports (their HTML page and pictures) into the site, as
    ``reports/<name>/`` (the results pages link to them, and they link back)."""
    if error is None and app.builder.format == "html":
        for name, folder in REPORTS.items():
            site = Path(app.outdir) / "reports" / name
            shutil.copytree(folder, site, dirs_exist_ok=True)
            if name in BACK:
                index = site / "index.html"
                index.write_text(back_link(index.read_text(encoding="utf-8"), name),
                                 encoding="utf-8")


def setup(app):
    app.connect("builder-inited", generate)
    app.connect("build-finished", copy_reports)
    app.add_css_file("mi_brdfs.css")
    docs_results.setup(app)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
