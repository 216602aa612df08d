"""The documentation site, built once as the README says (warnings are errors):
the build leaves the source tree untouched; each plugin page names every
parameter and option, loads its Python example as written, shows renders that
vary its main parameter; the command-line page covers every command and
option in sentences, with exit statuses; the results pages and guides read
their figures from the committed results; the API page lists the public API
only; no page body, nor a report's page, names a repository path. The site
in Chromium: test_site_browser.py (the same build, made once per process)."""
from __future__ import annotations

import argparse
import html
import json
import os
import re

import numpy as np
import pytest

from mi_brdfs.bsdfs import PLUGINS
from mi_brdfs.bsdfs.cases import ALL
from mi_brdfs.tools import cli

import sitebuild
from sitebuild import pages

ROOT = sitebuild.ROOT
DOCS = sitebuild.DOCS


@pytest.fixture(scope="module")
def build() -> sitebuild.Build:
    built = sitebuild.build()
    assert not built.error, built.error
    return built


@pytest.fixture(scope="module")
def site(build) -> str:
    return build.out


def read(site: str, page: str) -> str:
    with open(os.path.join(site, page), encoding="utf-8") as f:
        return f.read()


def plain(fragment: str) -> str:
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", fragment)).split())


def text_of(site: str, page: str) -> str:
    return plain(read(site, page))


def article(page_html: str) -> str:
    match = re.search(r"<article[^>]*>(.*)</article>", page_html, re.S)
    return match.group(1) if match else page_html


def test_the_build_writes_nothing_into_the_source_tree(build):
    assert build.changed == []


# ----------------------------------------------------------------------------
#  Plugin pages
# ----------------------------------------------------------------------------

def table_rows(site: str, page: str) -> dict[str, list[str]]:
    """The page's parameter table: each body row's cells as text, by its first
    cell (the parameter's or option's name)."""
    table = read(site, page).split("<table", 1)[1].split("</table>", 1)[0]
    body = table.split("<tbody", 1)[1]
    rows = [[plain(c) for c in re.findall(r"<td[^>]*>(.*?)</td>", r, flags=re.S)]
            for r in re.findall(r"<tr[^>]*>(.*?)</tr>", body, flags=re.S)]
    return {r[0]: r for r in rows}


@pytest.mark.parametrize("cls", PLUGINS, ids=lambda c: c.name)
def test_plugin_page_names_every_parameter_and_option(site, cls):
    names = set(table_rows(site, f"plugins/{cls.name}.html"))
    declared = {p.name for p in cls.PARAMS} | {o.name for o in cls.all_options()}
    assert declared <= names, f"missing from the page's table: {sorted(declared - names)}"


@pytest.mark.parametrize("cls", PLUGINS, ids=lambda c: c.name)
def test_plugin_page_flags_are_what_traverse_puts(site, cls):
    """The table's flags column (Mitsuba's P, ∂, D) says what ``mi.traverse``
    of the loaded plugin gives: P for each key it exposes, ∂ unless flagged
    NonDifferentiable, D if flagged Discontinuous; options carry none. The
    legend sits under the table."""
    import mitsuba as mi
    page = read(site, f"plugins/{cls.name}.html")
    rows = table_rows(site, f"plugins/{cls.name}.html")
    params = mi.traverse(mi.load_dict({"type": cls.name}))
    assert len(params.keys()) > 0
    for key in params.keys():
        f = params.flags(key)
        expected = ["P"] + ([] if f & mi.ParamFlags.NonDifferentiable else ["∂"]) \
            + (["D"] if f & mi.ParamFlags.Discontinuous else [])
        assert rows[key.split(".")[0]][-1].split() == expected, key
    for o in cls.all_options():
        assert rows[o.name][-1] == "", o.name
    assert "P exposed by mi.traverse" in plain(page) and "D discontinuous" in plain(page)
    if cls.name == "cook_torrance":          # the roughness: exposed, differentiable, discontinuous
        assert rows["alpha"][-1] == "P ∂ D" and rows["f0"][-1] == "P ∂"
        assert rows["distribution"][-1] == ""


@pytest.mark.parametrize("cls", PLUGINS, ids=lambda c: c.name)
def test_help_shows_the_module_documentation(cls):
    """help(mi_brdfs.Phong) shows the module's documentation (its formulas and
    XML example; the parameter table is made from the declarations by the
    site's build), and every parameter and option says what it is."""
    doc = cls.__doc__
    assert doc.lstrip().startswith(f"``{cls.name}``") and ".. code-block:: xml" in doc
    assert ".. math::" in doc, "the formulas of eval as math"
    for item in cls.PARAMS + cls.all_options():
        assert len(" ".join(item.doc.split())) > 20, item.name


def code_blocks(page_html: str) -> list[str]:
    return [html.unescape(re.sub(r"<[^>]+>", "", b))
            for b in re.findall(r"<pre[^>]*>(.*?)</pre>", page_html, flags=re.S)]


