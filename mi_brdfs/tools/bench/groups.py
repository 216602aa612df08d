"""The bench's groups: each a function of the settings and the reference cache
returning its rows (a list of flat dicts), its configurations from the
models' own cases (:mod:`mi_brdfs.bsdfs.cases`: each model declares what the bench runs of it) and the
bench's scenes (:mod:`.measure`).

:data:`GROUPS`, at the end, is the one place a group is added: its runner
(here), its finding (report.py) and its plots (plots.py), the last two
optional. The runner's docstring says what the group measures; the report
shows it above the group's table.
"""
from __future__ import annotations

import os
import statistics
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

import mitsuba as mi

from ...bsdfs import cases
from ...bsdfs.compensation import AlbedoSpec
from ..explore import latency
from ..fit import rank
from ..fit.trade import TARGETS, fit_materials
from ..measures import relmse
from ..tables import build
from . import ladder as rungs, plots, report
from .measure import FULL, References, Settings, alternating, efficiency, image, scene_dict, timed
from .workers import in_subprocess


# ----------------------------------------------------------------------------
#  In this process
# ----------------------------------------------------------------------------

# The glossy sphere the integrators and convergence groups render, and the
# integrator of their converged reference.
GLOSSY = {"type": "cook_torrance", "distribution": "ggx", "alpha": 0.3, "k": 0.5}
REFERENCE_INTEGRATOR = {"type": "path", "max_depth": 16}
INTEGRATORS: list[tuple[str, dict]] = [
    ("scanline", {"type": "scanline", "clamp": False, "shadows": True}),
    ("direct", {"type": "direct"}),
    ("path depth 2", {"type": "path", "max_depth": 2}),
    ("path depth 3", {"type": "path", "max_depth": 3}),
    ("path depth 8", {"type": "path", "max_depth": 8}),
]
# Scan-line cost against resolution and number of lights: (BSDF, integrator).
SCALING = ({"type": "lambert", "mode": "scanline"}, {"type": "scanline"})

def builtin(s: Settings, refs: References) -> list[dict]:
    """Python plugin vs Mitsuba's C++ built-in, the same BSDF, scene and spp: the
    time ratio, and where the time goes (Python tracing, LLVM codegen, kernel
    execution, from Dr.Jit's kernel history)."""
    rows = []
    for name, ours, builtin in ((t.label, t.ours, t.builtin) for t in cases.twins()):
        t_ours = timed(mi.load_dict(scene_dict(ours, s.res)), s.spp, s.repeats)
        t_builtin = timed(mi.load_dict(scene_dict(builtin, s.res)), s.spp, s.repeats)
        row = {"name": name, "plugin_s": t_ours["median_s"], "builtin_s": t_builtin["median_s"],
               "ratio": t_ours["median_s"] / t_builtin["median_s"]}
        for part in ("compile", "tracing", "execution", "codegen"):
            row[f"plugin_{part}_s"] = t_ours[f"{part}_s"]
            row[f"builtin_{part}_s"] = t_builtin[f"{part}_s"]
        rows.append(row)
    return rows


def models(s: Settings, refs: References) -> list[dict]:
    """Render time per spp of every model and variant (each model's cases().costs),
    relative to lambert."""
    rows = []
    for name, config in cases.costs():
        t = timed(mi.load_dict(scene_dict(config, s.res)), s.spp, s.repeats)
        rows.append({"name": name, "median_s": t["median_s"], "per_spp_s": t["median_s"] / s.spp,
                     "compile_s": t["compile_s"]})
    base = next(r["median_s"] for r in rows if r["name"] == "lambert")
    for r in rows:
        r["relative_to_lambert"] = r["median_s"] / base
    return rows


