"""The speed/accuracy trade across the course models: ``mi-brdfs fit`` over a
fixed list of materials (:data:`TARGETS`) and the table "which model for
which material" (:func:`table`). The bench's ``trade`` group runs it in one
line, and so does ``python -m mi_brdfs.tools.fit.trade -o DIR [--quick] [-j N] [--materials LABEL ...]``
(the committed ``docs/benchmarks/trade``)::

    records = trade.fit_materials(os.path.join(out_dir, "trade"), quick=quick)

which writes the fit report there, with ``trade.md`` (the table) beside
``fits.json``. The targets: Mitsuba's ``roughconductor`` in gold, copper and
aluminium (spectral indices of refraction, through their RGB response in
``llvm_ad_rgb``) at α 0.1 and 0.3 (Beckmann, Mitsuba's default), gold at α
0.05 and chromium at α 0.15 (GGX), ``roughplastic`` (a red-brown plastic at
α 0.1 and 0.3, a blue one at α 0.15), ``principled`` as a rough dielectric
and as a brass-like metal (GGX), ``diffuse``, and brushed aluminium
(anisotropic GGX, α 0.05 along the tangent and 0.3 across it; the fit adds
anisotropic Ward and Cook-Torrance for it).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys

from ..errors import one_line
from . import effective, fit, rank, report, scene, targets as T
from .models import EC, names
from .sweep import progress_printer
from .task import FULL, QUICK

PLASTIC = "diffuse_reflectance=[0.6,0.2,0.1]"
TARGETS = (          # (label, target)
    ("Au α0.1", "roughconductor:material=Au,alpha=0.1"),
    ("Au α0.3", "roughconductor:material=Au,alpha=0.3"),
    ("Cu α0.1", "roughconductor:material=Cu,alpha=0.1"),
    ("Cu α0.3", "roughconductor:material=Cu,alpha=0.3"),
    ("Al α0.1", "roughconductor:material=Al,alpha=0.1"),
    ("Al α0.3", "roughconductor:material=Al,alpha=0.3"),
    ("Au α0.05 GGX", "roughconductor:material=Au,alpha=0.05,distribution=ggx"),
    ("Cr α0.15 GGX", "roughconductor:material=Cr,alpha=0.15,distribution=ggx"),
    ("plastic α0.1", f"roughplastic:alpha=0.1,{PLASTIC}"),
    ("plastic α0.3", f"roughplastic:alpha=0.3,{PLASTIC}"),
    ("blue plastic α0.15", "roughplastic:alpha=0.15,diffuse_reflectance=[0.1,0.2,0.6]"),
    ("principled dielectric", "principled:base_color=[0.8,0.25,0.1],roughness=0.4,specular=0.5"),
    ("principled metal", "principled:base_color=[0.9,0.75,0.4],roughness=0.25,metallic=1"),
    ("diffuse", "diffuse:reflectance=[0.7,0.5,0.3]"),
    ("brushed Al α0.05×0.3 GGX",
     "roughconductor:distribution=ggx,alpha_u=0.05,alpha_v=0.3,material=Al"),
)


def fit_materials(out_dir: str, quick: bool = False, jobs: int | None = None,
                  scheduler: str | None = None, show=None, models: list[str] | None = None,
                  targets=TARGETS, settings=None) -> list[dict]:
    """Fit every model (or ``models``) to every target; the report, with
    ``trade.md``, goes to ``out_dir`` (a report folder). ``jobs``: fits at
    once (default: one per core, at most 2, :func:`.sweep.default_jobs`; the
    costs are timed one at a time)."""
    labels = dict((spec, label) for label, spec in targets)

    def write_table(folder: str, records: list[dict]) -> None:
        walk = walk_flips([spec for _, spec in targets], settings or (QUICK if quick else FULL))
        with open(os.path.join(folder, WALK_FILE), "w", encoding="utf-8") as f:
            json.dump(walk, f, indent=1)
        with open(os.path.join(folder, "trade.md"), "w", encoding="utf-8") as f:
            f.write(subset_note(targets) + table(records, labels, walk))

    return fit([spec for _, spec in targets], out_dir, models, quick=quick, jobs=jobs,
               scheduler=scheduler, show=show, settings=settings,
               command="mi_brdfs.tools.fit.trade.fit_materials", also=write_table)


def subset_note(targets) -> str:
    """A line saying which of :data:`TARGETS` a partial run left out (empty
    for the whole sweep), and the command that runs them all."""
    left = [label for label, spec in TARGETS if spec not in {s for _, s in targets}]
    if not left:
        return ""
    return (f"**A partial run**: {len(targets)} of the {len(TARGETS)} materials; not fitted "
            f"here: {', '.join(left)}. The whole sweep: "
            "`python -m mi_brdfs.tools.fit.trade -o docs/benchmarks/trade` "
            "(or `mi-brdfs bench --group trade`).\n\n")


CAPTION = ("Each cell: the FLIP of the model's image against the material's, then, after the "
           "dot, its BRDF error (L² over a black BSDF's: 0 identical, 1 as far as black, above 1 "
           "farther); bold: the first-ranked fit per material (the cheapest cost class among "
           f"the fits within FLIP {rank.TIE_FLIP} of the best). Cost ×: the model's median render "
           "time over the material's own, with the medians of its 90 % intervals' ends; ops ×: "
           "its median Dr.Jit operation count over the material's.")


def table(records: list[dict], labels: dict[str, str] | None = None,
          walk: dict[str, dict] | None = None) -> str:
    """"Which model for which material": a Markdown table, one row per model,
    its median render cost over the targets (× the target's, with the median
    of its interval's ends) and its median operation count (× the target's),
    and on each target its image FLIP and its BRDF error (``0.06 · 0.110``);
    the first-ranked model per target (:func:`.rank.ranked`) in bold, as
    :data:`CAPTION` says; then the answers, the rungs and, given ``walk``
    (:func:`walk_flips`), energy compensation against the walk."""
    labels = labels or {}
    first = {spec: id(order[0]) for spec in dict.fromkeys(r["target"] for r in records)
             if (order := rank.ranked([r for r in records if r["target"] == spec]))}
    specs = list(dict.fromkeys(r["target"] for r in records))
    canonical = {name: i for i, name in enumerate(names())}          # the models' own order
    models = sorted(dict.fromkeys(r["model"] for r in records),
                    key=lambda m: canonical.get(m, len(canonical)))
    cell = {(r["target"], r["model"]): r for r in records}
    head = ["model", "cost × (90 %)", "ops ×"] + [labels.get(s, s) for s in specs]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]

    def median(m, key):
        values = [cell[(s, m)].get(key) for s in specs if (s, m) in cell]
        values = [v for v in values if v is not None and math.isfinite(v)]
        return statistics.median(values) if values else None

    for m in models:
        c, lo, hi, ops = (median(m, k) for k in ("cost_ratio", "cost_low", "cost_high", "ops_ratio"))
        row = [f"`{m}`", "–" if c is None else f"{c:.2f} ({lo:.2f}–{hi:.2f})",
               "–" if ops is None else f"{ops:.2f}"]
        for s in specs:
            r = cell.get((s, m))
            if r is None or "error" in r:
                row.append("failed" if r else "–")
                continue
            flip = r.get("image_flip")
            text = (f"{flip:.2f} · " if flip is not None else "") + f"{r['brdf_error']:.3f}"
            row.append(f"**{text}**" if first.get(s) == id(r) else text)
        lines.append("| " + " | ".join(row) + " |")
    return ("\n".join(lines) + "\n\n" + answers(records, labels) + ladder(records, labels)
            + walk_table(records, walk or {}, labels))


RUNG_COLUMNS = (      # (heading, the model's name after cook_torrance/<D>/smith)
    ("lecture's form (Schlick, k-mix)", ""),
    ("F82-tint", "/f82"),
    ("exact conductor F", "/conductor"),
    ("plastic base", "/plastic"),
)
LADDER_CAPTION = ("The rungs: `cook_torrance` with Smith's G, from the lecture's form (Schlick's "
                  "F, the k-weighted Lambert) one option at a time to the physics it stands "
                  "for: Hoffman's F82-tint and the exact conductor Fresnel for a conductor, "
                  "roughplastic's base under the exact dielectric Fresnel for a plastic. Each "
                  "cell: the image FLIP against the material, then the cost × the material's "
                  "own (90 % interval), of the better of GGX and Beckmann (by FLIP); – where "
                  "the rung was not fitted.")


def rung_of(model: str) -> str | None:
    """The ladder's column suffix of a model (:data:`RUNG_COLUMNS`), None
    for a model on no rung (``+ec``, other G, other plugins)."""
    for d in ("ggx", "beckmann"):
        head = f"cook_torrance/{d}/smith"
        rest = model[len(head):] if model.startswith(head) else None
        if rest in ("/plastic/nonlinear", "/plastic"):
            return "/plastic"
        if rest in [suffix for _, suffix in RUNG_COLUMNS]:
            return rest
    return None


def ladder(records: list[dict], labels: dict[str, str] | None = None) -> str:
    """Per material fitted with a rung beyond the lecture's form: each rung's
    FLIP and cost (:data:`LADDER_CAPTION`); empty if no material was."""
    labels = labels or {}
    fitted = [r for r in rank.ok(records) if rung_of(r["model"]) is not None]
    specs = [s for s in dict.fromkeys(r["target"] for r in fitted)
             if any(rung_of(r["model"]) and r["target"] == s for r in fitted)]
    if not specs:
        return ""
    columns = [(h, suffix) for h, suffix in RUNG_COLUMNS
               if any(rung_of(r["model"]) == suffix for r in fitted if r["target"] in specs)]
    lines = ["| material | " + " | ".join(h for h, _ in columns) + " |",
             "|---|" + "---|" * len(columns)]
    for spec in specs:
        row = [labels.get(spec, spec)]
        for _, suffix in columns:
            mine = [r for r in fitted if r["target"] == spec and rung_of(r["model"]) == suffix]
            if not mine:
                row.append("–")
                continue
            best = min(mine, key=rank.quality)
            cost = "" if best.get("cost_ratio") is None else f" · {rank.cost_text(best)}"
            row.append(f"{rank.quality(best):.3f}{cost} ({best['model'].split('/')[1]})")
        lines.append("| " + " | ".join(row) + " |")
    return "\n" + LADDER_CAPTION + "\n\n" + "\n".join(lines) + "\n"


def answers(records: list[dict], labels: dict[str, str] | None = None) -> str:
    """Per material: the verdict (:func:`.rank.verdict`), how far the
    first-ranked fit's FLIP is from the best FLIP of any fit, and for a
    conductor the largest channel difference between the first-ranked fit's
    colour at normal incidence and the material's F0 (:func:`checks`)."""
    labels = labels or {}
    lines = ["| material | verdict | first-ranked FLIP - best FLIP | conductor: F0 error |",
             "|---|---|---|---|"]
    for spec, gap, f0_error in checks(records):
        if gap is None:
            lines.append(f"| {labels.get(spec, spec)} | every fit failed | – | – |")
            continue
        mine = [r for r in records if r["target"] == spec]
        error = "–" if f0_error is None else f"{f0_error:.3f}"
        lines.append(f"| {labels.get(spec, spec)} | {rank.verdict(mine, rank.target_plugin(spec))} "
                     f"| {gap:.3f} | {error} |")
    return "\n".join(lines) + "\n"