@pytest.mark.parametrize("cls", PLUGINS, ids=lambda c: c.name)
def test_python_example_loads_the_xml_example(site, cls):
    """The page's Python dictionary, run as written, loads the same BSDF as
    its XML example read by Mitsuba's own parser."""
    import mitsuba as mi
    blocks = code_blocks(read(site, f"plugins/{cls.name}.html"))
    xml = next(b for b in blocks if b.lstrip().startswith(f'<bsdf type="{cls.name}"'))
    xml = xml[:xml.index("</bsdf>") + len("</bsdf>")].replace("<bsdf ", '<bsdf version="3.0.0" ', 1)
    python = next(b for b in blocks if "mi.load_dict(" in b)
    namespace = {}
    exec(compile(python, f"{cls.name} page", "exec"), namespace)
    ours = mi.traverse(namespace["bsdf"])
    reference = mi.traverse(mi.load_string(xml))
    assert set(ours.keys()) == set(reference.keys())
    for key in reference.keys():
        np.testing.assert_array_equal(np.array(ours[key]), np.array(reference[key]), err_msg=key)
    assert type(namespace["bsdf"]).__name__ == type(mi.load_string(xml)).__name__


def preview_images(site: str, cls, param: str) -> dict[tuple[str, str], np.ndarray]:
    """The page's renders of the sweep of ``param`` by (mode, value), read
    from the built site."""
    import mitsuba as mi
    page = read(site, f"plugins/{cls.name}.html")
    found = {}
    for tag in re.findall(r"<img[^>]*>", page):
        attrs = dict(re.findall(r'(\w+)="([^"]*)"', tag))
        match = re.fullmatch(rf"{cls.name}, (\w+), {param} = (\S+)", html.unescape(attrs["alt"]))
        if match:
            path = os.path.normpath(os.path.join(site, "plugins", attrs["src"]))
            found[match.groups()] = np.array(mi.Bitmap(path), dtype=np.float64)
    return found


@pytest.mark.parametrize("cls", PLUGINS, ids=lambda c: c.name)
def test_plugin_page_renders_vary_its_main_parameter(site, cls):
    """Both modes at every value of the model's pictures, captioned with the
    value; each value and each mode gives a different image."""
    sweeps = ALL[cls.name].picture_sets()
    assert sweeps, "a model declares the renders of its page"
    page = text_of(site, f"plugins/{cls.name}.html")

    def differ(a, b) -> bool:          # a highlight (8 % of the 8-bit range) or the shading
        d = np.abs(a - b)              # (same seed: an unused parameter gives 0 and 0)
        return d.max() > 20 or d.mean() > 1
    for pictures in sweeps:
        images = preview_images(site, cls, pictures.parameter)
        values = [f"{v:g}" for v in pictures.values]
        assert set(images) == {(m, v) for m in ("scanline", "hdr") for v in values}
        for v in values:
            assert f"{pictures.parameter} = {v}" in page
        for mode in ("scanline", "hdr"):
            for a, b in zip(values, values[1:]):
                assert differ(images[mode, a], images[mode, b]), (pictures.parameter, mode, a, b)
        assert differ(images["scanline", values[0]], images["hdr", values[0]])


def figures(site: str, page: str) -> list[dict]:
    """The page's render figures (``div.matpreview``): each image's file in the
    site, its alt text and its caption."""
    html_ = read(site, page)
    found = []
    for grid in re.findall(r'<div class="matpreview[^"]*">(.*?)</div>', html_, re.S):
        for fig in re.findall(r"<figure[^>]*>(.*?)</figure>", grid, re.S):
            attrs = dict(re.findall(r'(\w+)="([^"]*)"', re.search(r"<img[^>]*>", fig).group(0)))
            caption = re.search(r"<figcaption>(.*?)</figcaption>", fig, re.S)
            found.append({"file": os.path.normpath(os.path.join(site, os.path.dirname(page),
                                                                attrs["src"])),
                          "alt": html.unescape(attrs.get("alt", "")),
                          "caption": plain(caption.group(1)) if caption else ""})
    return found


@pytest.mark.parametrize("cls", PLUGINS, ids=lambda c: c.name)
def test_plugin_renders_in_matpreview_style(site, cls):
    """Every render of a plugin page is a captioned figure with alt text, its
    image 256² pixels, the sphere on a floor under a neutral grey background
    (not black: the top corners are grey, R = G = B, neither dark nor white)
    and a checkered floor (the bottom rows alternate light and dark)."""
    import mitsuba as mi
    found = figures(site, f"plugins/{cls.name}.html")
    assert len(found) >= 2 * len(ALL[cls.name].picture_sets()[0].values)
    for f in found:
        assert f["alt"].startswith(f"{cls.name}, ") and f["caption"], f
        image = np.array(mi.Bitmap(f["file"]), dtype=np.float64)
        assert image.shape[:2] == (256, 256), f
        corners = np.concatenate([image[:8, :8].reshape(-1, 3), image[:8, -8:].reshape(-1, 3)])
        grey = corners.mean(axis=0)
        assert 25 < grey.mean() < 230 and np.ptp(grey) < 3, (f["alt"], grey)
        floor = image[-20:].mean(axis=(0, 2))              # along the bottom rows
        assert np.ptp(floor) > 25, (f["alt"], np.ptp(floor))


def _conductor_fresnel(eta, kappa, theta):
    """The unpolarised Fresnel reflectance of a conductor of complex index
    n = η + iκ (from air) at the angle θ, by complex arithmetic (Snell's law
    with a complex refracted cosine), independent of the plugin's real form."""
    n = np.asarray(eta) + 1j * np.asarray(kappa)
    c = np.cos(theta)
    ct = np.sqrt(1 - (np.sin(theta) / n) ** 2)
    rs = (c - n * ct) / (c + n * ct)
    rp = (n * c - ct) / (n * c + ct)
    return (abs(rs) ** 2 + abs(rp) ** 2) / 2