def oren_nayar(s: Settings, refs: References) -> list[dict]:
    """The Oren-Nayar table at several resolutions vs the exact formulas: time
    and error against the exact render (same seed: no noise)."""
    _, base = cases.of("oren_nayar").variants[0]
    exact_scene = mi.load_dict(scene_dict({**base, "method": "exact"}, s.res))
    exact = timed(exact_scene, s.spp, s.repeats)
    exact_img = image(exact_scene, s.spp, seed=99)
    again = image(exact_scene, s.spp, seed=99)        # same seed: no noise
    rows = [{"name": "exact", "table_resolution": 0, "median_s": exact["median_s"],
             "speedup": 1.0, "relmse_vs_exact": relmse(again, exact_img),
             "max_abs_vs_exact": float(np.max(np.abs(again - exact_img)))}]
    for n in s.table_resolutions:
        scene = mi.load_dict(scene_dict({**base, "method": "table", "table_resolution": n}, s.res))
        t = timed(scene, s.spp, s.repeats)
        img = image(scene, s.spp, seed=99)
        rows.append({"name": f"table {n}", "table_resolution": n, "median_s": t["median_s"],
                     "speedup": exact["median_s"] / t["median_s"],
                     "relmse_vs_exact": relmse(img, exact_img),
                     "max_abs_vs_exact": float(np.max(np.abs(img - exact_img)))})
    return rows


def sampling(s: Settings, refs: References) -> list[dict]:
    """Glossy lobes: cosine-hemisphere vs the lobe's importance sampling (and
    full-distribution vs visible-normal microfacet sampling), error at equal
    spp and efficiency."""
    rows = []
    for name, config, strategies in cases.every("sampling"):
        reference = refs.get(scene_dict({**config, **strategies[0][1]}, s.res))
        for label, options in strategies:
            scene = mi.load_dict(scene_dict({**config, **options}, s.res))
            t = timed(scene, s.spp, s.repeats)
            err = relmse(image(scene, s.spp, seed=7), reference)
            rows.append({"name": name, "strategy": label, "spp": s.spp,
                         "median_s": t["median_s"], "relmse": err,
                         "efficiency": efficiency(err, t["median_s"])})
        best = rows[-len(strategies)]["efficiency"]
        for r in rows[-len(strategies):]:
            r["efficiency_vs_first"] = r["efficiency"] / best if best else float("nan")
    return rows


def integrators(s: Settings, refs: References) -> list[dict]:
    """Scan-line direct lighting, Mitsuba's ``direct``, ``path`` with max depth
    2, 3 and 8, against a converged path-traced reference."""
    bsdf = GLOSSY
    reference = refs.get(scene_dict(bsdf, s.res, REFERENCE_INTEGRATOR))
    rows = []
    for name, integrator in INTEGRATORS:
        scene = mi.load_dict(scene_dict(bsdf, s.res, integrator))
        t = timed(scene, s.spp, s.repeats)
        err = relmse(image(scene, s.spp, seed=5), reference)
        rows.append({"name": name, "median_s": t["median_s"], "relmse": err,
                     "efficiency": efficiency(err, t["median_s"])})
    return rows


def convergence(s: Settings, refs: References) -> list[dict]:
    """Error vs spp (log-log) and its slope (about -1 for relMSE)."""
    d = scene_dict(GLOSSY, s.res)
    reference = refs.get(d)
    scene = mi.load_dict(d)
    rows = []
    for spp in s.spp_ladder:
        errors = [relmse(image(scene, spp, seed=100 + i), reference) for i in range(3)]
        rows.append({"spp": spp, "relmse": float(np.mean(errors))})
    x = np.log([r["spp"] for r in rows])
    y = np.log([r["relmse"] for r in rows])
    slope = float(np.polyfit(x, y, 1)[0])
    for r in rows:
        r["slope"] = slope
    return rows


def scaling(s: Settings, refs: References) -> list[dict]:
    """Render time vs resolution and vs number of lights (scan-line)."""
    bsdf, integrator = SCALING
    rows = []
    for res in s.resolutions:
        t = timed(mi.load_dict(scene_dict(bsdf, res, integrator)), s.spp, s.repeats)
        rows.append({"axis": "resolution", "value": res, "median_s": t["median_s"]})
    for n in s.light_counts:
        t = timed(mi.load_dict(scene_dict(bsdf, s.res, integrator, lights=n)), s.spp, s.repeats)
        rows.append({"axis": "lights", "value": n, "median_s": t["median_s"]})
    return rows