def checks(records: list[dict]) -> list[tuple[str, float | None, float | None]]:
    """Per material (spec): the first-ranked fit's FLIP minus the best FLIP of
    any fit (None if every fit failed), and for a conductor the largest
    channel difference between the first-ranked fit's colour at normal
    incidence and the material's F0 (else None)."""
    out = []
    for spec in dict.fromkeys(r["target"] for r in records):
        order = rank.ranked([r for r in records if r["target"] == spec])
        if not order:
            out.append((spec, None, None))
            continue
        gap = rank.quality(order[0]) - min(rank.quality(r) for r in order)
        f0 = effective.conductor_f0(T.parse([spec])[0])
        colour = effective.normal_colour(order[0])
        error = (None if f0 is None or colour is None
                 else max(abs(a - b) for a, b in zip(colour, f0)))
        out.append((spec, gap, error))
    return out


def compensated_pairs(records: list[dict]) -> list[tuple[str, str, float, float]]:
    """(material, compensated model, its FLIP, the uncompensated model's
    FLIP) of every model fitted to a material with and without energy
    compensation (:func:`.rank.quality`; failed fits left out)."""
    flip = {(r["target"], r["model"]): rank.quality(r) for r in rank.ok(records)}
    return [(t, m, flip[(t, m)], flip[(t, m[:-len(EC)])]) for t, m in flip
            if m.endswith(EC) and (t, m[:-len(EC)]) in flip]