def test_cook_torrance_gold_under_three_fresnel_forms(site):
    """The cook_torrance page's gold: Schlick's (the lecture's, first), F82-tint
    and the exact conductor's, side by side and captioned, with parameters
    that are gold's exact reflectance (Mitsuba's Au as roughconductor reads
    it) at 0° and at acos(1/7), worked here by complex arithmetic; the exact
    conductor's sphere is paler (bluer) than Schlick's."""
    import drjit as dr
    import mitsuba as mi
    page = "plugins/cook_torrance.html"
    gold = [f for f in figures(site, page) if ", gold, " in f["alt"]]
    assert [f["alt"].rsplit(" ", 1)[-1] for f in gold] == ["schlick", "f82", "conductor"]
    assert "lecture" in gold[0]["caption"] and 'material="Au"' in gold[2]["caption"]
    rows = table_rows(site, page)                           # the lecture's forms first
    assert rows["fresnel"][2].startswith('F: "schlick" is the lecture')
    assert rows["base"][2].startswith('the diffuse lobe: "lambert" is the lecture')
    reference = mi.load_dict({"type": "roughconductor", "material": "Au"})
    si = dr.zeros(mi.SurfaceInteraction3f)
    eta, kappa = (np.array(reference.eval_attribute(p, si), dtype=np.float64).ravel()
                  for p in ("eta", "k"))
    normal = _conductor_fresnel(eta, kappa, 0.0)
    grazing = _conductor_fresnel(eta, kappa, np.arccos(1 / 7))
    f0 = normal.max()
    colour = normal / f0
    tint = np.minimum(grazing / (colour * (f0 + (1 - f0) * (6 / 7) ** 5)), 1.0)
    triple = lambda v: "(" + ", ".join(f"{x:.3f}" for x in v) + ")"    # noqa: E731
    text = text_of(site, page)
    assert f"F(0°) = {triple(normal)}" in text and f"F(81.8°) = {triple(grazing)}" in text
    assert f"f0 = {f0:.3f}, specular_reflectance = {triple(colour)}" in gold[0]["caption"]
    assert f"f82_tint = {triple(tint)}" in gold[1]["caption"]
    # the sphere's box: the exact conductor's blue rises towards grazing, Schlick's
    # with one f0 keeps m_S's (3.6 levels of 255 more in the build of 4 Dec 2026)
    schlick, _, exact = (np.array(mi.Bitmap(f["file"]), dtype=np.float64)[40:200, 60:200]
                         for f in gold)
    assert exact[..., 2].mean() - schlick[..., 2].mean() > 2.0


def test_index_hero_shows_every_plugin(site):
    """The index's hero image is the course scene: it holds a sphere of every
    registered plugin, and its caption names each."""
    import xml.etree.ElementTree as ET
    scene = ET.parse(os.path.join(ROOT, "scenes", "course.xml"))
    shown = {b.get("type") for b in scene.iter("bsdf")}
    assert {cls.name for cls in PLUGINS} <= shown
    caption = re.search(r"Back row:.*?front row:[^.]*\.", text_of(site, "index.html")).group(0)
    assert all(cls.name in caption for cls in PLUGINS), caption


@pytest.mark.parametrize("cls", PLUGINS, ids=lambda c: c.name)
def test_plugin_page_has_notes_links_lobes_and_scene(site, cls):
    page = read(site, f"plugins/{cls.name}.html")
    text = plain(page)
    assert "One-sided" in text and "depolarizer" in text and "Modes" in text
    lobes = text.split("Lobes", 1)[1].split("Bundled scene", 1)[0]
    assert "radial scale" in lobes and "θ_" not in lobes     # angles typeset, not raw
    for name in ALL[cls.name].mitsuba:
        assert f'plugins_bsdfs.html#bsdf-{name}"' in page, name
    for picture in (f"{cls.name}_scanline.png", f"{cls.name}_hdr.png", f"lobe_{cls.name}.png"):
        assert picture in page, picture
        assert os.path.exists(os.path.join(site, "_images", picture)), picture


# ----------------------------------------------------------------------------
#  The command line
# ----------------------------------------------------------------------------

def commands() -> dict[str, argparse.ArgumentParser]:
    top = cli.parser()
    return next(a for a in top._actions if isinstance(a, argparse._SubParsersAction)).choices


def _options(parser: argparse.ArgumentParser) -> list[str]:
    return [a.option_strings[-1] if a.option_strings else (a.metavar or a.dest) for a in parser._actions
            if not isinstance(a, (argparse._HelpAction, argparse._SubParsersAction))]


def test_cli_page_covers_every_command_and_option(site):
    page = text_of(site, "cli.html")
    for name, sub in commands().items():
        assert f"mi-brdfs {name}" in page, name
        for option in _options(sub):
            assert option in page, (name, option)


def test_every_cli_argument_is_explained():
    """The reference is generated from the help strings: none may be missing,
    and none is dead (``scenes`` takes no option but ``--help``)."""
    missing = [(name, a.dest) for name, sub in commands().items() for a in sub._actions
               if not isinstance(a, argparse._HelpAction) and not a.help]
    assert not missing
    assert _options(commands()["scenes"]) == []