def lobes(s: Settings, refs: References) -> list[dict]:
    """Model only what the scene requires: a plugin with a lobe switched off
    renders at the cost of the model without that lobe (the two taking turns
    in one process, medians: timed one after the other, a drift of the
    machine's load would read as the cost of a dead lobe)."""
    rows = []
    for name, off, reference in cases.every("lobes_off"):
        flags = mi.load_dict(off).flags()
        t = alternating({"off": mi.load_dict(scene_dict(off, s.res)),
                         "reference": mi.load_dict(scene_dict(reference, s.res))},
                        s.spp, 5 * s.repeats)       # renders of ~40 ms: more of them
        t_off, t_ref = t["off"], t["reference"]
        rows.append({"name": name, "lobe_off_s": t_off["median_s"],
                     "reference_s": t_ref["median_s"],
                     "ratio": t_off["median_s"] / t_ref["median_s"],
                     "diffuse_lobe": bool(flags & mi.BSDFFlags.Diffuse),
                     "glossy_lobe": bool(flags & mi.BSDFFlags.Glossy)})
    return rows


def energy(s: Settings, refs: References) -> list[dict]:
    """Energy compensation: render time of each compensated model with
    energy_compensation on vs off (same scene and spp; on and off taking turns
    in one process, medians; wall and kernel execution time), and the time to
    build its albedo table (as python -m mi_brdfs.tools.tables does)."""
    built: dict[str, float] = {}
    rows = []
    for name, config in cases.every("energy"):
        compensated = {**config, "energy_compensation": True}
        ms = mi.load_dict(compensated).compensation()
        scenes = {"off": mi.load_dict(scene_dict(config, s.res)),
                  "on": mi.load_dict(scene_dict(compensated, s.res))}
        directional = getattr(ms, "directional", False)
        if directional:               # cook_torrance's directional lobe: its separable one too
            scenes["separable"] = mi.load_dict(scene_dict({**compensated,
                                                           "compensation": "separable"}, s.res))
        t = alternating(scenes, s.spp, s.repeats)
        t_off, t_on = t["off"], t["on"]
        # the single-scattering table the compensation is made from (none: analytic
        # or, for the directional lobe, the pair table, built by the tables command)
        table = getattr(mi.load_dict(config).compensation(), "table", None)
        spec = next((t for t in table.specs if isinstance(t, AlbedoSpec)), None) if table \
            else None
        if spec is not None and spec.name not in built:
            start = time.perf_counter()
            build(spec, s.table_samples)
            built[spec.name] = time.perf_counter() - start
        rows.append({"name": name, "off_s": t_off["median_s"], "on_s": t_on["median_s"],
                     "ratio": t_on["median_s"] / t_off["median_s"],
                     "execution_ratio": t_on["execution_s"] / t_off["execution_s"],
                     **({"separable_s": t["separable"]["median_s"],
                         "vs_separable": t_on["median_s"] / t["separable"]["median_s"]}
                        if directional else {}),
                     "table": spec.name if spec else (ms.pairs.specs[0].name if directional
                                                      else "(analytic)"),
                     "table_nodes": int(np.prod([a.n for a in spec.axes])) if spec else 0,
                     "table_samples": s.table_samples if spec else 0,
                     "table_build_s": built[spec.name] if spec else 0.0})
    return rows


def ladder(s: Settings, refs: References, out_dir: str) -> list[dict]:
    """The multiple-scattering ladder (tools/bench/ladder.py): cook_torrance
    (GGX, Smith G) on a rough gold and a rough white sphere, in the fit's
    environment and under a directional light from behind the sphere (160°
    off the camera's axis) and from behind the camera (10°), at each rung:
    single scattering, the separable energy-compensation lobe, the random
    walk in the renderer. Per rung: the median render time (one BSDF alive
    in the process) and over single scattering's, the noise (expected relMSE
    of one render against its own mean), one render's relMSE and HDR-FLIP
    against a converged render of the walk, the FLIP of the renders' mean,
    and the light reflected to the camera over the walk's (sums over the
    sphere's pixels); ladder.png shows the renders and their differences
    from the converged walk."""
    rows, images = [], {}
    for material, _ in rungs.MATERIALS:
        for lighting in rungs.LIGHTINGS:
            truth = rungs.reference(material, lighting, s.ladder_res, refs)
            images[(material, lighting, f"{rungs.TRUTH}, converged")] = truth
            mine = []
            for rung, _ in rungs.RUNGS:
                case = rungs.measure(material, lighting, rung, s.ladder_res, s.spp, s.repeats,
                                     truth)
                mine.append(case.row)
                images[(material, lighting, rung)] = case.mean
            for r in mine:
                r["time_vs_single"] = r["median_s"] / mine[0]["median_s"]
            rows += mine
    plots.save(out_dir, plots.ladder(images, s.repeats * s.spp))
    return rows


