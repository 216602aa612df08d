"""The pages of the documentation that are generated from the code, never written by hand.

- one page per BSDF plugin (``_generated/plugins/<name>.rst``): the plugin's
  module docstring, its ``.. parameters::`` line replaced by the table
  generated from ``PARAMS`` and the options (:func:`parameter_table`), its
  bundled scene, the scene's renders in both modes and its lobe plot from the
  committed validation report;
- the command-line reference (``_generated/cli.rst``), from the argparse
  parsers of :mod:`mi_brdfs.tools.cli`;
- the benchmark results (``_generated/benchmarks.md``), from the committed
  ``docs/benchmarks/results.json`` through the bench's own report writer.

The committed validation report (``docs/validation``) is copied into the built
site as it is, so the guide can link to it.
"""
from __future__ import annotations

import argparse
import inspect
import json
import os
import shutil
import textwrap

DOCS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ROOT = os.path.dirname(DOCS)
OUT = os.path.join(DOCS, "_generated")


def _write(path: str, text: str) -> None:
    """Write ``text`` unless the file already holds it (Sphinx rebuilds what changed)."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    if os.path.exists(path):
        with open(path, encoding="utf-8") as f:
            if f.read() == text:
                return
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)


def _image(path: str, alt: str, width: str | None = None) -> str:
    """An image directive for a file given relative to the repository's root."""
    lines = [f".. image:: /../{path}", f"   :alt: {alt}"]
    if width:
        lines.append(f"   :width: {width}")
    return "\n".join(lines)


# ----------------------------------------------------------------------------
#  The parameter table of each plugin's page, from its declarations
# ----------------------------------------------------------------------------

PARAMETERS = ".. parameters::"     # the line of a model's docstring that becomes its table
FORMS = {"spectrum": "float, rgb, spectrum or texture", "scalar": "float or texture",
         "float": "float"}


def _range(lo, hi) -> str:
    if lo is not None and hi is not None:
        return f" in [{lo:g}, {hi:g}]"
    if lo is not None:
        return f" >= {lo:g}"
    return f" <= {hi:g}" if hi is not None else ""


def _row(name: str, kind: str, doc: str, default: str) -> list[str]:
    lines = textwrap.wrap(" ".join(doc.split()), 66) or [""]
    return [f"   * - ``{name}``", f"     - {kind}", f"     - {lines[0]}",
            *(f"       {line}" for line in lines[1:]), f"     - {default}"]


def parameter_table(cls) -> str:
    """The reStructuredText table of a plugin's parameters and options, made
    from its declarations (``PARAMS``, the model's ``OPTIONS``, then the
    base's): the one source of the plugin's parameter documentation."""
    rows = [".. list-table::", "   :header-rows: 1", "   :widths: 20 20 50 10", "",
            "   * - Parameter", "     - Type", "     - Description", "     - Default"]
    for p in cls.PARAMS:
        kind = FORMS[p.kind] + _range(p.lo, p.hi) + " (∂)"
        rows += _row(p.name, kind, p.doc, "none" if p.optional else f"{p.default:g}")
    for o in cls.OPTIONS + tuple(o for o in cls.all_options() if o not in cls.OPTIONS):
        doc = o.doc
        if isinstance(o.default, bool):
            kind, default = "boolean", str(o.default).lower()
        elif isinstance(o.default, int):
            kind, default = "integer" + _range(o.lo, o.hi), str(o.default)
        else:
            kind, default = "string", f'``"{o.default}"``'
            doc += " One of " + ", ".join(f'``"{c}"``' for c in o.choices) + "."
        rows += _row(o.name, kind, doc, default)
    return "\n".join(rows)


# ----------------------------------------------------------------------------
#  Plugins
# ----------------------------------------------------------------------------

def plugin_page(cls) -> str:
    module = inspect.getmodule(cls)
    name = cls.name
    doc = inspect.getdoc(module).strip().replace(PARAMETERS, parameter_table(cls))
    parts = [f".. _plugin-{name}:", "", doc, ""]
    renders = [f"scenes/renders/{name}_{mode}.png" for mode in ("scanline", "hdr")]
    if all(os.path.exists(os.path.join(ROOT, r)) for r in renders):
        parts += ["Renders", "-------", "",
                  f"The bundled scene ``{name}`` (``mi-brdfs render {name} -D mode=MODE``), "
                  "scan-line mode on the left, hdr mode on the right "
                  "(``sh scenes/renders/make.sh`` makes them):", "",
                  ".. list-table::", "   :class: renders", "",
                  "   * - " + textwrap.indent(_image(renders[0], f"{name}, scanline"),
                                              "       ").lstrip(),
                  "     - " + textwrap.indent(_image(renders[1], f"{name}, hdr"),
                                              "       ").lstrip(), ""]
    lobe = f"docs/validation/lobe_{name}.png"
    if os.path.exists(os.path.join(ROOT, lobe)):
        parts += ["Lobes", "-----", "",
                  "Polar plots of the lobe in the plane of incidence, both modes "
                  "(from the committed :doc:`validation report </guide/validation>`):", "",
                  _image(lobe, f"{name} lobes"), ""]
    scene = f"scenes/{name}.xml"
    if os.path.exists(os.path.join(ROOT, scene)):
        parts += ["Scene", "-----", "",
                  f"``{scene}``, bundled: ``mi_brdfs.scenes.path(\"{name}\")``.", "",
                  f".. literalinclude:: /../{scene}", "   :language: xml", ""]
    return "\n".join(parts)