def cli_sections(site: str) -> dict[str, str]:
    page = article(read(site, "cli.html"))
    parts = re.split(r"<section id=\"mi-brdfs-([a-z]+)\">", page)
    return dict(zip(parts[1::2], parts[2::2]))


def test_cli_page_is_sentences_with_exit_statuses(site):
    sections = cli_sections(site)
    assert set(sections) == set(commands())
    for name, section in sections.items():
        cells = re.findall(r"<tr[^>]*>\s*<td[^>]*>.*?</td>\s*<td[^>]*>(.*?)</td>", section, re.S)
        for cell in cells:
            text = plain(cell)
            assert text[0].isupper() and text.endswith("."), (name, text)
        statuses = plain(section.split("Exit status", 1)[1])
        assert "1:" in statuses or name == "scenes", name
        assert ("130:" in statuses) == (name != "explore"), name
    assert "3:" in plain(sections["compare"].split("Exit status", 1)[1])
    page = read(site, "cli.html")
    assert "tcp://host:8786" in page and 'href="tcp://' not in page
    # flags stay flags: Sphinx's smart quotes would turn "--help" into "–help"
    assert re.findall(r"[–—][a-z]", plain(article(page))) == []


# ----------------------------------------------------------------------------
#  Figures read from the committed results; the reports on the site
# ----------------------------------------------------------------------------

def committed(*path: str):
    with open(os.path.join(DOCS, *path), encoding="utf-8") as f:
        return json.load(f)


def test_validation_figures_are_the_committed_report(site):
    report = committed("validation", "results.json")
    s = report["summary"]
    expected = (f"{len(report['checks'])} checks, {s['pass']} pass, {s['documented']} documented "
                f"behaviour, {s['known']} documented known limitation, {s['fail']} fail "
                f"({report['seconds']:.0f} s")
    for page in ("guide/validation.html", "results/validation.html"):
        text = text_of(site, page)
        assert str(len(report["checks"])) in text
    guide = text_of(site, "guide/validation.html")
    assert expected in guide
    assert f"every one of the {len(report['sampling'])} χ² tests passes" in guide
    results = text_of(site, "results/validation.html")
    for check in report["checks"]:
        if check["status"] != "pass":
            assert check["reason"].split()[0] in results, check["id"]


def test_fit_table_is_the_committed_sweep(site):
    records = committed("benchmarks", "trade", "fits.json")
    targets = list(dict.fromkeys(r["target"] for r in records))
    for page in ("guide/fit.html", "results/fit.html"):
        tables = article(read(site, page)).split("<table")[1:]
        table = next(t for t in tables if "cost ×" in t).split("</table>", 1)[0]
        header = re.findall(r"<th[ >]", table)
        assert len(header) == len(targets) + 3, page       # model, cost, operations, targets
        rows = [plain(row) for row in re.findall(r"<tr[^>]*>(.*?)</tr>", table, re.S)[1:]]
        assert len(rows) == len(dict.fromkeys(r["model"] for r in records))
        for r in records:                                 # each cell: FLIP · BRDF error
            row = next(row for row in rows if row.split()[0] == r["model"])
            assert f"{r['image_flip']:.2f} · {r['brdf_error']:.3f}" in row, (page, r["model"])
    walk = committed("benchmarks", "trade", "walk.json")        # the walk rung's table
    assert walk
    for page in ("guide/fit.html", "results/fit.html"):
        text = " ".join(text_of(site, page).split())
        assert "Energy compensation against the walk" in text, page
        for spec, row in walk.items():
            assert f"{row['walk']:.3f} ({row['single']:.3f})" in text, (page, spec)
    caption = " ".join(text_of(site, "results/fit.html").split())
    assert "Each cell: the FLIP of the model" in caption, caption     # FLIP first, as the cells
    assert "after the dot, its BRDF error" in caption and "bold: the first-ranked fit" in caption
    assert f"{len(records)} fits" in text_of(site, "guide/fit.html")


