"""The speed/accuracy trade across the course models: ``mi-brdfs fit`` over a
fixed list of materials (:data:`TARGETS`) and the table "which model for
which material" (:func:`table`). A bench group runs it in one line::

    records = trade.run(os.path.join(out_dir, "trade"), quick=quick)

which writes the fit report there, with ``trade.md`` (the table) beside
``fits.json``. The targets: Mitsuba's ``roughconductor`` in gold, copper and
aluminium (spectral indices of refraction, through their RGB response in
``llvm_ad_rgb``) at α 0.1 and 0.3, ``roughplastic`` (a red-brown plastic) at
α 0.1 and 0.3, ``principled`` as a rough dielectric and as a brass-like
metal, and ``diffuse``. The conductors and plastics have Mitsuba's default
distribution (Beckmann); ``principled`` is GGX.
"""
from __future__ import annotations

import math
import os
import statistics

PLASTIC = "diffuse_reflectance=[0.6,0.2,0.1]"
TARGETS = (          # (label, target)
    ("Au α0.1", "roughconductor:material=Au,alpha=0.1"),
    ("Au α0.3", "roughconductor:material=Au,alpha=0.3"),
    ("Cu α0.1", "roughconductor:material=Cu,alpha=0.1"),
    ("Cu α0.3", "roughconductor:material=Cu,alpha=0.3"),
    ("Al α0.1", "roughconductor:material=Al,alpha=0.1"),
    ("Al α0.3", "roughconductor:material=Al,alpha=0.3"),
    ("plastic α0.1", f"roughplastic:alpha=0.1,{PLASTIC}"),
    ("plastic α0.3", f"roughplastic:alpha=0.3,{PLASTIC}"),
    ("principled dielectric", "principled:base_color=[0.8,0.25,0.1],roughness=0.4,specular=0.5"),
    ("principled metal", "principled:base_color=[0.9,0.75,0.4],roughness=0.25,metallic=1"),
    ("diffuse", "diffuse:reflectance=[0.7,0.5,0.3]"),
)


def run(out_dir: str, quick: bool = False, jobs: int = 1, scheduler: str | None = None,
        show=None, models: list[str] | None = None, targets=TARGETS) -> list[dict]:
    """Fit every model (or ``models``) to every target; the report, with
    ``trade.md``, goes to ``out_dir`` (a report folder)."""
    from . import fit
    labels = dict((spec, label) for label, spec in targets)

    def write_table(folder: str, records: list[dict]) -> None:
        with open(os.path.join(folder, "trade.md"), "w") as f:
            f.write(table(records, labels))

    return fit([spec for _, spec in targets], out_dir, models, quick=quick, jobs=jobs,
               scheduler=scheduler, show=show, command="mi_brdfs.tools.fit.trade.run",
               also=write_table)


def table(records: list[dict], labels: dict[str, str] | None = None) -> str:
    """"Which model for which material": a Markdown table, one row per model,
    its median render cost over the targets (× the target's) and, on each
    target, its BRDF error and the image's FLIP (``0.080 · 0.40``); the
    lowest BRDF error per target in bold."""
    labels = labels or {}
    specs = list(dict.fromkeys(r["target"] for r in records))
    models = list(dict.fromkeys(r["model"] for r in records))
    cell = {(r["target"], r["model"]): r for r in records}
    best = {}
    for s in specs:
        ok = [r for r in records if r["target"] == s and "error" not in r]
        if ok:
            best[s] = min(ok, key=lambda r: r["brdf_error"])["model"]
    head = ["model", "cost ×"] + [labels.get(s, s) for s in specs]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for m in models:
        costs = [cell[(s, m)].get("cost_ratio") for s in specs if (s, m) in cell]
        costs = [c for c in costs if c is not None and math.isfinite(c)]
        row = [f"`{m}`", f"{statistics.median(costs):.2f}" if costs else "–"]
        for s in specs:
            r = cell.get((s, m))
            if r is None or "error" in r:
                row.append("failed" if r else "–")
                continue
            text = f"{r['brdf_error']:.3f}"
            text = f"**{text}**" if best.get(s) == m else text
            flip = r.get("image_flip")
            row.append(text if flip is None else f"{text} · {flip:.2f}")
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines) + "\n"