def walk(s: Settings, refs: References) -> list[dict]:
    """The ladder's rungs in the bundled scenes (tools/bench/ladder.py): each
    cook_torrance of a GGX or Beckmann D in the cook_torrance and course
    scenes, path traced (HDR), given Smith's G and single scattering, the
    directional energy-compensation lobe, then the random walk in the
    renderer (Blinn's D, which the walk does not take, as it is), at the
    scenes' own pixels and samples (quick: the bench's). Per rung:
    the median render time (the scene the only one alive), the noise
    (expected relMSE of one render against its own mean, weighed by the
    walk's mean for every rung), the light reflected to the camera over the
    walk's, and the time, noise and time to the same noise over the
    directional lobe's."""
    own = s is FULL
    rows = []
    for name, _ in rungs.SCENES:
        rows += rungs.measure_scene(name, None if own else s.res, None if own else s.spp,
                                    s.repeats)
    return rows


# ----------------------------------------------------------------------------
#  In processes of their own (workers.py)
# ----------------------------------------------------------------------------

def explore(s: Settings, refs: References) -> list[dict]:
    """mi-brdfs explore as its page sees it (tools/explore/latency.py): rows
    ``page: ...``, the page in Chromium, a drag and single changes, every
    request of a change timed together from the slider's input event to the
    view drawn (the load average in ``load``); then one websocket client, one
    request at a time: start-up, a configuration's first 128² image, slider
    -> plot data, re-render to the first pass and to 256 spp, and a fit;
    medians and maxima over the moves."""
    full = s is FULL
    return latency.both(drag_moves=20 if full else 5, moves=20 if full else 3,
                        changes=8 if full else 2)


def explore_finding(rows: list[dict]) -> str:
    return latency.finding(rows)


MATERIALS_COLUMNS = {     # column: the worker's figure
    "first_s": "first_wall_s", "first_tracing_s": "first_tracing_s",
    "first_codegen_s": "first_codegen_s", "warm_s": "wall_s", "tracing_s": "tracing_s",
    "codegen_s": "codegen_s", "execution_s": "execution_s", "frozen_s": "frozen_s",
    "frozen_recordings": "frozen_recordings", "peak_mib": "peak_mib"}


def materials(s: Settings, refs: References) -> list[dict]:
    """N spheres, each with its own material (path depth 3, constant
    environment), plugin vs built-in (the twins with a spread of materials) and the
    floor beside them: the same BSDF as a bare Python mi.BSDF without the
    framework (tools/bench/floor.py, the twins' floors), what Python itself
    costs. First and warm render split into tracing, code generation and kernel
    execution, a frozen render's replay (render/frozen.py), and peak memory;
    each (kind, N) in processes of its own (``rounds`` of them, alternating
    kinds; medians). The first render loads its kernels from Dr.Jit's disk
    cache when an earlier run compiled them."""
    rows = []
    for twin in (t for t in cases.twins() if t.spread is not None):
        plugin, builtin, floor = twin.ours["type"], twin.builtin["type"], twin.floor["type"]
        kinds = {"plugin": plugin, "builtin": builtin, "floor": floor}
        for n in s.materials:
            # Each (kind, n) in processes of its own, the kinds alternating; the
            # median over the rounds of each process's figures.
            runs: dict[str, list[dict]] = {side: [] for side in kinds}
            for _ in range(s.rounds):
                for side, kind in kinds.items():
                    runs[side].append(in_subprocess("materials", twin=twin.label, side=side, n=n,
                                                    res=s.materials_res, spp=s.materials_spp,
                                                    repeats=s.repeats))
            row = {"name": f"{plugin} vs {builtin}", "materials": n, "floor": floor}
            for side in kinds:
                for column, key in MATERIALS_COLUMNS.items():
                    row[f"{side}_{column}"] = statistics.median(r[key] for r in runs[side])
            row["first_ratio"] = row["plugin_first_s"] / row["builtin_first_s"]
            row["warm_ratio"] = row["plugin_warm_s"] / row["builtin_warm_s"]
            row["execution_ratio"] = row["plugin_execution_s"] / row["builtin_execution_s"]
            row["frozen_ratio"] = row["plugin_frozen_s"] / row["builtin_frozen_s"]
            row["memory_ratio"] = row["plugin_peak_mib"] / row["builtin_peak_mib"]
            row["floor_warm_ratio"] = row["floor_warm_s"] / row["builtin_warm_s"]
            row["warm_vs_floor"] = row["plugin_warm_s"] / row["floor_warm_s"]
            rows.append(row)
    return rows