def test_fit_guide_figures_are_the_committed_sweep(site):
    """The fit guide's prose is the committed records': every model fitted
    there is named, and what it says holds in them: of the brushed aluminium
    (the anisotropic Cook-Torrance the closest image by far, with the
    target's roughnesses; Ashikhmin-Shirley and anisotropic Ward next; every
    isotropic model behind them), of the conductors (each one's own
    microfacet D first, with a conductor's Fresnel; the plastics with the plastic
    base) and of energy compensation (worse, on these
    single-scattering targets, far more often than better)."""
    from mi_brdfs.tools.fit import rank, trade
    records = [r for r in committed("benchmarks", "trade", "fits.json") if "error" not in r]
    assert records
    guide = " ".join(text_of(site, "guide/fit.html").split())
    for r in records:
        assert r["model"] in guide, r["model"]
    brushed = sorted((r for r in records if "alpha_u=0.05,alpha_v=0.3" in r["target"]),
                     key=lambda r: r["image_flip"])
    assert brushed[0]["model"] == "cook_torrance/ggx/smith/anisotropic"
    assert {r["model"] for r in brushed[1:3]} == {"ashikhmin_shirley", "ward/anisotropic"}
    assert brushed[0]["image_flip"] < 0.1 * brushed[1]["image_flip"]          # "by far"
    fitted = brushed[0]["parameters"]
    assert fitted["alpha_u"] == pytest.approx(0.05, rel=0.02)
    assert fitted["alpha_v"] == pytest.approx(0.3, rel=0.02)
    assert "recovers the target" in guide
    assert ("its image is the closest by far; Ashikhmin-Shirley and anisotropic Ward get part "
            "of the way") in guide
    for spec in dict.fromkeys(r["target"] for r in records):
        first = rank.ranked([r for r in records if r["target"] == spec])[0]["model"]
        if spec.startswith("roughconductor:material=") and "distribution" not in spec:
            assert first.startswith("cook_torrance/beckmann/"), (spec, first)  # Beckmann: the default
        elif spec.startswith("roughconductor:") and "alpha_u" not in spec:
            assert first.startswith("cook_torrance/ggx/smith"), (spec, first)
        if spec.startswith("roughconductor:") and "alpha_u" not in spec:   # a conductor's F
            assert first.endswith(("/conductor", "/f82")), (spec, first)
        if spec.startswith("roughplastic:"):
            assert first.endswith("/plastic"), (spec, first)
    worse, better, pairs = trade.compensation_effect(records)
    assert worse > 10 * better and f"worse in {worse} of the {pairs}" in guide
    for spec in dict.fromkeys(r["target"] for r in records):     # the cheaper model's bullet
        order = rank.ranked([r for r in records if r["target"] == spec])
        closest = rank.closest_cheaper(order)
        alternative = rank.cheaper_alternative(order)
        if alternative is not None:
            first = order[0]["model"]
            rung_down = (first.endswith("/conductor") and alternative["model"].endswith("/f82")) \
                or (first.endswith("/f82") and alternative["model"] == first[:-len("/f82")])
            if not rung_down:       # another model: the guide names it with both FLIPs
                assert (f"FLIP {rank.quality(alternative):.3f} against "
                        f"{rank.quality(order[0]):.3f}") in guide, spec
        elif closest is not None:                      # "beyond the tolerance"
            best, tol = rank.quality(order[0]), rank.tolerance(order)
            assert rank.quality(closest) > best + tol, spec
            if rank.quality(closest) <= best + 2 * tol:    # the one the guide names
                label = next(label for label, s in trade.TARGETS if s == spec)
                assert (f"on {label} (FLIP {rank.quality(closest):.3f}, where the tolerance ends "
                        f"at {best + tol:.3f})") in guide, spec
    assert "no cheaper model looks the same" in guide


def test_reports_are_pages_of_the_site_with_their_pictures(site):
    for name, guide in (("validation", "guide/validation.html"), ("trade", "results/fit.html")):
        report = os.path.join(site, "reports", name, "index.html")
        pictures = re.findall(r"src=['\"]?([^'\" >]+)", read(site, report))
        assert pictures, name
        for picture in pictures:
            assert os.path.exists(os.path.join(site, "reports", name, picture)), picture
    assert 'href="../reports/validation/index.html"' in read(site, "guide/validation.html")
    assert 'href="../reports/trade/index.html"' in read(site, "results/fit.html")
    assert "/results/fit" in read(site, "guide/fit.html").replace(".html", "").replace("..", "")
    assert "_downloads" not in read(site, "guide/validation.html")


def test_benchmark_results_page_is_the_committed_run(site):
    results = committed("benchmarks", "results.json")
    page = text_of(site, "results/benchmarks.html")
    for group in results["groups"]:
        assert group in page
    assert f"{results['seconds']:.0f} s" in page


def test_explore_latencies_are_the_committed_run():
    """The explorer guide's latency table and its start-up and fit times are
    the committed bench run's group ``explore`` (rounded to the millisecond,
    start-up and fit to 10 ms)."""
    rows = committed("benchmarks", "results.json")["groups"]["explore"]
    with open(os.path.join(DOCS, "guide", "explore.md"), encoding="utf-8") as f:
        guide = f.read()
    table = {line.split("|")[1].strip(): line for line in guide.splitlines()
             if line.startswith("| slider") or line.startswith("| first 128")}
    lines = {"slider -> plots": "slider → plot data",
             "re-render": "slider → first pass of the re-render",
             "256 spp": "slider → 256 spp", "first image": "first 128² image of the configuration"}
    configs = ["cook_torrance ggx smith", "cook_torrance ggx smith +ec", "phong scanline",
               "roughconductor (Mitsuba)"]
    for measure, label in lines.items():
        cells = [c.strip() for c in table[label].split("|")[2:-1]]
        for config, cell in zip(configs, cells, strict=True):
            row = next(r for r in rows if r["measure"] == measure and r["config"] == config)
            expected = (f"{row['median_ms']:.0f}" if measure == "first image"
                        else f"{row['median_ms']:.0f} ({row['max_ms']:.0f})")
            assert cell == expected, (label, config)
    start = next(r for r in rows if r["measure"] == "startup")["median_ms"] / 1000
    fit = next(r for r in rows if r["measure"] == "fit")["median_ms"] / 1000
    assert f"started in {start:.2f} s" in guide
    assert f"answered in {fit:.1f} s" in guide


