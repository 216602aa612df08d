"""Every page of the documentation site, the copied reports included, in
Chromium at 1280 px with the network off, as a reader sees it: nothing leaves
the machine, no image is missing, the page is no wider than the window and
nothing is cut at the column's edge (a wide table or code block scrolls in a
box of its own, a plain-text formula needs no scroll bar), no raw Sphinx role
(``:func:`x```) or LaTeX escape (``\\_``) shows as text, and every page
whose source holds maths has it typeset by the site's own MathJax.

The browser is the system's Chromium (Debian's ``chromium``) driven by
Playwright through ``executable_path`` (mi_brdfs/tools/explore/browser.py):
nothing here downloads a browser. The site is the one test_docs.py reads
(``sitebuild``: built once per process)."""
from __future__ import annotations

import os
import re
import shutil

import pytest

pytest.importorskip("playwright")
if not shutil.which("chromium") and not os.environ.get("CHROMIUM"):
    pytest.skip("no system Chromium (apt-get install chromium)", allow_module_level=True)

import sitebuild                                       # noqa: E402

from mi_brdfs.bsdfs import PLUGINS                     # noqa: E402

WIDTH = 1280
SCREENSHOTS = {"landing": "index.html", "plugin": "plugins/cook_torrance.html",
               "guide": "guide/fit.html", "energy": "guide/energy.html",
               "validation": "reports/validation/index.html"}

# What a page holds once drawn. ``cut``: an element of the text column that
# reaches past the column's right edge outside a box that scrolls sideways,
# or whose content its box clips; headings are left out (their ¶ link sits
# past the edge, hidden). ``wide_pre``: literal blocks that need a scroll bar.
MEASURE = r"""() => {
    const column = document.querySelector('article') || document.body;
    const right = column.getBoundingClientRect().right;
    const cut = [];
    const parts = 'p, li, pre, table, th, td, img, figure, svg, div.math, mjx-container, '
                  + 'div.highlight';
    for (const el of column.querySelectorAll(parts)) {
        const style = getComputedStyle(el);
        if (['hidden', 'clip'].includes(style.overflowX) && el.scrollWidth > el.clientWidth + 1)
            cut.push('clipped ' + el.tagName + ': ' + el.textContent.trim().slice(0, 50));
        if (el.getBoundingClientRect().right <= right + 1) continue;
        let box = el.parentElement, scrolls = false;
        for (; box && box !== column.parentElement; box = box.parentElement) {
            const o = getComputedStyle(box).overflowX;
            if (['auto', 'scroll'].includes(o)) { scrolls = true; break; }
            if (['hidden', 'clip'].includes(o)) break;
        }
        if (!scrolls)
            cut.push('past the edge ' + el.tagName + ': ' + el.textContent.trim().slice(0, 50));
    }
    return {
        width: document.documentElement.scrollWidth, view: innerWidth,
        missing: [...document.images].filter(i => !i.complete || !i.naturalWidth)
                                     .map(i => i.getAttribute('src')),
        math_sources: document.querySelectorAll('.math').length,
        typeset: document.querySelectorAll('mjx-container').length,
        mathjax: !!(window.MathJax && MathJax.startup),
        // plain literal blocks (no language: formulas, quoted text) that need a scroll bar
        wide_pre: [...column.querySelectorAll('.highlight-none pre, .highlight-default pre')]
                  .filter(p => p.scrollWidth > p.clientWidth + 1)
                  .map(p => p.textContent.slice(0, 50)),
        text: document.body.innerText,
        // the text but code blocks and literals, which show code; a formula's
        // text as MathJax shows it is its MathML copy (its glyphs are CSS)
        prose: (() => {
            const clone = document.body.cloneNode(true);
            clone.querySelectorAll('pre, code, script, style').forEach(e => e.remove());
            return clone.textContent;
        })(),
        cut: cut,
    };
}"""
WIDE_TABLES = """() => [...document.querySelectorAll('article table')].map(t => {
    let box = t.parentElement, scrolls = false;
    for (; box && box.tagName !== 'ARTICLE'; box = box.parentElement)
        if (['auto', 'scroll'].includes(getComputedStyle(box).overflowX)
            && box.scrollWidth > box.clientWidth) scrolls = true;
    return {wide: t.getBoundingClientRect().width > t.closest('article').clientWidth + 1,
            scrolls: scrolls};
})"""
# The renders of a plugin page (Mitsuba's matpreview style): each figure's
# image (its pixels and its size on the page), alt text and caption.
PREVIEWS = """() => [...document.querySelectorAll('div.matpreview figure')].map(f => {
    const img = f.querySelector('img'), caption = f.querySelector('figcaption');
    return {alt: img ? img.getAttribute('alt') : '', natural: img ? img.naturalWidth : 0,
            shown: img ? img.getBoundingClientRect().width : 0,
            caption: caption ? caption.innerText.trim() : ''};
})"""
ROLE = re.compile(r":(?:func|mod|class|meth|data|attr|obj|exc|doc|ref|math|term|py:\w+):`")
TEX = re.compile(r"\\_|\\(?:frac|operatorname|mathrm|text|cdot|sqrt|begin)\{|\$\$|\\\(|\\\[")


@pytest.fixture(scope="module")
def site() -> str:
    built = sitebuild.build()
    assert not built.error, built.error
    return built.out