def frozen(s: Settings, refs: References) -> list[dict]:
    """render_passes at the largest N of materials in 1 and more passes (the
    same spp in all), traced and frozen, each in a process of its own."""
    n = s.materials[-1]
    rows = []
    for passes in s.frozen_passes:
        for freeze in ((False,) if passes == 1 else (False, True)):
            r = in_subprocess("passes", n=n, res=s.materials_res, spp=s.materials_spp,
                              passes=passes, freeze=freeze, repeats=3)
            rows.append({"materials": n, "spp": s.materials_spp, "passes": passes,
                         "frozen": freeze, "first_s": r["first_s"], "warm_s": r["warm_s"],
                         "peak_mib": r["peak_mib"], "note": r["note"]})
    one = next(r for r in rows if r["passes"] == 1)
    for r in rows:
        r["first_vs_1_pass"] = r["first_s"] / one["first_s"]
        r["warm_vs_1_pass"] = r["warm_s"] / one["warm_s"]
    return rows


def kernels(s: Settings, refs: References) -> list[dict]:
    """eval, pdf, eval_pdf and sample of many direction pairs: kernel execution
    time, plugin and built-in (the models' twins) alternating in one
    process, on one thread (stable on shared cores)."""
    return in_subprocess("kernels", lanes=s.kernel_lanes, repeats=s.repeats)["rows"]


def tracing(s: Settings, refs: References) -> list[dict]:
    """Tracing time of one call of each method, plugin vs built-in and, where
    there is one (the twin's floor), the floor: the same BSDF as a
    bare Python mi.BSDF (tools/bench/floor.py); the Dr.Jit variables one call
    creates (from Dr.Jit's trace log); and what the plugin's call does:
    texture evaluations, Mitsuba objects built, BSDF methods it calls again,
    helpers called more than once, and how often a path-traced render calls
    each method."""
    return in_subprocess("tracing", lanes=1024, calls=25 * s.repeats)["rows"]


def trade(s: Settings, refs: References, out_dir: str) -> list[dict]:
    """Which course model for which material: every model fitted by mi-brdfs fit
    to the fixed materials of mi_brdfs.tools.fit.trade (gold, copper, aluminium,
    chromium, plastics, principled, diffuse), ranked by the image's FLIP in the
    standard views, with its BRDF error and its render cost against the
    material's own plugin (a 90 % interval) and its traced operations; the fit
    report, with its Pareto plots, renders and each fit as XML, is in the
    folder trade/."""
    targets = TARGETS[:s.trade_targets or None]
    labels = {spec: label for label, spec in targets}
    records = fit_materials(os.path.join(out_dir, "trade"), quick=s is not FULL,
                            targets=targets, models=list(s.trade_models) or None,
                            show=lambda *a: None)
    keys = ("model", "rank", "image_flip", "image_relmse", "brdf_error", "cost_ratio", "cost_low",
            "cost_high", "time_to_noise", "ops_ratio", "seconds")
    chosen = set()           # the verdict's cheaper model that looks the same, per material
    for spec in labels:
        alt = rank.cheaper_alternative(rank.ranked([r for r in records if r["target"] == spec]))
        if alt is not None:
            chosen.add(id(alt))
    return [{"material": labels[r["target"]], **{k: r.get(k) for k in keys},
             "looks_same_cheaper": id(r) in chosen, "failed": r.get("error", "")}
            for r in records]