def test_energy_costs_are_the_committed_run():
    """The energy guide's render-time ratios (compensation on over off) are the
    committed bench run's group ``energy``, to two decimals."""
    rows = {r["name"]: r for r in committed("benchmarks", "results.json")["groups"]["energy"]}
    with open(os.path.join(DOCS, "guide", "energy.md"), encoding="utf-8") as f:
        guide = " ".join(f.read().split())
    ratio = lambda name: f"{rows[name]['ratio']:.2f}×"                # noqa: E731
    for label, name in (("EON", "oren_nayar (EON)"), ("phong", "phong"), ("blinn", "blinn"),
                        ("ward", "ward"), ("anisotropic `ward`", "ward anisotropic"),
                        ("anisotropic GGX × Smith", "cook_torrance ggx smith anisotropic")):
        assert f"{label} {ratio(name)}" in guide, label
    everything = [r["ratio"] for r in rows.values()]
    assert f"{min(everything):.2f}–{max(everything):.2f}× for every compensated model" in guide
    ct = [r["ratio"] for n, r in rows.items() if n.startswith("cook_torrance")]
    assert f"cook_torrance {min(ct):.2f}–{max(ct):.2f}×" in guide
    aniso = rows["ward anisotropic"]["execution_ratio"]
    assert f"(kernel execution {aniso:.2f}×" in guide


# ----------------------------------------------------------------------------
#  The API page; repository paths
# ----------------------------------------------------------------------------

PUBLIC = {"mi_brdfs.register", "mi_brdfs.scenes.names", "mi_brdfs.scenes.path",
          "mi_brdfs.bsdfs.base.BRDF", "mi_brdfs.bsdfs.params.Param",
          "mi_brdfs.bsdfs.params.Option", "mi_brdfs.bsdfs.params.ParameterError",
          "mi_brdfs.bsdfs.params.DeclarationError", "mi_brdfs.bsdfs.mixture.Mixture",
          *(f"mi_brdfs.bsdfs.cases.{c}" for c in ("Cases", "Chi2", "Furnace", "Twin", "Pictures")),
          "mi_brdfs.render.passes.render_passes", "mi_brdfs.render.frozen.FrozenRender",
          "mi_brdfs.render.frozen.GradientStep", "mi_brdfs.render.tonemap.tonemap",
          "mi_brdfs.render.tonemap.to_srgb8", "mi_brdfs.render.tonemap.write_png",
          "mi_brdfs.render.imagefile.write", "mi_brdfs.render.exr.write_exr",
          "mi_brdfs.render.exr.read_exr", "mi_brdfs.tools.compare.compare",
          "mi_brdfs.tools.validate.validate", "mi_brdfs.tools.bench.run",
          "mi_brdfs.tools.fit.fit"}


def test_api_page_lists_the_public_api_only(site):
    ids = set(re.findall(r'<dt class="sig sig-object py" id="([^"]+)"', read(site, "api.html")))
    hooks = ("mi_brdfs.bsdfs.base.BRDF.", "mi_brdfs.bsdfs.mixture.Mixture.")
    extra = {i for i in ids - PUBLIC if not i.startswith(hooks)}
    assert not extra, sorted(extra)
    assert PUBLIC <= ids, sorted(PUBLIC - ids)


PATH = re.compile(r"(?<![\w.:/-])(?:mi_brdfs|tests|docs|scenes|notebooks)/[\w./*-]*")
ABOUT_THE_REPOSITORY = {"layout.html", "contributing.html"}    # pages that describe it


def repository_paths(page_html: str) -> set[str]:
    """Paths in the page's prose: outside code blocks; a code literal counts
    when it is a bare path (a command that contains one does not)."""
    body = re.sub(r"<pre.*?</pre>", " ", article(page_html), flags=re.S)

    def literal(match):
        inner = plain(match.group(1))
        return " " if " " in inner else f" {inner} "
    body = re.sub(r"<code[^>]*>(.*?)</code>", literal, body, flags=re.S)
    return set(PATH.findall(plain(body)))


def test_no_repository_paths_in_page_bodies(site):
    found = {page: repository_paths(read(site, page)) for page in pages(site)
             if not page.startswith(("reports/", "_")) and page not in ABOUT_THE_REPOSITORY}
    assert not {p: sorted(v) for p, v in found.items() if v}
    assert repository_paths("<article><p>see tests/test_docs.py</p></article>")   # the check bites


REPORTS = ["reports/validation/index.html", "reports/trade/index.html"]


@pytest.mark.parametrize("report", REPORTS)
def test_no_repository_paths_in_the_reports(site, report):
    """The generated reports are pages of the site too: no repository path in
    their prose either."""
    assert repository_paths(read(site, report)) == set()


# ----------------------------------------------------------------------------
#  What a reader reads (issue 38): numbers, headers, names
# ----------------------------------------------------------------------------

CONSTANT_NAME = re.compile(r"\b[A-Z]{2,}[A-Z0-9]*_[A-Z0-9_]+\b")      # ALPHA_MIN, KH_MIN
E_NOTATION = re.compile(r"(?<![\w#.])\d+(?:\.\d+)?e[+-]?\d+\b")         # 1e+06, 1e-4


def prose(page_html: str) -> str:
    """A page's article without its code blocks and code literals."""
    body = re.sub(r"<pre.*?</pre>", " ", article(page_html), flags=re.S)
    return plain(re.sub(r"<code[^>]*>.*?</code>", " ", body, flags=re.S))