def compensation_effect(records: list[dict]) -> tuple[int, int, int]:
    """Over the (material, model) pairs fitted both with and without energy
    compensation: in how many the compensated fit's FLIP is worse by more
    than :data:`.rank.TIE_FLIP`, in how many better by more, of how many."""
    pairs = [(on, off) for _, _, on, off in compensated_pairs(records)]
    worse = sum(a > b + rank.TIE_FLIP for a, b in pairs)
    better = sum(a < b - rank.TIE_FLIP for a, b in pairs)
    return worse, better, len(pairs)


def summary(records: list[dict], labels: dict[str, str] | None = None) -> str:
    """The README's "which model for my material" table: per material, the
    first-ranked model with its image FLIP and render cost (× the material's
    own plugin, 90 % interval), and the cheaper model that looks the same
    (:func:`.rank.cheaper_alternative`), or "none" with the closest cheaper one."""
    labels = labels or {}
    lines = ["| material | first-ranked model | FLIP | cost × (90 %) | "
             "cheaper model that looks the same |", "|---|---|---|---|---|"]
    for spec in dict.fromkeys(r["target"] for r in records):
        order = rank.ranked([r for r in records if r["target"] == spec])
        if not order:
            lines.append(f"| {labels.get(spec, spec)} | every fit failed | – | – | – |")
            continue
        best, alt = order[0], rank.cheaper_alternative(order)
        cost = "–" if best.get("cost_ratio") is None else rank.cost_text(best)
        if alt is not None:
            other = f"`{alt['model']}`: FLIP {rank.quality(alt):.3f} at {rank.cost_text(alt)}"
        else:
            closest = rank.closest_cheaper(order)
            other = ("none: no model costs less" if closest is None else
                     f"none (closest: `{closest['model']}`, FLIP {rank.quality(closest):.3f})")
        lines.append(f"| {labels.get(spec, spec)} | `{best['model']}` | "
                     f"{rank.quality(best):.3f} | {cost} | {other} |")
    return "\n".join(lines)


