"""What ``mi-brdfs fit -o DIR`` writes (a report folder, :mod:`..destinations`):

``fits.json``
    a list of records, one per target × model, in rank order per target:
    ``target`` (as given), ``model``, ``plugin``, ``rank`` (1 = first,
    :mod:`.rank`), ``parameters`` (the fitted material: plugin properties,
    options included; ``{"type": plugin, **parameters}`` loads it),
    ``image_flip`` and ``image_relmse`` (the fitted model's renders against
    the target's, mean over the standard views, same seed and spp;
    ``image_views`` per view), ``brdf_error`` (the ``metric``'s L² distance
    over a black BSDF's: 0 identical, 1 as far as black, above 1 farther), ``objective`` and
    ``objective_error`` (what the fit minimised, and its value), ``cost_ratio``
    with ``cost_low`` and ``cost_high`` (render time over the target's: the
    90 % interval, :mod:`.cost`), ``ops_ratio`` (traced operations over the
    target's) and ``seconds`` (the fit's wall time), and more: ``effective``
    (the colours that matter, :mod:`.effective`), ``albedo`` and
    ``target_albedo`` ([0°, 60°, 85°][R, G, B]), ``image_noise_flip`` and
    ``image_noise_relmse`` (the target against itself at another seed: the
    seed noise, the tolerance of "looks the same", :mod:`.rank`),
    ``noise_ratio`` with ``noise_low`` and ``noise_high`` (the pixel variance
    at equal samples over the target's, 90 %: :func:`.scene.variance_ratio`;
    ``noise_seeds`` renders at ``noise_spp`` each), ``time_to_noise`` (the
    time to the target's noise over the target's, [ratio, low, high]:
    :func:`.rank.time_to_noise`, the cost the verdict compares; absent in
    records made before the variance was measured),
    ``cost_rounds``, ``cost_timing`` (what a round timed: :data:`.cost.TIMINGS`),
    ``cost_spp`` (a timed render's samples per pixel; absent: the views' ``spp``),
    ``cost_closed`` (the interval reached the tolerance),
    ``cost_load`` and ``cost_cores`` (the machine's load average when it was
    timed, and its cores), ``ops``, ``reruns`` and ``worker`` (a task re-run
    after its Dask worker was lost), ``target_features``, ``xml``,
    ``renders``, ``start_errors``; a failed fit has ``error`` instead.
``fits.csv``
    the main fields, one row each, parameters and effective colours as JSON.
``index.html``
    per target: the verdict, what the target has that no model has (when
    none comes close), the Pareto plot of image error against cost, the table
    in rank order, the renders (the three views side by side) and the lobe
    slices per colour channel.
``TARGET__MODEL.xml``
    each fitted material as a ``<bsdf>`` that ``mi.load_file`` loads as
    written; ``TARGET__MODEL.jpg`` its renders, ``TARGET.jpg`` the target's.
"""
from __future__ import annotations

import csv
import html
import json
import math
import os
import re

from .. import pages
from . import effective, models as M, plots, rank
from .scene import VIEWS
from .targets import slug

FIELDS = ("target", "model", "plugin", "rank", "parameters", "image_flip", "image_relmse",
          "brdf_error", "metric", "objective", "objective_error", "cost_ratio", "cost_low",
          "cost_high", "ops_ratio", "seconds")
EXTRA = ("image_views", "image_noise_flip", "image_noise_relmse", "noise_ratio", "noise_low",
         "noise_high", "noise_seeds", "noise_spp", "time_to_noise", "effective", "albedo",
         "target_albedo", "cost_rounds", "cost_closed", "cost_aim", "cost_load", "cost_cores", "ops",
         "cost_timing", "cost_spp", "reruns", "worker",
         "target_features", "xml", "renders", "start_errors", "error", "cost_error")
CSV_EXTRA = ("effective", "image_noise_flip", "noise_ratio", "noise_low", "noise_high",
             "time_to_noise", "cost_rounds", "cost_load", "reruns", "xml", "error")
TONEMAP = "aces"


def file_stem(record: dict) -> str:
    return f"{record['target_name']}__{slug(record['model'].replace('+', '-'), 64)}"