@pytest.mark.parametrize("cls", PLUGINS, ids=lambda c: c.name)
def test_plugin_page_reads_numbers_not_code(site, cls):
    """The Type column and the descriptions give values (in [0, 10⁶]), not
    the code's spelling of them (in [0, 1e+06], ALPHA_MIN); the bundled scene's
    comment says the command the page says."""
    page = read(site, f"plugins/{cls.name}.html")
    text = prose(page)
    assert CONSTANT_NAME.findall(text) == [] and E_NOTATION.findall(text) == []
    table = plain(page.split("<table", 1)[1].split("</table>", 1)[0])
    assert "e+" not in table and CONSTANT_NAME.findall(table) == []
    assert "in [0, 10⁶]" in table                     # the colours' bound, as a reader writes it
    scene = "".join(code_blocks(page))
    assert f"mi-brdfs render {cls.name} " in scene and "render scenes/" not in scene


def test_benchmark_headers_are_words_with_units(site):
    page = read(site, "results/benchmarks.html")
    headers = [plain(h) for h in re.findall(r"<th[^>]*>(.*?)</th>", page, re.S)]
    assert headers and [h for h in headers if "_" in h] == []
    assert "plugin (s)" in headers and "built-in compile (s)" in headers
    assert any(h.startswith("efficiency over the first strategy") for h in headers)


def test_help_names_bench_groups_and_compare_metrics(site):
    """``bench --only`` lists the groups it takes; each compare threshold says
    which metric it bounds (``abs`` alone was never defined)."""
    from mi_brdfs.tools.bench.groups import GROUPS
    assert cli.BENCH_GROUPS == tuple(GROUPS)
    page = text_of(site, "cli.html")
    assert ", ".join(GROUPS) in page
    assert "whose abs exceeds" not in page and "max(|t - r|)" in page


def test_typeset_where_a_reader_expects_it(site):
    """The energy guide's formulas are maths (MathJax), and MathJax reads the
    fit guide's \\text{brdf\\_error} as brdf_error (textmacros, from the site's
    own copy)."""
    assert read(site, "guide/energy.html").count('class="math notranslate nohighlight"') >= 2
    fit = read(site, "guide/fit.html")
    assert '"[tex]/textmacros"' in fit and r"\text{brdf\_error}" in fit


def test_index_names_the_lecture(site):
    text = text_of(site, "index.html")
    assert "course lecture BRDF Models" in text


def test_validation_report_on_the_site_links_back(site):
    page = read(site, "reports/validation/index.html")
    assert "href='../../results/validation.html'" in page and "href='../../index.html'" in page
    assert "<nav class='contents'>" in page


def test_energy_guide_reads_as_a_guide(site):
    """Figures of what it says (the walk against compensation, from the
    validation report); no test function names, no e-notation (1e-39:
    10⁻³⁹), no "this machine" in the energy guide's prose."""
    page = read(site, "guide/energy.html")
    assert all(f"groundtruth_{name}.png" in page for name in ("ggx_smith", "slices"))
    # every D × G against the walk, the residual map, and each compensated
    # model's furnace plot with and without compensation (the validation
    # report's rows say which plot is whose)
    assert all(f"groundtruth_{d}_{g}.png" in page for d in ("ggx", "beckmann", "blinn")
               for g in ("smith", "cook_torrance"))
    assert "groundtruth_residuals.png" in page
    report = committed("validation", "results.json")
    shown = set(re.findall(r"furnace_\w+?_\d+\.png", page))
    compensated = {r["plot"]: r["model"] for r in report["furnace"] if r["compensated"]}
    assert shown <= set(compensated)
    assert {compensated[p] for p in shown} == {
        cls.name for cls in PLUGINS if cls.compensable}
    text = prose(page)
    assert re.findall(r"\btest_\w+", text) == [] and E_NOTATION.findall(text) == []
    assert "this 2-core machine" not in text


def test_plot_labels_typeset_angles():
    """Every matplotlib label, title and legend entry in the package writes an
    angle's subscript in mathtext ($\\theta_i$), never raw ("θ_i" printed as
    typed was on the validation report's furnace plots)."""
    drawn = re.compile(r"(set_xlabel|set_ylabel|set_title|suptitle|label=|\.text\()")
    raw = []
    for folder, _, files in os.walk(os.path.join(ROOT, "mi_brdfs")):
        for name in files:
            if name.endswith(".py"):
                path = os.path.join(folder, name)
                with open(path, encoding="utf-8") as f:
                    for n, line in enumerate(f, 1):
                        code = line.split("#", 1)[0]
                        if drawn.search(code) and re.search(r"[θφ]_\w", code):
                            raw.append(f"{os.path.relpath(path, ROOT)}:{n}: {line.strip()}")
    assert raw == []


def test_screenshots_beside_the_guides_that_show_them(site):
    """The site's screenshots (docs/screenshots.py) and the explorer's (at rest
    and mid-drag) are committed beside the guide that shows them, PNGs of the
    1280 px window, each under 400 KB; the pages show them."""
    from PIL import Image
    shown = {"guide/site.html": ("guide/site", ("plugin", "energy", "trade")),
             "guide/explore.html": ("guide/explore", ("page", "drag"))}
    for page, (folder, names) in shown.items():
        html_text = read(site, page)
        for name in names:
            path = os.path.join(DOCS, folder, f"{name}.png")
            assert os.path.getsize(path) < 400_000, path
            assert Image.open(path).size[0] == 1280, path
            assert re.search(rf'<img[^>]+src="[^"]*/{name}\.png"', html_text), (page, name)


