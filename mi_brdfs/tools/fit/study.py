"""Which objective the fit should minimise, measured:
``python -m mi_brdfs.tools.fit.study -o DIR [--quick] [-j N]``.

Every objective of :data:`.metric.OBJECTIVES` (``linear``: the BRDF metric
itself; ``cbrt``, ``log``: compressed values) fits the models of
:data:`MODELS` to the trade sweep's materials (:data:`.trade.TARGETS`); each
fit is rendered in the standard views and ranked by FLIP (:mod:`.rank`). Per
objective, ``objectives.md`` gives

- the share of the objective's weight within 10° of the horizon (either
  direction), median over the materials: where the metric looks;
- per material, the best FLIP among the fits and the FLIP of the fit of the
  material's own family (the microfacet model with its distribution);
- for the conductors, the largest channel difference between the
  first-ranked fit's colour at normal incidence (its specular colour at 0°,
  :func:`.effective.parameters`) and the target's F0
  (:func:`.effective.conductor_f0`).

No render cost is measured (it does not depend on the objective).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys

import numpy as np

from .. import destinations
from ..errors import one_line
from . import effective, metric, models as M, rank, sweep, targets as T, trade
from .optimise import problem
from .sweep import progress_printer
from .task import FULL, QUICK

MODELS = ("lambert", "oren_nayar", "phong", "blinn", "ward", "cook_torrance/beckmann/cook_torrance",
          "cook_torrance/beckmann/smith", "cook_torrance/ggx/smith")
GRAZING_DEG = 80.0


def family(spec: str) -> str:
    """The course model of the target's own family: Cook-Torrance with Smith G
    and the target's distribution (Mitsuba's default Beckmann; principled: GGX)."""
    if spec.startswith("principled") or "distribution=ggx" in spec:
        return "cook_torrance/ggx/smith"
    if spec.startswith("diffuse"):
        return "lambert"
    return "cook_torrance/beckmann/smith"


def grazing_share(target, settings, objective: str) -> float:
    """The share of E²(0) (the objective's norm) from pairs with a direction
    within 10° of the horizon."""
    p = metric.pairs(settings.metric, settings.viewers, settings.uniform, settings.lobe)
    bsdf = target.load()
    prob = problem(bsdf, p, objective)
    del bsdf
    a = prob.arrays
    near = (p.wi[:, 2] < math.cos(math.radians(GRAZING_DEG))) | \
        (p.wo[:, 2] < math.cos(math.radians(GRAZING_DEG)))
    if objective == "linear":
        each = a["weight"] * np.sum(a["target"] ** 2, axis=1)
    else:
        each = a["shown"] * np.sum(a["target_c"] ** 2, axis=1)
    return float(np.sum(each[near]) / np.sum(each))


def run_study(quick: bool = False, jobs: int = 2, show=None, targets=None) -> dict:
    """Fits, renders and measures per objective (see the module docstring)."""
    base = (QUICK if quick else FULL).replace(cost=False)
    chosen = [spec for _, spec in (targets or trade.TARGETS)]
    parsed = T.parse(chosen)
    models = M.select(list(MODELS))
    out = {"targets": chosen, "models": list(MODELS), "objectives": {}}
    for objective in metric.OBJECTIVES:
        settings = base.replace(objective=objective)
        records = sweep.run_fits([(t, m) for t in parsed for m in models], settings, jobs=jobs,
                                 show=show)
        rows = []
        for t in parsed:
            mine = [r for r in records if r["target_name"] == t.name]
            order = rank.ranked(mine)
            own = next((r for r in order if r["model"] == family(t.spec)), None)
            f0 = effective.conductor_f0(t)
            first = order[0] if order else None
            colour = None if first is None else effective.normal_colour(first)
            rows.append({"target": t.spec, "first": first and first["model"],
                         "first_flip": first and first["image_flip"],
                         "best_flip": min(rank.quality(r) for r in order) if order else None,
                         "own": own and own["model"], "own_flip": own and own["image_flip"],
                         "own_brdf_error": own and own["brdf_error"],
                         "f0": f0, "first_f0": colour,
                         "f0_error": (None if f0 is None or colour is None else
                                      float(np.max(np.abs(np.array(colour) - np.array(f0))))),
                         "grazing_share": grazing_share(t, settings, objective)})
        out["objectives"][objective] = rows
    return out


def table(results: dict) -> str:
    """objectives.md: one summary row per objective, then one row per material."""
    lines = ["| objective | weight within 10° of the horizon (median) | best FLIP (mean) | "
             "own family's FLIP (mean) | conductors: first-ranked F0 error (max) |",
             "|---|---|---|---|---|"]
    for objective, rows in results["objectives"].items():
        share = statistics.median(r["grazing_share"] for r in rows)
        best = statistics.fmean(r["best_flip"] for r in rows if r["best_flip"] is not None)
        own = statistics.fmean(r["own_flip"] for r in rows if r["own_flip"] is not None)
        f0 = [r["f0_error"] for r in rows if r["f0_error"] is not None]
        worst = f"{max(f0):.3f}" if f0 else "–"
        lines.append(f"| `{objective}` | {share:.2f} | {best:.3f} | {own:.3f} | {worst} |")
    lines += ["", "| material | " + " | ".join(
        f"`{o}`: first-ranked (FLIP) · F0 error" for o in results["objectives"]) + " |",
        "|---|" + "---|" * len(results["objectives"])]
    for i, spec in enumerate(results["targets"]):
        cells = []
        for rows in results["objectives"].values():
            r = rows[i]
            f0 = "" if r["f0_error"] is None else f" · {r['f0_error']:.3f}"
            cells.append(f"{r['first']} ({r['first_flip']:.3f}){f0}")
        lines.append(f"| `{spec}` | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m mi_brdfs.tools.fit.study",
                                description="Measure the fit's objectives (see the module).")
    p.add_argument("-o", "--output", required=True, help="report folder: new, empty, or a previous one")
    p.add_argument("--quick", action="store_true", help="fewer pairs and pixels")
    p.add_argument("-j", "--jobs", type=int, default=2, help="fits at once (default 2)")
    args = p.parse_args(argv)
    try:
        destinations.check_report_dir(args.output)
        show = progress_printer(p.prog)
        results = run_study(args.quick, args.jobs, show)
        show.close()
        with destinations.report_dir(args.output, "fit-study") as tmp:
            with open(os.path.join(tmp, "objectives.json"), "w") as f:
                json.dump(results, f, indent=1)
            with open(os.path.join(tmp, "objectives.md"), "w") as f:
                f.write(table(results))
    except Exception as error:
        print(f"{p.prog}: error: {one_line(error)}", file=sys.stderr)
        return 1
    print(table(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