def plugin_pages() -> list[str]:
    from mi_brdfs.bsdfs import PLUGINS
    names = []
    for cls in PLUGINS:
        _write(os.path.join(OUT, "plugins", f"{cls.name}.rst"), plugin_page(cls))
        names.append(cls.name)
    index = ["BSDF plugins", "============", "",
             "One page per plugin, in the lecture's order (diffuse models, then specular "
             "ones). Each page is generated from the plugin's module: its parameter "
             "declarations and its formulas.", "",
             ".. toctree::", "   :maxdepth: 1", "", *(f"   {n}" for n in names), ""]
    _write(os.path.join(OUT, "plugins", "index.rst"), "\n".join(index))
    return names


# ----------------------------------------------------------------------------
#  The command line
# ----------------------------------------------------------------------------

def _subcommands(parser: argparse.ArgumentParser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help for a in action._choices_actions}
            for name, sub in action.choices.items():
                yield name, sub, helps.get(name, "")


def _argument_rows(parser: argparse.ArgumentParser) -> list[tuple[str, str]]:
    rows = []
    for a in parser._actions:
        if isinstance(a, argparse._HelpAction):
            continue
        if a.option_strings:
            flag = ", ".join(a.option_strings)
            if a.nargs != 0:
                flag += " " + (a.metavar or a.dest.upper())
        else:
            flag = a.metavar or a.dest
            if a.nargs in ("+", "*"):
                flag += " ..."
        text = " ".join((a.help or "").split())
        if a.choices and not isinstance(a, argparse._SubParsersAction):
            text += " One of: " + ", ".join(f"``{c}``" for c in a.choices) + "."
        if a.required and a.option_strings:
            text += " Required."
        rows.append((flag, text))
    return rows


def _table(rows: list[tuple[str, str]]) -> list[str]:
    lines = [".. list-table::", "   :header-rows: 1", "   :widths: 30 70", "",
             "   * - Argument", "     - Meaning"]
    for flag, text in rows:
        lines += [f"   * - ``{flag}``", f"     - {text}"]
    return lines + [""]


def cli_page() -> str:
    from mi_brdfs.tools import cli
    top = cli.parser()
    lines = ["Command line: ``mi-brdfs``", "==========================", "",
             inspect.getdoc(cli).split("\n\n")[0].replace("\n", " "), "",
             "Every command checks its numbers and paths before it starts; an error is "
             "one line, ``mi-brdfs COMMAND: error: ...``, and exit status 1. Generated "
             "from the command's own parsers (``mi_brdfs/tools/cli.py``).", "",
             ".. code-block:: text", "",
             textwrap.indent(top.format_usage().strip(), "   "), ""]
    lines += _table(_argument_rows(top)[:1])          # --version
    for name, sub, short in _subcommands(top):
        title = f"``mi-brdfs {name}``"
        lines += [title, "-" * len(title), "", (short[0].upper() + short[1:] + ".") if short
                  else "", ""]
        if sub.description:
            lines += [" ".join(sub.description.split()), ""]
        usage = sub.format_usage().replace("usage: ", "").strip()
        lines += [".. code-block:: text", "", textwrap.indent(usage, "   "), ""]
        lines += _table(_argument_rows(sub))
    return "\n".join(lines)


# ----------------------------------------------------------------------------
#  Benchmark results
# ----------------------------------------------------------------------------

def benchmarks_page() -> str:
    from mi_brdfs.tools.bench import report
    from mi_brdfs.tools.bench.groups import GROUPS
    with open(os.path.join(DOCS, "benchmarks", "results.json")) as f:
        results = json.load(f)
    about = {name: g.about for name, g in GROUPS.items()}
    text = report.markdown(results, about, images="../benchmarks/")
    return text.replace("# mi-brdfs bench results", "# Benchmark results", 1)


# ----------------------------------------------------------------------------
#  Sphinx
# ----------------------------------------------------------------------------

def generate(app) -> None:
    import mi_brdfs  # noqa: F401  (LLVM set-up, variant, plugins)
    plugin_pages()
    _write(os.path.join(OUT, "cli.rst"), cli_page())
    _write(os.path.join(OUT, "benchmarks.md"), benchmarks_page())


def copy_validation(app, error) -> None:
    if error is None and app.builder.format == "html":
        target = os.path.join(app.outdir, "validation")
        shutil.copytree(os.path.join(DOCS, "validation"), target, dirs_exist_ok=True)


def setup(app):
    app.connect("builder-inited", generate)
    app.connect("build-finished", copy_validation)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