# ----------------------------------------------------------------------------
#  Energy compensation against the walk
# ----------------------------------------------------------------------------

WALK_FILE = "walk.json"        # the walk rung's FLIPs, beside fits.json
WALK_MARGIN = 0.05             # a +ec fit within the walk rung's FLIP + this


def walk_rung(spec: str) -> dict | None:
    """The walk rung of a single-scattering conductor target (``roughconductor``
    with one ``alpha``): ``cook_torrance`` on the same microsurface (Smith's
    G, the same D and α) with the exact conductor Fresnel, which without the
    walk is the target, and ``multiple_scattering="walk"``: the light the
    random walk on that microsurface reflects, every bounce (Heitz, Hanika,
    d'Eon & Dachsbacher 2016). None for any other target."""
    props = dict(T.parse([spec])[0].props)
    if props["type"] != "roughconductor" or "alpha" not in props or "material" not in props:
        return None
    return {"type": "cook_torrance", "mode": "hdr",
            "distribution": props.get("distribution", "beckmann"), "geometry": "smith",
            "fresnel": "conductor", "material": props["material"],
            "alpha": props["alpha"], "k": 0.0, "specular_reflectance": 1.0,
            "multiple_scattering": "walk"}


def walk_flips(specs, settings=FULL) -> dict[str, dict]:
    """Per target of ``specs`` with a walk rung (:func:`walk_rung`): the mean
    FLIP over the standard views, as a fit's (the same resolution, samples
    and seed), of the walk rung's renders against the target's (``walk``:
    what multiple scattering really adds to the material) and of the same
    rung without the walk (``single``: the material itself, the floor of the
    comparison)."""
    out = {}
    for spec in specs:
        rung = walk_rung(spec)
        if rung is None:
            continue
        reference = scene.target_views(T.parse([spec])[0], settings.res, settings.spp, seed=0)
        row = {"properties": rung, "res": settings.res, "spp": settings.spp}
        single = {k: v for k, v in rung.items() if k != "multiple_scattering"}
        for name, props in (("walk", rung), ("single", single)):
            image = scene.render_views(lambda p=props: p, settings.res, settings.spp, seed=0)
            views = scene.view_metrics(reference, image, settings.res)
            row[name] = statistics.fmean(v["flip"] for v in views.values())
        out[spec] = row
    return out