def test_explore_page_latencies_are_the_committed_run():
    """The explorer guide's table of what the page sees: its quiet columns are
    the committed run's rows ``page: ...`` (every request of a change
    together, in Chromium), with the load average the bench recorded, and the
    guide says which goals they meet."""
    rows = {r["measure"]: r for r in committed("benchmarks", "results.json")["groups"]["explore"]}
    with open(os.path.join(DOCS, "guide", "explore.md"), encoding="utf-8") as f:
        guide = f.read()
    table = {line.split("|")[1].strip(): [c.strip() for c in line.split("|")[2:-1]]
             for line in guide.split("### What the page sees", 1)[1].split("###", 1)[0]
             .splitlines() if line.startswith("| the ") or line.startswith("| every")}
    views = {"the lobe in the plane of incidence and the albedo": "plots",
             "the 3-D lobe": "3-D lobe", "the first pass of the 128² render": "first pass",
             "the random walk (after the release)": "walk",
             "every request of the change": "all"}
    cell = lambda r: f"{r['median_ms']:.0f} ({r['max_ms']:.0f})"             # noqa: E731
    for label, view in views.items():
        assert table[label][0] == cell(rows[f"page: change -> {view}"]), label
        drag = rows.get(f"page: drag -> {view}")
        assert table[label][1] == (cell(drag) if drag else ""), label
    assert f"load average {rows['page: drag -> plots']['load']} when it started" in guide
    drag, first = rows["page: drag -> plots"], rows["page: change -> first pass"]
    met = drag["median_ms"] <= 100 and first["median_ms"] <= 250
    assert ("Quiet, the page meets\nboth" in guide) == met
    assert f"follow a drag in {drag['median_ms']:.0f} ms" in guide


def test_the_fit_guide_says_how_long_a_fit_takes_as_the_bench_measured(site):
    """The fit guide's "How long" gives the bench's fit group figures
    (docs/benchmarks/results.json), default and --quick."""
    rows = {r["fit"]: r for r in committed("benchmarks", "results.json")["groups"]["fit"]}
    guide = " ".join(text_of(site, "guide/fit.html").split())
    for name in ("default", "quick"):
        r = rows[name]
        assert (f"{r['median_s']:.0f} s for {r['models']} models (median of {r['runs']} runs: "
                f"{r['fits_s']:.0f} s of fits, {r['costs_s']:.0f} s of costs") in guide, name


def test_the_energy_guides_ladder_tables_are_the_committed_run(site):
    """The energy guide's two ladder tables are the bench's committed ladder
    rows (docs/benchmarks/results.json): per material and lighting, each
    rung's FLIP and light over the walk's, its time over single scattering's
    and its noise (10⁻³, two significant digits)."""
    rows = committed("benchmarks", "results.json")["groups"]["ladder"]
    text = read(site, "guide/energy.html")
    lines = [plain(row) for row in re.findall(r"<tr[^>]*>(.*?)</tr>", text, re.S)]
    for case in dict.fromkeys((r["material"], r["lighting"]) for r in rows):
        mine = {r["rung"]: r for r in rows if (r["material"], r["lighting"]) == case}
        found = [line for line in lines if line.startswith(f"{case[0]}, {case[1]}")]
        assert len(found) == 2, (case, found)
        for rung in ("single", "separable", "directional", "walk"):
            r = mine[rung]
            assert f"{r['flip_mean']:.3f}, {r['light_vs_walk']:.3f}" in found[0], (case, rung)
            noise = f"{r['noise_relmse'] * 1e3:.2g}"
            assert f"{r['time_vs_single']:.2f}×, {noise}" in found[1], (case, rung, noise)


def test_the_energy_guides_bundled_scene_table_is_the_committed_run(site):
    """The energy guide's table of the walk in the bundled scenes is the
    bench's committed walk rows: per scene its pixels and samples, the single
    and walk rungs' time over the directional lobe's, each rung's noise
    (10⁻³, two significant digits) and the light over the walk's."""
    rows = committed("benchmarks", "results.json")["groups"]["walk"]
    text = read(site, "guide/energy.html")
    lines = [plain(row) for row in re.findall(r"<tr[^>]*>(.*?)</tr>", text, re.S)]
    for scene in dict.fromkeys(r["scene"] for r in rows):
        at = {r["rung"]: r for r in rows if r["scene"] == scene}
        found = [line for line in lines if line.split()[0] == scene]
        assert len(found) == 1, (scene, found)
        line = found[0]
        assert f"{at['walk']['res']}², {at['walk']['spp']}" in line, line
        assert (f"{at['single']['time_vs_directional']:.2f}×, "
                f"{at['walk']['time_vs_directional']:.2f}×") in line, line
        noise = ", ".join(f"{at[r]['noise_relmse'] * 1e3:.2g}" for r in ("single", "directional", "walk"))
        assert noise in line, (line, noise)
        assert (f"{at['single']['light_vs_walk']:.4f}, "
                f"{at['directional']['light_vs_walk']:.4f}") in line, line
