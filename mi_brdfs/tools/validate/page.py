"""The validation report's page (:mod:`mi_brdfs.tools.pages` builds it)."""
from __future__ import annotations

import html

from .. import groundtruth, pages
from .sections import ALPHA, PRESERVED_UP_TO
from .verdicts import LABELS, STATUSES

# beside the shared page's: a readable column of text, a contents box, headed
# tables; the first two columns are names, left-aligned
CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; line-height: 1.45;
       color: #222; max-width: 74em; margin: 2em auto; padding: 0 1.5em; }
h1 { margin-bottom: 0.2em; } h2 { margin-top: 2em; border-bottom: 1px solid #ddd; }
a { color: #2456a4; }
nav.contents { background: #f6f7f9; border: 1px solid #e2e4e8; padding: 0.6em 1.2em;
               display: inline-block; }
nav.contents ol { margin: 0.3em 0; padding-left: 1.4em; }
th { background: #f0f2f5; }
td, th { vertical-align: top; }
td:first-child, td:nth-child(2) { text-align: left; }
table.summary td, table.summary th { text-align: left; }
figure img { border: 1px solid #eee; }
"""


def _status(results: dict) -> dict[str, str]:
    """Check id -> status (the colour of a row anywhere in the report)."""
    return {c["id"]: c["status"] for c in results["checks"]}


def _summary_html(results: dict) -> str:
    """The summary at the top: counts per section and status, every check that
    did not pass (with the documented reason), and all checks on demand."""
    esc = html.escape
    check_list, s = results["checks"], results["summary"]
    sections = list(dict.fromkeys(c["section"] for c in check_list))
    shown = ("pass", "documented", "known", "fail")
    counts = "".join(
        f"<tr><td>{esc(sec)}</td>" + "".join(
            f"<td>{sum(c['section'] == sec and c['status'] == st for c in check_list)}</td>"
            for st in shown) + "</tr>" for sec in sections)

    def rows(items):
        return "".join(
            f"<tr><td class='{c['status']}'>{LABELS[c['status']]}</td>"
            f"<td>{esc(c['what'])}</td><td>{esc(c['measured'])}</td>"
            f"<td>{esc(c['reason'])}</td></tr>" for c in items)
    head = "<tr><th>status</th><th>check</th><th>measured</th><th>documented reason</th></tr>"
    order = {st: i for i, st in enumerate(STATUSES)}
    not_passed = sorted((c for c in check_list if c["status"] != "pass"),
                        key=lambda c: order[c["status"]])
    verdict = (f"<p class='fail'>{s['fail']} check(s) FAIL." if s["fail"] else
               "<p class='pass'>Every check passes or is documented.")
    return (f"<h2 id='summary'>Summary</h2>{verdict} {len(check_list)} checks: {s['pass']} pass, "
            f"{s['documented']} documented behaviour, "
            f"{plural(s['known'], 'documented known limitation')}, {s['fail']} fail.</p>"
            "<table class='summary'><tr><th>section</th>"
            + "".join(f"<th>{LABELS[st]}</th>" for st in shown) + f"</tr>{counts}</table>"
            + (f"<table class='summary'>{head}{rows(not_passed)}</table>" if not_passed else "")
            + f"<details><summary>All {len(check_list)} checks</summary>"
            f"<table class='summary'>{head}{rows(sorted(check_list, key=lambda c: order[c['status']]))}"
            "</table></details>")


def plural(n: int, noun: str) -> str:
    """``1 documented known limitation``, ``2 documented known limitations``."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def _figures(files: dict[str, str]) -> str:
    """A section's images: the two renders side by side (pixelated), then the maps."""
    renders = [(f, "built-in" if k == "reference" else "ours") for k, f in files.items()
               if k in ("reference", "test")]
    maps = [(f, k) for k, f in files.items() if k not in ("reference", "test")]
    return pages.figures(renders, "render") + pages.figures(maps)


def equivalence_html(results: dict) -> str:
    esc, status = html.escape, _status(results)
    parts = ["<h2>1. Built-in equivalence</h2>"]
    for r in results["equivalence"]:
        t = r["test"]
        verdict = ("identical up to noise" if t["identical"] else
                   f"differs: {t['significant_pixels']} of {t['pixels']} pixels significant")
        parts.append(
            f"<h3>{esc(r['title'])}</h3><p>Expected: {esc(r['expected'])}. "
            f"Measured: <span class='{status['equivalence/' + r['id']]}'>{esc(verdict)}</span> "
            f"(Welch t-test per pixel, Bonferroni α/N = {t['bonferroni_alpha']:.2g}, "
            f"min p = {t['min_p']:.3g}); "
            f"mean relative difference {100 * t['mean_relative_difference']:.3f} %; "
            f"RMSE {r['metrics']['rmse']:.4g}, FLIP {r['metrics']['flip']:.4g}.</p>"
            + _figures(r["files"]))
    if results.get("fresnel"):
        parts.append(
            "<h3>Exact Fresnel: cook_torrance's lobe is roughplastic's</h3>"
            f"<p>At {results['fresnel'][0]['pairs']:,} random direction pairs (wi, wo) on the "
            "upper hemisphere: eval of <code>cook_torrance</code> (k = 0, Smith G, GGX) with "
            "<code>fresnel=\"dielectric\"</code>, and with the lecture's Schlick F, against eval "
            "of <code>roughplastic</code> (diffuse_reflectance 0, the same η). Largest "
            "difference relative to the largest value, and the range of "
            "F_dielectric / F_Schlick (transcribed in NumPy) over the pairs:</p>"
            "<table><tr><th>α</th><th>fresnel=\"dielectric\"</th>"
            "<th>with Schlick's F</th><th>F ratio range</th></tr>")
        for r in results["fresnel"]:
            cls = status[f"equivalence/{r['id']}"]
            parts.append(f"<tr><td>{r['alpha']:g}</td><td class='{cls}'>{r['exact']:.2g}</td>"
                         f"<td>{r['schlick']:.3g}</td><td>{r['ratio_range'][0]:.3f} – "
                         f"{r['ratio_range'][1]:.3f}</td></tr>")
        parts.append("</table><p>So the render difference of the Schlick form against "
                     "roughplastic above is the measured effect of Schlick's approximation.</p>")
    return "".join(parts)


def furnace_html(results: dict) -> str:
    esc, status = html.escape, _status(results)
    parts = ["<h2>2. White furnace</h2><p>Rows <i>hdr, compensated</i> are the same "
             "configuration with <code>energy_compensation</code>: its albedo is 1 "
             "where its lobes are white (checked against 1 where its cases promise "
             "it); a lobe's colour scales its compensated albedo linearly (m_S = 0.5 "
             "reflects 0.5), Fresnel being the only per-bounce reflectance (section 5). "
             "The scan-line rows are the lecture's clamped formulas (no 1/π): an albedo "
             "above 1 there is by design.</p><table><tr><th>model</th><th>configuration</th>"
             "<th>mode</th><th>max albedo</th><th>at θ_i</th><th>mean</th><th>min</th>"
             "<th>|render − quadrature|</th><th>flag</th></tr>"]
    for r in results["furnace"]:
        cls = status[f"furnace/{r['model']}/{r['config']}/{r['mode']}/energy"]
        if r.get("promised"):
            flag = (f"= 1 within {100 * r['deviation']:.2f} % up to {PRESERVED_UP_TO:g}°")
        elif r["exceeds_1"]:
            flag = f"exceeds 1 by {100 * (r['max'] - 1):.1f} % at {r['max_at']:g}°"
            if cls == "documented":
                flag += " (by design)"
        elif r["loses_energy"]:
            flag = f"loses {100 * (1 - r['max']):.1f} % or more"
        else:
            flag = "≤ 1"
        parts.append(f"<tr><td>{esc(r['model'])}</td><td>{esc(r['config'])}</td><td>{r['mode']}</td>"
                     f"<td>{r['max']:.4f}</td><td>{r['max_at']:g}°</td><td>{r['mean']:.4f}</td>"
                     f"<td>{r['min']:.4f}</td><td>{r['render_vs_quadrature']:.4f}</td>"
                     f"<td class='{cls}'>{flag}</td></tr>")
    plots = sorted({r["plot"] for r in results["furnace"]})
    parts.append("</table>" + pages.figures((p, "furnace: albedo against θ_i") for p in plots))
    return "".join(parts)


def sampling_html(results: dict) -> str:
    esc, status = html.escape, _status(results)
    parts = ["<h2>3. Sampling</h2><p>Mitsuba's χ² test, the density integrated per "
             "histogram cell until it converges (<i>ires</i>: the most points per cell and "
             "axis a cell needed); Šidák-corrected over every χ² test of the report.</p>"
             "<table><tr><th>model</th><th>configuration</th><th>θ_i</th><th>χ² p-value</th>"
             "<th>ires</th><th>verdict</th><th>mean weight</th><th>weight variance</th></tr>"]
    for r in results["sampling"]:
        cls = status[f"sampling/{r['model']}/{r['config']}/{r['theta']:g}"]
        parts.append(f"<tr><td>{esc(r['model'])}</td><td>{esc(r['config'])}</td>"
                     f"<td>{r['theta']:g}°</td><td>{r['p_value']:.3g}</td><td>{r['ires']}</td>"
                     f"<td class='{cls}'>{LABELS[cls]}</td><td>{r['weight_mean']:.4g}</td>"
                     f"<td>{r['weight_variance']:.4g}</td></tr>")
    parts.append("</table>")
    if results.get("negative"):
        parts.append("<h3>Negative controls</h3><p>The sampler of one configuration against "
                     "the pdf of a slightly different one: the test must reject it.</p>"
                     "<table><tr><th>model</th><th>difference</th><th>θ_i</th>"
                     "<th>χ² p-value</th><th>verdict</th></tr>")
        for r in results["negative"]:
            cls = status[f"sampling/{r['model']}/negative control"]
            parts.append(f"<tr><td>{esc(r['model'])}</td><td>{esc(r['config'])}</td>"
                         f"<td>{r['theta']:g}°</td><td>{r['p_value']:.3g}</td><td class='{cls}'>"
                         f"{'rejected' if r['rejected'] else 'NOT rejected'}</td></tr>")
        parts.append("</table>")
    return "".join(parts)


def lobes_html(results: dict) -> str:
    return ("<h2>4. Lobes (eval = f·cos θ_o in the plane of incidence; viewer on the left)"
            "</h2>" + pages.figures((r["plot"], f"{r['model']} lobes") for r in results["lobes"]))


def groundtruth_html(results: dict) -> str:
    return ("<h2>5. Ground truth: the random walk</h2>"
            + groundtruth.report_html(results.get("groundtruth", [])))


SECTIONS_HTML = (equivalence_html, furnace_html, sampling_html, lobes_html, groundtruth_html)


def _anchored(section_html: str, anchor: str) -> tuple[str, str]:
    """(the section with an id on its heading, the heading's text)."""
    heading = section_html[len("<h2>"):section_html.index("</h2>")]
    return f"<h2 id='{anchor}'>" + section_html[len("<h2>"):], heading


def html_page(results: dict) -> str:
    """The report's page: the run, its contents, the summary, then each section."""
    esc = html.escape
    sections = [_anchored(section(results), f"section-{i}")
                for i, section in enumerate(SECTIONS_HTML, 1)]
    contents = ("<nav class='contents'><b>Contents</b><ol>"
                "<li><a href='#summary'>Summary</a></li>"
                + "".join(f"<li><a href='#section-{i}'>{heading.split('. ', 1)[-1].split(' (')[0]}</a></li>"
                          for i, (_, heading) in enumerate(sections, 1))
                + "</ol></nav>")
    body = (f"<p>{esc(results['size'])} run, {results['seconds']:.0f} s; Mitsuba "
            f"{esc(results['mitsuba'])}, variant {esc(results['variant'])}. Statistical tests "
            f"at α = {ALPHA}.</p>{contents}{_summary_html(results)}"
            + "".join(text for text, _ in sections))
    return pages.page("mi_brdfs validation", body, CSS)
