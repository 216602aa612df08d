"""What ``mi-brdfs fit -o DIR`` writes (a report folder, :mod:`..outputs`):

``fits.json``
    a list of records, one per target × model: ``target`` (as given),
    ``model``, ``plugin``, ``parameters`` (the fitted material: plugin
    properties, options included; ``{"type": plugin, **parameters}`` loads
    it), ``brdf_error`` (:mod:`.metric`: 0 identical, 1 a black BSDF's error),
    ``image_relmse`` and ``image_flip`` (the fitted model's render against the
    target's in the standard scene, same seed and spp), ``cost_ratio``
    (render time over the target's, same scene and spp, side by side) and
    ``seconds`` (the fit's wall time), and more: ``metric``,
    ``image_noise_relmse`` (the target against itself at another seed: the
    noise floor of ``image_relmse``), ``xml``, ``render_seconds``,
    ``start_errors``; a failed fit has an ``error`` message instead.
``fits.csv``
    the same records, one row each, parameters as JSON.
``index.html``
    per target: the Pareto plot of BRDF error against cost, the table, the
    renders side by side and the lobe slices (``eval`` in the plane of
    incidence at four viewer angles, the target and the models on the front).
``TARGET__MODEL.xml``
    each fitted material as a ``<bsdf>`` that ``mi.load_file`` loads as
    written; ``TARGET__MODEL.png`` its render, ``TARGET.png`` the target's.
"""
from __future__ import annotations

import csv
import html
import json
import math
import os

import numpy as np

from ...render import tonemap
from . import models as M
from .targets import slug

FIELDS = ("target", "model", "plugin", "parameters", "brdf_error", "image_relmse", "image_flip",
          "cost_ratio", "seconds")
EXTRA = ("metric", "image_noise_relmse", "xml", "render_seconds", "start_errors", "error")
TONEMAP = "aces"


def file_stem(record: dict) -> str:
    return f"{record['target_name']}__{slug(record['model'].replace('+', '-'), 64)}"


def clean(record: dict) -> dict:
    """The JSON record: FIELDS, then EXTRA where present."""
    out = {k: record.get(k) for k in FIELDS}
    if "starts" in record:
        record = {**record, "start_errors": [s["error"] for s in record["starts"]]}
    out.update({k: record[k] for k in EXTRA if record.get(k) is not None})
    return out


def pareto(points: list[tuple[float, float]]) -> list[bool]:
    """For (cost, error) points: True where no other point is at least as cheap
    and as accurate and strictly better in one."""
    return [not any(c2 <= c and e2 <= e and (c2 < c or e2 < e)
                    for j, (c2, e2) in enumerate(points) if j != i)
            for i, (c, e) in enumerate(points)]


def _figure(width, height):
    from matplotlib.figure import Figure      # no pyplot: no global backend change
    return Figure(figsize=(width, height), dpi=100)


def pareto_plot(path: str, title: str, rows: list[dict]) -> None:
    fig = _figure(6.4, 4.4)
    ax = fig.subplots()
    pts = [(r["cost_ratio"], r["brdf_error"]) for r in rows]
    front = pareto(pts)
    for r, (c, e), on in zip(rows, pts, front):
        ax.scatter([c], [max(e, 1e-6)], s=28 if on else 14,
                   color="C3" if on else "C0", zorder=3 if on else 2)
        if on:
            ax.annotate(r["model"], (c, max(e, 1e-6)), fontsize=7, xytext=(4, 3),
                        textcoords="offset points")
    line = sorted((c, max(e, 1e-6)) for (c, e), on in zip(pts, front) if on)
    if line:
        ax.plot(*zip(*line), color="C3", lw=1, alpha=0.6, label="Pareto front")
        ax.legend(fontsize=8)
    costs = [c for c, _ in pts]
    if max(costs) > 4 * min(costs):           # else a log axis has no labelled decade
        ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("render cost / target's (same scene and spp)")
    ax.set_ylabel("BRDF error (1 = black)")
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    fig.savefig(path, bbox_inches="tight")


def slice_plot(path: str, title: str, target_record: dict, rows: list[dict]) -> None:
    angles = target_record["slices"]["angles"]
    fig = _figure(3.2 * len(angles), 3.0)
    axes = fig.subplots(1, len(angles))
    theta = np.linspace(-89.5, 89.5, len(target_record["slices"]["target"][0]))
    for k, (ax, a) in enumerate(zip(axes, angles)):
        ax.plot(theta, target_record["slices"]["target"][k], color="black", lw=2, label="target")
        for i, r in enumerate(rows):
            ax.plot(theta, r["slices"]["model"][k], lw=1, color=f"C{i % 10}", label=r["model"])
        ax.set_title(f"viewer at θ = {a:g}° (mirror side > 0)", fontsize=8)
        ax.set_xlabel("light θ (degrees)", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0].set_ylabel("eval (f·cos θ), channel mean", fontsize=8)
    axes[-1].legend(fontsize=6)
    fig.suptitle(title, fontsize=9)
    fig.savefig(path, bbox_inches="tight")