def clean(record: dict) -> dict:
    """The JSON record: FIELDS, then EXTRA where present."""
    out = {k: record.get(k) for k in FIELDS}
    if "starts" in record:
        record = {**record, "start_errors": [s["objective"] for s in record["starts"]]}
    out.update({k: record[k] for k in EXTRA if record.get(k) is not None})
    return out


def write(out: str, records: list[dict], settings, command: str, features: dict | None = None
          ) -> list[dict]:
    """Every file of the report into the folder ``out`` (a temporary one);
    the records in the report's order (targets as given, fits in rank order,
    failed fits last), each with its ``rank``."""
    timed = [r for r in records if r.get("cost_ratio") is not None]
    if timed and "cost_timing" not in timed[0]:   # records timed before cost_timing existed:
        settings = settings.replace(cost_timing="wall", cost_rounds=(6, 40),  # by wall clock
                                    cost_tolerance=rank.EARLIER_AIM - 1.0)
    if timed and "cost_spp" not in timed[0]:      # timed before cost_spp: at the views' spp
        settings = settings.replace(cost_spp=settings.spp)
    by_target: dict[str, list[dict]] = {}
    for r in records:
        by_target.setdefault(r["target_name"], []).append(r)
    ordered = []
    for name, rows in by_target.items():
        ranks = rank.ranked(rows)
        for i, r in enumerate(ranks, 1):
            r["rank"] = i
            if features and name in features:
                r["target_features"] = features[name]
        ordered += ranks + [r for r in rows if "error" in r]
    for r in ordered:
        if "error" in r:
            continue
        if rank.time_to_noise(r) is not None:
            r["time_to_noise"] = list(rank.time_to_noise(r))
        stem = file_stem(r)
        r["xml"] = stem + ".xml"
        with open(os.path.join(out, r["xml"]), "w") as f:
            f.write(M.xml(r["parameters"]))
        images = r.get("images")
        if images is not None:
            r["renders"] = stem + ".jpg"
            plots.views_strip(os.path.join(out, r["renders"]), images["model"], TONEMAP)
            target_jpg = os.path.join(out, r["target_name"] + ".jpg")
            if not os.path.exists(target_jpg):
                plots.views_strip(target_jpg, images["target"], TONEMAP)
    sections = [_section(out, name, [r for r in ordered if r["target_name"] == name],
                         (features or {}).get(name)) for name in by_target]
    with open(os.path.join(out, "fits.json"), "w") as f:
        json.dump([clean(r) for r in ordered], f, indent=1)
    with open(os.path.join(out, "fits.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(FIELDS + CSV_EXTRA)
        for r in ordered:
            w.writerow([json.dumps(r.get(k)) if k in ("parameters", "effective") else r.get(k)
                        for k in FIELDS + CSV_EXTRA])
    contents = [(name, label(rows[0]["target"])) for name, rows in by_target.items()]
    with open(os.path.join(out, "index.html"), "w") as f:
        f.write(_html(sections, settings, command, contents))
    return ordered


# ----------------------------------------------------------------------------
#  HTML
# ----------------------------------------------------------------------------

def _fmt(x, spec=".3g") -> str:
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def _rgb(c) -> str:
    return "–" if c is None else "(" + ", ".join(f"{v:.2f}" for v in c) + ")"


def _albedo(a) -> str:
    """Directional albedo per angle: its largest channel, flagged above 1."""
    if not a:
        return "–"
    cells = []
    for angle, rgb in zip(effective.ALBEDO_ANGLES, a):
        top = max(rgb)
        text = f"{angle:g}°: {top:.2f}"
        cells.append(f'<b class="over">{text}</b>' if top > 1.0 + 1e-3 else text)
    return "<br>".join(cells)


def _cost(r: dict) -> str:
    """The time per sample over the target's, with its 90 % interval."""
    if r.get("cost_ratio") is None:
        return "–" if "cost_error" not in r else f"failed: {html.escape(r['cost_error'])}"
    return f"{r['cost_ratio']:.2f} ({r['cost_low']:.2f}–{r['cost_high']:.2f})"


def _noise(r: dict) -> str:
    """The pixel variance at equal samples over the target's (90 %)."""
    if r.get("noise_ratio") is None:
        return "–"
    return "{} ({}–{})".format(*map(rank.times, (r["noise_ratio"], r["noise_low"],
                                                 r["noise_high"])))


def _to_noise(r: dict) -> str:
    """The time to the target's noise over the target's (90 %): the verdict's cost."""
    t = rank.time_to_noise(r)
    return "–" if t is None else "{} ({}–{})".format(*map(rank.times, t))


def _row(r: dict, front: set, equals: dict) -> str:
    e = r.get("effective") or {}
    params = ", ".join(f"{k}={_short(v)}" for k, v in r["parameters"].items()
                       if k not in ("type", "mode"))
    mark = " ★" if r.get("rank") == 1 else (" ◇" if r["model"] in front else "")
    note = []
    if equals.get(r["model"]):
        note.append("same cost class: " + ", ".join(equals[r["model"]]))
    if r.get("reruns"):
        note.append(f"re-run after its worker was lost ({r['reruns']}×), finished on {r['worker']}")
    note += e.get("notes", [])
    return (f"<tr><td>{r['rank']}</td><td>{html.escape(r['model'])}{mark}</td>"
            f"<td>{_fmt(r.get('image_flip'))}</td><td>{_fmt(r.get('image_relmse'))}</td>"
            f"<td>{_fmt(r['brdf_error'], '.4g')}</td><td>{_fmt(r.get('objective_error'), '.4g')}</td>"
            f"<td>{_to_noise(r)}</td><td>{_cost(r)}</td><td>{_noise(r)}</td>"
            f"<td>{_fmt(r.get('ops_ratio'), '.2f')}</td>"
            f"<td>{_rgb(e.get('diffuse'))}</td><td>{_rgb(e.get('specular_0'))}<br>"
            f"{_rgb(e.get('specular_85'))}</td><td>{_albedo(r.get('albedo'))}</td>"
            f"<td>{_fmt(r['seconds'], '.1f')}</td><td class=p>{html.escape(params)}"
            f"{'<br><i>' + html.escape('; '.join(note)) + '</i>' if note else ''}</td>"
            f'<td><a href="{r["xml"]}">xml</a></td></tr>')


TIMED = {"cpu": "CPU time (every thread's: the work, not the wait for a core)",
         "wall": "wall-clock time", "kernels": "kernel time (Dr.Jit's kernel history)"}
BRDF_ERROR = ("BRDF error: the L² distance of the fit's eval from the target's over the "
              "direction pairs (projected solid angle), over a black BSDF's: 0 identical, 1 as "
              "far as black. It is not bounded by 1: a lobe sharper or taller than the "
              "target's weighs in by its height squared while the image sees its integral, "
              "so a fit can be farther than black in L² and still look close")
TO_NOISE = ("time to render the sphere as clean as the target renders it, over the target's: "
            "time per sample × variance at equal samples; the cost the ranking, the front and "
            "the verdict compare (time per sample alone where the variance was not measured)")
PER_SAMPLE = "render time at equal samples over the target's, timed in turns (90 % interval)"
VARIANCE = ("pixel variance at equal samples over the target's, each relative to its own image "
            "(relMSE's noise term) over the sphere's pixels of the views, from renders at "
            "several seeds (90 %: bootstrap over the pixels); above 1 the model needs that "
            "many times the samples to be as clean")
HEAD = ("<tr><th>#</th><th>model</th><th>FLIP</th><th>image relMSE</th>"
        f'<th title="{html.escape(BRDF_ERROR)}">BRDF error (L², black = 1)</th>'
        "<th>objective</th>"
        f'<th title="{html.escape(TO_NOISE)}">time to the same noise × (90 %)</th>'
        f'<th title="{html.escape(PER_SAMPLE)}">time per sample × (90 %)</th>'
        f'<th title="{html.escape(VARIANCE)}">variance at equal samples × (90 %)</th>'
        "<th>ops ×</th><th>diffuse colour</th>"
        "<th>specular colour at 0° / 85°</th><th>albedo (max channel)</th><th>fit s</th>"
        "<th>parameters</th><th>XML</th></tr>")


def _section(out: str, name: str, rows: list[dict], found: dict | None) -> str:
    ok = [r for r in rows if "error" not in r]
    failed = [r for r in rows if "error" in r]
    title = html.escape(label(rows[0]["target"]))
    plugin = rank.target_plugin(rows[0]["target"])
    parts = [f'<h2 id="{html.escape(name)}">{title}</h2>',
             f'<p class=top><code>{html.escape(rows[0]["target"])}</code> · '
             '<a href="#top">↑ back to top</a></p>',
             f"<p class=verdict>{html.escape(rank.verdict(rows, plugin))}</p>"]
    if not ok:
        parts.append("<p>every fit failed.</p>")
    best = ok[0] if ok else None
    if best is not None and rank.quality(best) > rank.SMALL_FLIP and found:
        said = effective.describe(found)
        said += effective.known_reasons(plugin)
        parts.append(f"<p>No course model comes close (best FLIP {rank.quality(best):.3f}). "
                     + ("What the target has that none of them has: " + "; ".join(said) + "."
                        if said else "No feature the fit can name (spectral Fresnel, "
                        "anisotropy) was found in the target.") + "</p>")
    front = {r["model"] for r in rank.front(ok)}
    equals = {r["model"]: [o["model"] for o in ok if o is not r and o["model"] in front
                           and rank.equal_cost(r, o)] for r in ok if r["model"] in front}
    if any(r.get("cost_ratio") is not None for r in ok):
        plots.pareto_plot(os.path.join(out, f"{name}__pareto.png"), label(rows[0]["target"]),
                          ok)
        parts.append(f'<img src="{name}__pareto.png" alt="Pareto plot">')
    body = [_row(r, front, equals) for r in ok]
    body += [f"<tr><td></td><td>{html.escape(r['model'])}</td><td colspan=14>FAILED: "
             f"{html.escape(r['error'])}</td></tr>" for r in failed]
    parts.append(f"<table>{HEAD}{''.join(body)}</table>")
    if ok and ok[0].get("target_albedo"):
        parts.append(f"<p>The target's albedo (max channel): "
                     f"{_albedo(ok[0]['target_albedo']).replace('<br>', ', ')}. ")
    noise = [r["image_noise_flip"] for r in ok if r.get("image_noise_flip") is not None]
    if noise:
        parts.append(f"Seed noise (the target against itself at another seed): FLIP "
                     f"{_fmt(noise[0])}, relMSE {_fmt(ok[0].get('image_noise_relmse'))}: what "
                     "rendering the target again changes. It is no floor for the fits: each is "
                     "rendered at the target's own seed, so their noise largely cancels and a "
                     "close fit can read below it. It is the tolerance: a cheaper model looks "
                     "the same when its FLIP is within it of the best. ")
    if ok:
        parts.append("★: first-ranked; ◇: on the Pareto front (costs compare in classes a "
                     f"factor {1 + rank.COST_BAND:g} wide).</p>")
    if any(r.get("renders") for r in ok):
        cells = [f'<figure><img src="{name}.jpg"><figcaption>target</figcaption></figure>']
        cells += [f'<figure><img src="{r["renders"]}"><figcaption>{r["rank"]}. '
                  f"{html.escape(r['model'])}, FLIP {_fmt(r.get('image_flip'), '.3f')}"
                  "</figcaption></figure>" for r in ok if r.get("renders")]
        parts.append(f'<div class="renders">{"".join(cells)}</div>')
    if ok and "slices" in ok[0]:
        plots.slice_plot(os.path.join(out, f"{name}__slices.png"), rows[0]["target"], ok[0], ok)
    if ok and os.path.exists(os.path.join(out, f"{name}__slices.png")):   # or drawn by the run
        parts.append(f'<figure class="slices"><a href="{name}__slices.png" title="full size">'
                     f'<img src="{name}__slices.png" alt="lobe slices of {title}"></a>'
                     "<figcaption>lobe slices per colour channel: click for full size"
                     "</figcaption></figure>")
    return "\n".join(parts)


def label(spec: str) -> str:
    """A target's short label for a heading: the trade sweep's own (``Au α0.1``)
    for its materials, else the plugin and its values (``roughconductor, Au,
    alpha 0.1``), a file target by its file name."""
    from .trade import TARGETS                    # trade imports this module
    known = {s: name for name, s in TARGETS}
    if spec in known:
        return known[spec]
    if ":" not in spec:
        return os.path.basename(spec)
    plugin, _, rest = spec.partition(":")
    values = [item.partition("=") for item in re.split(r",(?![^\[]*\])", rest) if item]
    return ", ".join([plugin] + [v if k == "material" else f"{k} {v}" for k, _, v in values])


def _short(v) -> str:
    if isinstance(v, list):
        return "[" + ", ".join(f"{c:.3g}" for c in v) + "]"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


FIT_CSS = """
table { font-size: 0.8em; }
td:nth-child(2), td.p { text-align: left; }
td.p { font-size: 0.85em; max-width: 36em; }
.verdict { font-weight: bold; }
.over { color: #b00; }
.renders { display: flex; flex-wrap: wrap; gap: 6px; }
figure { text-align: center; font-size: 0.7em; }
.renders img { height: 96px; }
figure.slices img { width: 100%; max-width: 1200px; }
p.top { font-size: 0.8em; margin-top: -0.5em; }
"""


def _contents(contents: list[tuple[str, str]]) -> str:
    """The table of contents: a link to each target's section (its heading's id)."""
    items = "".join(f'<li><a href="#{html.escape(name)}">{html.escape(title)}</a></li>'
                    for name, title in contents)
    return f'<nav id="contents"><h2>Contents</h2><ol>{items}</ol></nav>\n'


def _html(sections: list[str], settings, command: str,
          contents: list[tuple[str, str]] = ()) -> str:
    """The page (the project's shared builder, :mod:`..pages`): the command,
    how the fits were made and measured, the table of contents (``contents``:
    each section's id and title), then a section per target, each with a
    link back to the top."""
    s = settings
    about = f"""<p id="top"><code>{html.escape(command)}</code></p>
<p>Each course model (hdr mode) fitted to each target on the <b>{s.objective}</b>-compressed
values of the <b>{s.metric}</b> metric's direction pairs ({s.viewers[0]}×{s.viewers[1]} viewers;
per viewer {s.uniform[0]}×{s.uniform[1]} uniform lights and {s.lobe} mirror-guided ones per
roughness): {s.scan} candidate shapes with their colours by least squares, the best {s.starts}
refined by Levenberg-Marquardt. Ranked by FLIP, the mean over the views
({", ".join(VIEWS)}: a sphere, {s.res}² pixels, {s.spp} spp, model and target at the same seed);
FLIP within {rank.TIE_FLIP} of the best counts as equal, the cheaper first. Costs compare by
class (a factor {1 + rank.COST_BAND:g} wide, class 0 as costly as the target): the ranking, the
front, the ★ and the verdict use that one rule. The verdict's cheaper model is the cheapest
whose FLIP is within the tolerance of the best: the target's seed noise (the target against
itself at another seed; {rank.LOOKS_SAME} without renders); if none is, it says so.
{html.escape(BRDF_ERROR, quote=False)}.
Cost, in three columns: the <b>time per sample</b>, the model's {TIMED.get(s.cost_timing, s.cost_timing)} over the target's
(the environment view at {s.cost_spp} spp), until the 90 % interval is within {s.cost_tolerance:.0%} or after
{s.cost_rounds[1]} rounds (at least {s.cost_rounds[0]}); the <b>variance at equal samples</b>,
the model's pixel variance over the target's, each relative to its own image (relMSE's noise
term over the sphere's pixels of the views, from {s.noise_seeds} renders each at {s.noise_spp}
spp; 90 % interval by a bootstrap over the pixels): a worse sampler needs that many times the
samples; and their product, the
<b>time to the same noise</b>, the cost the ranking, the front and the verdict compare (the
time per sample where the records have no variance, as the verdict says). The verdict says
when a timing interval did not close, and the load it was timed at; ops: Dr.Jit operations of
a traced eval and sample
over the target's. The documentation's fit guide explains each figure.</p>
"""
    return pages.page("mi-brdfs fit", about + _contents(list(contents)) + "".join(sections),
                      css=FIT_CSS)