@pytest.fixture(scope="module")
def browsed(site, tmp_path_factory):
    """Every page at 1280 px in the system's Chromium, MathJax done, every
    request outside the site's files refused and recorded."""
    from mi_brdfs.tools.explore.browser import chromium
    shots = tmp_path_factory.mktemp("screenshots")
    outside, seen = [], {}

    def route(r):
        if r.request.url.startswith(("file://", "data:")):
            r.continue_()
        else:
            outside.append(r.request.url)
            r.abort()
    with chromium(permissions=()) as context:
        context.route("**/*", route)
        page = context.new_page()
        page.set_viewport_size({"width": WIDTH, "height": 900})
        for name in sitebuild.pages(site):
            page.goto("file://" + os.path.join(site, name), wait_until="load")
            page.evaluate("() => window.MathJax && MathJax.startup && MathJax.startup.promise")
            seen[name] = page.evaluate(MEASURE)
            seen[name]["tables"] = page.evaluate(WIDE_TABLES)
            seen[name]["previews"] = page.evaluate(PREVIEWS)
            for shot, target in SCREENSHOTS.items():
                if name == target:
                    page.screenshot(path=str(shots / f"{shot}.png"), full_page=True)
    return seen, outside, shots


def bad(seen: dict, key: str) -> dict:
    return {page: s[key] for page, s in seen.items() if s[key]}


def test_nothing_is_loaded_from_the_network(browsed):
    seen, outside, _ = browsed
    assert len(seen) > 30 and not outside, outside[:5]


def test_every_image_is_there(browsed):
    seen, _, _ = browsed
    assert bad(seen, "missing") == {}
    assert len(seen["plugins/cook_torrance.html"]["text"]) > 1000


@pytest.mark.parametrize("cls", PLUGINS, ids=lambda c: c.name)
def test_plugin_renders_are_large_captioned_figures(browsed, cls):
    """Every plugin page shows its renders as Mitsuba's pages do: captioned
    figures with alt text, drawn at least 200 px wide at 1280 px (the 128²
    renders of before were 128 px), from images of 256² pixels; the
    cook_torrance page adds gold under the three Fresnel forms."""
    seen, _, _ = browsed
    figures = seen[f"plugins/{cls.name}.html"]["previews"]
    assert len(figures) >= 6, figures                  # a sweep of 3 values, both modes
    for f in figures:
        assert f["alt"].startswith(cls.name + ",") and f["caption"], f
        assert f["natural"] >= 256 and f["shown"] >= 200, f
    gold = [f for f in figures if ", gold, " in f["alt"]]
    if cls.name == "cook_torrance":
        assert [f["alt"].rsplit(" ", 1)[-1] for f in gold] == ["schlick", "f82", "conductor"]
        assert "lecture" in gold[0]["caption"] and "Au" in gold[2]["caption"]
    else:
        assert gold == []


def test_no_page_is_wider_than_the_window(browsed):
    seen, _, _ = browsed
    assert {p: s["width"] for p, s in seen.items() if s["width"] > s["view"]} == {}


def test_nothing_is_cut_at_the_column_edge(browsed):
    """Every element of the text column ends inside it or scrolls in its own
    box; none clips its content (a formula, a table cell)."""
    seen, _, _ = browsed
    assert bad(seen, "cut") == {}


def test_wide_tables_scroll_in_their_own_box(browsed):
    """A table wider than the text scrolls in its own box (the fit table, 13
    columns, and the benchmark tables are)."""
    seen, _, _ = browsed
    clipped = {p: s["tables"] for p, s in seen.items()
               if any(t["wide"] and not t["scrolls"] for t in s["tables"])}
    assert clipped == {}
    assert any(t["wide"] and t["scrolls"] for t in seen["results/benchmarks.html"]["tables"])


def test_plain_text_formulas_fit_the_column(browsed):
    """A literal block without a language (a plain-text formula, such as the
    shared modules' on the API page, which wrap there) never needs a scroll
    bar to be read: a formula is half hidden behind one."""
    seen, _, _ = browsed
    assert bad(seen, "wide_pre") == {}


def test_no_raw_roles_or_tex_escapes_in_the_text(browsed):
    """What a reader sees never holds a Sphinx role that was not resolved
    (``:func:`g1```) nor LaTeX that was not typeset (``\\_``, ``\\frac``, $$)."""
    seen, _, _ = browsed
    roles = {p: ROLE.findall(s["prose"]) for p, s in seen.items() if ROLE.search(s["prose"])}
    tex = {p: TEX.findall(s["prose"]) for p, s in seen.items() if TEX.search(s["prose"])}
    assert roles == {} and tex == {}


def test_maths_is_typeset(browsed):
    """Every formula of the source (``.. math::``, ``$$``) is typeset by
    MathJax, on every page that has one; the plugin pages and the energy
    guide have formulas."""
    seen, _, _ = browsed
    untypeset = {p: (s["math_sources"], s["typeset"]) for p, s in seen.items()
                 if s["math_sources"] and not (s["mathjax"] and s["typeset"] >= s["math_sources"])}
    assert untypeset == {}
    for page in [f"plugins/{cls.name}.html" for cls in PLUGINS] + ["guide/energy.html"]:
        assert seen[page]["typeset"] >= 1, page


def test_screenshots(browsed):
    _, _, shots = browsed
    for shot in SCREENSHOTS:
        assert os.path.getsize(shots / f"{shot}.png") > 20_000, shot