def write(out: str, records: list[dict], settings, command: str) -> None:
    """Every file of the report into the folder ``out`` (a temporary one)."""
    by_target: dict[str, list[dict]] = {}
    for r in records:
        by_target.setdefault(r["target_name"], []).append(r)
    for r in records:
        if "error" in r:
            continue
        stem = file_stem(r)
        r["xml"] = stem + ".xml"
        with open(os.path.join(out, r["xml"]), "w") as f:
            f.write(M.xml(r["parameters"]))
        images = r.get("images")
        if images is not None:
            tonemap.write_png(os.path.join(out, stem + ".png"), images["model"], TONEMAP)
            target_png = os.path.join(out, r["target_name"] + ".png")
            if not os.path.exists(target_png):
                tonemap.write_png(target_png, images["target"], TONEMAP)
    sections = []
    for name, rows in by_target.items():
        sections.append(_section(out, name, rows))
    with open(os.path.join(out, "fits.json"), "w") as f:
        json.dump([clean(r) for r in records], f, indent=1)
    with open(os.path.join(out, "fits.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(FIELDS + ("image_noise_relmse", "xml", "error"))
        for r in records:
            w.writerow([json.dumps(r.get(k)) if k == "parameters" else r.get(k)
                        for k in FIELDS + ("image_noise_relmse", "xml", "error")])
    with open(os.path.join(out, "index.html"), "w") as f:
        f.write(_html(sections, settings, command))


def _fmt(x, spec=".3g") -> str:
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def _section(out: str, name: str, rows: list[dict]) -> str:
    ok = [r for r in rows if "error" not in r]
    failed = [r for r in rows if "error" in r]
    title = html.escape(rows[0]["target"])
    parts = [f'<h2 id="{name}">{title}</h2>']
    if not ok:
        parts.append("<p>every fit failed.</p>")
    ok.sort(key=lambda r: r["brdf_error"])
    measured = [r for r in ok if r.get("cost_ratio") is not None]
    front_models = set()
    if measured:
        pareto_plot(os.path.join(out, f"{name}__pareto.png"), rows[0]["target"], measured)
        parts.append(f'<img src="{name}__pareto.png" alt="Pareto plot">')
        front = pareto([(r["cost_ratio"], r["brdf_error"]) for r in measured])
        front_models = {r["model"] for r, on in zip(measured, front) if on}
    head = ("<tr><th>model</th><th>BRDF error</th><th>image relMSE</th><th>FLIP</th>"
            "<th>cost ×</th><th>fit s</th><th>parameters</th><th>XML</th></tr>")
    body = []
    for r in ok:
        params = ", ".join(f"{k}={_short(v)}" for k, v in r["parameters"].items()
                           if k not in ("type", "mode"))
        mark = " ★" if r["model"] in front_models else ""
        body.append(f"<tr><td>{html.escape(r['model'])}{mark}</td><td>{_fmt(r['brdf_error'], '.4g')}</td>"
                    f"<td>{_fmt(r.get('image_relmse'))}</td><td>{_fmt(r.get('image_flip'))}</td>"
                    f"<td>{_fmt(r.get('cost_ratio'), '.2f')}</td><td>{_fmt(r['seconds'], '.1f')}</td>"
                    f"<td class=p>{html.escape(params)}</td>"
                    f'<td><a href="{r["xml"]}">xml</a></td></tr>')
    for r in failed:
        body.append(f"<tr><td>{html.escape(r['model'])}</td><td colspan=7>FAILED: "
                    f"{html.escape(r['error'])}</td></tr>")
    parts.append(f"<table>{head}{''.join(body)}</table>")
    noise = [r["image_noise_relmse"] for r in ok if r.get("image_noise_relmse") is not None]
    if noise:
        parts.append(f"<p>Noise floor of the image relMSE (the target against itself, another "
                     f"seed): {_fmt(float(np.median(noise)))}. ★: on the Pareto front.</p>")
    if any(r.get("images") is not None for r in ok):
        cells = [f'<figure><img src="{name}.png"><figcaption>target</figcaption></figure>']
        cells += [f'<figure><img src="{file_stem(r)}.png"><figcaption>{html.escape(r["model"])}'
                  f"<br>{_fmt(r['brdf_error'], '.3g')}</figcaption></figure>"
                  for r in ok if r.get("images") is not None]
        parts.append(f'<div class="renders">{"".join(cells)}</div>')
    if ok and "slices" in ok[0]:
        shown = [r for r in ok if r["model"] in front_models] or ok[:4]
        slice_plot(os.path.join(out, f"{name}__slices.png"), rows[0]["target"], ok[0], shown)
        parts.append(f'<img src="{name}__slices.png" alt="lobe slices" class="wide">')
    return "\n".join(parts)


def _short(v) -> str:
    if isinstance(v, list):
        return "[" + ", ".join(f"{c:.3g}" for c in v) + "]"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def _html(sections: list[str], settings, command: str) -> str:
    s = settings
    return f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>mi-brdfs fit</title>
<style>
body {{ font-family: sans-serif; margin: 2em; }}
table {{ border-collapse: collapse; font-size: 0.85em; margin: 1em 0; }}
td, th {{ border: 1px solid #ccc; padding: 2px 6px; text-align: right; }}
td:first-child, td.p {{ text-align: left; }}
td.p {{ font-size: 0.85em; max-width: 40em; }}
.renders {{ display: flex; flex-wrap: wrap; gap: 4px; }}
figure {{ margin: 0; text-align: center; font-size: 0.7em; }}
.renders img {{ width: 160px; image-rendering: pixelated; }}
img.wide {{ max-width: 100%; }}
</style></head><body>
<h1>mi-brdfs fit</h1>
<p><code>{html.escape(command)}</code></p>
<p>Each course model (hdr mode) fitted to each target by Adam from {s.starts} starts,
{s.steps} steps, on the <b>{s.metric}</b> metric's direction pairs ({s.viewers[0]}×{s.viewers[1]}
viewers; per viewer {s.uniform[0]}×{s.uniform[1]} uniform lights and {s.lobe} mirror-guided ones
per roughness). BRDF error: 0 identical, 1 a black BSDF's error. Images: a sphere under an
environment map and a key light, {s.res}² pixels, {s.spp} spp, both at the same seed;
render cost: the model's render time over the target's, measured side by side
({s.rounds} rounds). See <code>docs/guide/fit.md</code>.</p>
{''.join(sections)}
</body></html>
"""
