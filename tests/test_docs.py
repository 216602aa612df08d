"""The documentation site: it builds with warnings as errors (the README's
command), each plugin page names every parameter and option of its plugin,
and the command-line page every command and every option of its parser."""
from __future__ import annotations

import argparse
import html
import os
import re
import subprocess
import sys

import pytest

from mi_brdfs.bsdfs import PLUGINS
from mi_brdfs.tools import cli

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> str:
    out = str(tmp_path_factory.mktemp("site"))
    run = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html",
                          os.path.join(ROOT, "docs"), out], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-4000:]
    return out


def text_of(site: str, page: str) -> str:
    with open(os.path.join(site, page), encoding="utf-8") as f:
        return html.unescape(re.sub(r"<[^>]+>", " ", f.read()))


def table_names(site: str, page: str) -> set[str]:
    """The names in the first column of the page's parameter table (code literals)."""
    with open(os.path.join(site, page), encoding="utf-8") as f:
        page_html = f.read()
    table = page_html.split("<table", 1)[1].split("</table>", 1)[0]
    rows = re.findall(r"<tr[^>]*>\s*<td[^>]*>(.*?)</td>", table, flags=re.S)
    return {html.unescape(re.sub(r"<[^>]+>", "", r)).strip() for r in rows}


@pytest.mark.parametrize("cls", PLUGINS, ids=lambda c: c.name)
def test_plugin_page_names_every_parameter_and_option(site, cls):
    names = table_names(site, f"_generated/plugins/{cls.name}.html")
    declared = {p.name for p in cls.PARAMS} | {o.name for o in cls.all_options()}
    assert declared <= names, f"missing from the page's table: {sorted(declared - names)}"


@pytest.mark.parametrize("cls", PLUGINS, ids=lambda c: c.name)
def test_help_shows_the_module_documentation(cls):
    """help(mi_brdfs.Phong) shows the module's documentation (its formulas and
    XML example; the parameter table is made from the declarations by the
    site's build), and every parameter and option says what it is."""
    doc = cls.__doc__
    assert doc.lstrip().startswith(f"``{cls.name}``") and ".. code-block:: xml" in doc
    for item in cls.PARAMS + cls.all_options():
        assert len(" ".join(item.doc.split())) > 20, item.name


def test_plugin_pages_show_renders_and_lobes(site):
    for cls in PLUGINS:
        page = open(os.path.join(site, f"_generated/plugins/{cls.name}.html"),
                    encoding="utf-8").read()
        for picture in (f"{cls.name}_scanline.png", f"{cls.name}_hdr.png", f"lobe_{cls.name}.png"):
            assert picture in page, (cls.name, picture)
            assert os.path.exists(os.path.join(site, "_images", picture)), picture


def _options(parser: argparse.ArgumentParser) -> list[str]:
    return [a.option_strings[-1] if a.option_strings else (a.metavar or a.dest) for a in parser._actions
            if not isinstance(a, (argparse._HelpAction, argparse._SubParsersAction))]


def test_cli_page_covers_every_command_and_option(site):
    page = text_of(site, "_generated/cli.html")
    top = cli.parser()
    commands = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
    for name, sub in commands.choices.items():
        assert f"mi-brdfs {name}" in page, name
        for option in _options(sub):
            assert option in page, (name, option)


def test_every_cli_argument_is_explained():
    """The reference is generated from the help strings: none may be missing."""
    top = cli.parser()
    commands = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
    missing = [(name, a.dest) for name, sub in commands.choices.items() for a in sub._actions
               if not isinstance(a, argparse._HelpAction) and not a.help]
    assert not missing


def test_benchmark_results_page_is_the_committed_run(site):
    import json
    with open(os.path.join(ROOT, "docs", "benchmarks", "results.json")) as f:
        results = json.load(f)
    page = text_of(site, "_generated/benchmarks.html")
    for group in results["groups"]:
        assert group in page
    assert f"{results['seconds']:.0f} s" in page