FIT_MATERIAL = 0          # the fit group's material: the first of the trade sweep (gold)


def fit_runs(name: str, settings, models: list[str] | None, repeats: int) -> dict:
    """``repeats`` fits of the fit group's material, each into a fresh folder:
    the median wall time, and of it the fits' share (the rest: the render
    costs), the load average before and after."""
    import tempfile

    from ..fit import fit
    label, spec = TARGETS[FIT_MATERIAL]
    runs, fits, loads = [], [], [os.getloadavg()[0]]
    for _ in range(repeats):
        marks = {}

        def show(done, total, elapsed, record, marks=marks):
            if "cost_rounds" not in record and "cost_error" not in record:
                marks["fits"] = elapsed
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            records = fit([spec], os.path.join(tmp, "fit"), models, settings=settings,
                          show=show, warn=lambda m: None)
            runs.append(time.perf_counter() - start)
        fits.append(marks.get("fits", 0.0))
        loads.append(os.getloadavg()[0])
    return {"fit": name, "material": label, "models": len(records),
            "median_s": statistics.median(runs), "fits_s": statistics.median(fits),
            "costs_s": statistics.median(r - f for r, f in zip(runs, fits)),
            "runs": repeats, "load_before": loads[0], "load_after": loads[-1],
            "failed": sum("error" in r for r in records)}


def fit_time(s: Settings, refs: References) -> list[dict]:
    """mi-brdfs fit's own time on one material (gold α 0.1, the trade sweep's
    first): a default fit and a --quick fit against every course model, the
    median wall time of three runs, split into the fits (the command's
    processes, :func:`..fit.sweep.default_jobs`) and the render costs timed
    after them, with the load average before and after (the machine's other
    work slows both). --quick (CI): one --quick
    fit of one model with two timing rounds."""
    from ..fit import FULL as FIT_FULL, QUICK as FIT_QUICK
    if s is not FULL:
        return [fit_runs("quick", FIT_QUICK.replace(cost_rounds=(2, 2)), ["lambert"], 1)]
    return [fit_runs("default", FIT_FULL, None, 3), fit_runs("quick", FIT_QUICK, None, 3)]


# ----------------------------------------------------------------------------
#  Every group, in the order they run
# ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Group:
    name: str
    run: Callable[..., list[dict]]                                # (settings, references)
    finding: Callable[[list[dict]], str | None] | None = None    # report.py
    plots: Callable[[list[dict]], dict] | None = None             # plots.py
    writes: bool = False      # run() also writes files: it gets out_dir, the report folder
    drawn: tuple[str, ...] = ()   # figures run() draws itself (they need more than its rows)

    @property
    def about(self) -> str:
        """What the group measures: its runner's docstring, on one line."""
        return " ".join((self.run.__doc__ or "").split())


GROUPS: dict[str, Group] = {g.name: g for g in [
    Group("builtin", builtin, report.builtin, plots.builtin),
    Group("models", models, report.models, plots.models),
    Group("oren_nayar", oren_nayar, report.oren_nayar, plots.oren_nayar),
    Group("sampling", sampling, report.sampling, plots.sampling),
    Group("integrators", integrators, report.integrators, plots.integrators),
    Group("convergence", convergence, report.convergence, plots.convergence),
    Group("scaling", scaling, report.scaling, plots.scaling),
    Group("lobes", lobes, report.lobes, plots.lobes),
    Group("energy", energy, report.energy),
    Group("ladder", ladder, report.ladder, writes=True, drawn=plots.LADDER),
    Group("walk", walk, report.walk),
    Group("materials", materials, report.materials, plots.materials),
    Group("frozen", frozen, report.frozen, plots.frozen),
    Group("kernels", kernels, report.kernels, plots.kernels),
    Group("tracing", tracing, report.tracing, plots.tracing),
    Group("explore", explore, explore_finding),
    Group("trade", trade, report.trade, writes=True),
    Group("fit", fit_time, report.fit_time),
]}