WALK_CAPTION = (
    "Energy compensation against the walk, per single-scattering conductor. The walk "
    "rung: `cook_torrance` on the material's microsurface with its exact Fresnel and "
    '`multiple_scattering="walk"`, against the material (FLIP; in brackets the same '
    "rung without the walk, the comparison's floor): the light that multiple "
    "scattering really adds. Then the fit of `cook_torrance` with Smith's G and the "
    "material's own distribution, whose compensation is the directional lobe: FLIP "
    "without → with `energy_compensation`, ✓ where the compensated fit is within the "
    f"walk rung's FLIP + {WALK_MARGIN}. Last, every other `+ec` fit (the other "
    "distribution's, and the models whose compensation is the separable lobe): how many "
    f"are worse than their uncompensated fit by more than the walk rung's FLIP + {WALK_MARGIN}.")


def walk_table(records: list[dict], walk: dict[str, dict],
               labels: dict[str, str] | None = None) -> str:
    """:data:`WALK_CAPTION`'s table from the fits and :func:`walk_flips`'
    figures; empty without them."""
    labels = labels or {}
    pairs = compensated_pairs(records)
    specs = [s for s in dict.fromkeys(r["target"] for r in records) if s in walk]
    if not specs:
        return ""
    lines = ["| material | walk rung (floor) | its D × Smith → `+ec` "
             f"| other `{EC}` fits worse by more |", "|---|---|---|---|"]
    for spec in specs:
        bound = walk[spec]["walk"] + WALK_MARGIN
        own = f"cook_torrance/{walk[spec]['properties']['distribution']}/smith"
        mine = [(on, off) for t, m, on, off in pairs if t == spec and m == own + EC]
        row = [labels.get(spec, spec), f"{walk[spec]['walk']:.3f} ({walk[spec]['single']:.3f})",
               "–" if not mine else
               f"`{own}`: {mine[0][1]:.3f} → {mine[0][0]:.3f} {'✓' if mine[0][0] <= bound else '✗'}"]
        others = [(m, on - off) for t, m, on, off in pairs if t == spec and m != own + EC]
        worse = [m for m, increase in others if increase > bound]
        row.append(f"{len(worse)} of {len(others)}"
                   + (f" ({', '.join(f'`{m}`' for m in worse)})" if worse else ""))
        lines.append("| " + " | ".join(row) + " |")
    return "\n" + WALK_CAPTION + "\n\n" + "\n".join(lines) + "\n"


def read_walk(folder: str) -> dict[str, dict]:
    """The walk rung's figures of a trade report (:data:`WALK_FILE`), or none."""
    path = os.path.join(folder, WALK_FILE)
    if not os.path.isfile(path):
        return {}
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def rebuild(folder: str, targets=TARGETS) -> list[dict]:
    """The trade report in ``folder`` written again from its ``fits.json``,
    with no fit and no timing: the ranks, the verdicts, the Pareto plots,
    ``index.html``, ``fits.json``/``fits.csv`` in rank order and ``trade.md``,
    as the current ranking and report writers make them (the renders, the XML,
    the lobe slices and the walk rung's figures the run drew stay as they are). The run's settings are
    taken to be :data:`.task.FULL`'s, as the sweep's."""
    if not os.path.isfile(os.path.join(folder, "fits.json")):
        raise ValueError(f"{folder} holds no trade sweep (no fits.json): nothing to write "
                         "again; run the sweep there without --from-records")
    with open(os.path.join(folder, "fits.json"), encoding="utf-8") as f:
        records = json.load(f)
    specs = list(dict.fromkeys(r["target"] for r in records))
    names = {t.spec: t.name for t in T.parse(specs)}
    features = {}
    for r in records:
        r["target_name"] = names[r["target"]]
        if r.get("xml") and not r["xml"].startswith(r["target_name"] + "__"):
            raise ValueError(f"{folder}: {r['xml']} is not named after {r['target_name']}; "
                             "the targets are not in the sweep's order")
        if r.get("target_features"):
            features[r["target_name"]] = r["target_features"]
    ordered = report.write(folder, records, FULL, "mi_brdfs.tools.fit.trade.fit_materials",
                           features)
    labels = dict((spec, label) for label, spec in targets)
    chosen = tuple((label, spec) for label, spec in targets if spec in names)
    with open(os.path.join(folder, "trade.md"), "w", encoding="utf-8") as f:
        f.write(subset_note(chosen) + table(ordered, labels, read_walk(folder)))
    return ordered


def main(argv: list[str] | None = None) -> int:
    """``python -m mi_brdfs.tools.fit.trade -o DIR [--quick] [-j N] [--materials LABEL ...]``;
    ``--from-records``: :func:`rebuild` instead of a sweep."""
    p = argparse.ArgumentParser(prog="python -m mi_brdfs.tools.fit.trade",
                                description="The trade sweep: every course model fitted to "
                                            "the fixed materials; a fit report with trade.md.")
    p.add_argument("-o", "--output", required=True,
                   help="report folder: new, empty, or a previous report")
    p.add_argument("--quick", action="store_true", help="fewer pairs, pixels and timing rounds")
    p.add_argument("-j", "--jobs", type=int, default=None, help="fits at once (default: up to 2)")
    p.add_argument("--materials", nargs="+", metavar="LABEL", default=None,
                   help="only these materials, by label (default: all): "
                        + "; ".join(label for label, _ in TARGETS))
    p.add_argument("--from-records", action="store_true",
                   help="fit nothing: write the report in -o DIR again from its fits.json "
                        "(ranks, verdicts, Pareto plots, index.html, trade.md)")
    args = p.parse_args(argv)
    if args.from_records:
        try:
            records = rebuild(args.output)
        except Exception as error:
            print(f"{p.prog}: error: {one_line(error)}", file=sys.stderr)
            return 1
        print(f"{os.path.join(args.output, 'trade.md')}: {len(records)} records written again")
        return 0
    chosen = TARGETS
    if args.materials:
        known = dict(TARGETS)
        unknown = [m for m in args.materials if m not in known]
        if unknown:
            p.exit(1, f"{p.prog}: error: --materials: unknown label {unknown[0]!r}; valid: "
                      f"{'; '.join(known)}\n")
        chosen = tuple((m, known[m]) for m in dict.fromkeys(args.materials))
    show = progress_printer(p.prog)
    try:
        records = fit_materials(args.output, quick=args.quick, jobs=args.jobs, show=show,
                                targets=chosen)
    except Exception as error:
        show.close()
        print(f"{p.prog}: error: {one_line(error)}", file=sys.stderr)
        return 1
    show.close()
    failed = [r for r in records if "error" in r]
    print(f"{os.path.join(args.output, 'trade.md')}: {len(records) - len(failed)} fits, "
          f"{len(failed)} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
