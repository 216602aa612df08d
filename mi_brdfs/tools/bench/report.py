"""What the bench writes: results.json, results.csv (group, row, key, value),
and README.md with the tables and the findings — a plain-language answer per
group, computed from the numbers of this run (one function per group, named
after it, given the group's rows). A quick run is a smoke test: it draws no
findings and its README says that its numbers are not measurements.

A report may hold groups of several runs: a partial run (``--only``) into a
previous bench report, or ``--merge`` of another report's groups, replaces
the groups it brings and keeps the others — their rows, their plots, their
folders (the trade sweep's ``trade/``) and every other file of the previous
report; results.json records each group's run (``runs``: its date, settings
and machine), and results.csv and README.md are written again from the
merged rows. The folder is replaced as a whole, once the new report is
complete (:mod:`mi_brdfs.tools.destinations`).
"""
from __future__ import annotations

import csv
import json
import os
import shutil

import numpy as np

SMOKE_TEST = ("Quick run (--quick): a smoke test that every group runs, on a tiny scene with "
              "few repeats. Its numbers are not measurements and change from run to run; it "
              "draws no findings. Run `mi-brdfs bench -o DIR` without --quick to measure.")


# ----------------------------------------------------------------------------
#  Findings, one per group
# ----------------------------------------------------------------------------

def builtin(rows: list[dict]) -> str:
    ratios = ", ".join(f"{r['name'].split(' vs ')[0]} {r['ratio']:.3f}" for r in rows)
    return (f"Python plugin / C++ built-in time ratio: {ratios} (parity is <= 1.05). "
            "Tracing the Python code takes "
            + ", ".join(f"{1e3 * r['plugin_tracing_s']:.2f} ms" for r in rows)
            + " per render; kernel execution time ratios: "
            + ", ".join(f"{r['plugin_execution_s'] / r['builtin_execution_s']:.3f}" for r in rows)
            + ".")


def models(rows: list[dict]) -> str:
    worst = max(rows, key=lambda r: r["relative_to_lambert"])
    return (f"Model cost: every model renders within {worst['relative_to_lambert']:.2f}x "
            f"of lambert on this scene (slowest: {worst['name']}); the BSDF is a small "
            "part of a path-traced sample's cost.")


def oren_nayar(rows: list[dict]) -> str:
    tables = [r for r in rows if r["table_resolution"]]
    best = max(tables, key=lambda r: r["speedup"])
    return (f"Oren-Nayar table: best speed-up {best['speedup']:.3f}x (resolution "
            f"{best['table_resolution']}); relMSE vs exact from "
            f"{tables[0]['relmse_vs_exact']:.2g} (resolution {tables[0]['table_resolution']}) "
            f"to {tables[-1]['relmse_vs_exact']:.2g} ({tables[-1]['table_resolution']})."
            + (" The table buys no measurable time here (< 5 %): on this CPU the "
               "trigonometry is not the bottleneck." if best["speedup"] < 1.05 else ""))


def sampling(rows: list[dict]) -> str:
    cos = [r for r in rows if r["strategy"] == "cosine"]
    gains = ", ".join(f"{r['name']} {1 / r['efficiency_vs_first']:.0f}x" for r in cos)
    return f"Importance sampling vs cosine sampling, efficiency gain: {gains}."


def integrators(rows: list[dict]) -> str | None:
    by_name = {r["name"]: r for r in rows}
    if "scanline" not in by_name or "path depth 8" not in by_name:
        return None
    s, p = by_name["scanline"], by_name["path depth 8"]
    return (f"Scan-line direct lighting takes {s['median_s'] / p['median_s']:.2f}x the "
            f"time of path tracing (depth 8) and has {s['relmse'] / p['relmse']:.1f}x its "
            "relMSE against converged path tracing (it has no indirect light and no "
            "environment light).")


def convergence(rows: list[dict]) -> str:
    return f"Convergence: relMSE vs spp has log-log slope {rows[0]['slope']:.2f}."


def scaling(rows: list[dict]) -> str | None:
    lights = [r for r in rows if r["axis"] == "lights"]
    if len(lights) < 2:
        return None
    slope = np.polyfit([r["value"] for r in lights], [r["median_s"] for r in lights], 1)[0]
    return (f"Scan-line cost per extra light: {1e3 * slope:.2f} ms "
            f"(on {lights[0]['median_s'] * 1e3:.1f} ms for one light).")


def lobes(rows: list[dict]) -> str:
    ratios = ", ".join(f"{r['name']} {r['ratio']:.3f}" for r in rows)
    verdict = ("within 5 %: a lobe that is off is not traced" if
               all(r["ratio"] < 1.05 for r in rows) else
               "above 1.05 somewhere: a dead lobe may still be traced (a bug)")
    return f"Lobes switched off, time against the model without them: {ratios} ({verdict})."


def energy(rows: list[dict]) -> str:
    ratios = ", ".join(f"{r['name']} {r['ratio']:.2f}x" for r in rows)
    tables = [r for r in rows if r["table_build_s"] > 0]
    execution = ", ".join(f"{r['name']} {r['execution_ratio']:.2f}x" for r in rows)
    directional = [r for r in rows if "vs_separable" in r]
    versus = ("; the directional lobe over the separable one: " + ", ".join(
        f"{r['name']} {r['vs_separable']:.2f}x" for r in directional)) if directional else ""
    return (f"Energy compensation, render time on / off: {ratios} (goal <= 1.10: "
            f"{'met' if all(r['ratio'] <= 1.10 for r in rows) else 'not met'}; kernel "
            f"execution on / off: {execution}){versus}. "
            f"Building a table ({tables[0]['table_samples']}² samples per node): "
            + ", ".join(f"{r['table']} {r['table_build_s']:.2f} s" for r in tables) + ".")


def ladder(rows: list[dict]) -> str:
    """Per material and lighting, each rung's FLIP against the converged walk
    and the light it reflects over the walk's; the time and noise of every
    rung against single scattering's, medians over the cases."""
    rungs = list(dict.fromkeys(r["rung"] for r in rows))
    cases = list(dict.fromkeys((r["material"], r["lighting"]) for r in rows))
    at = {(r["material"], r["lighting"], r["rung"]): r for r in rows}
    parts = "; ".join(f"{m}, {l}: " + ", ".join(
        f"{rung} {at[m, l, rung]['flip_mean']:.3f} ({at[m, l, rung]['light_vs_walk']:.3f})"
        for rung in rungs) for m, l in cases)
    median = lambda rung, key: float(np.median([at[m, l, rung][key] / at[m, l, rungs[0]][key]
                                                for m, l in cases]))
    r0 = rows[0]
    return (f"Multiple-scattering ladder (cook_torrance, GGX, Smith G; HDR-FLIP of the mean "
            f"of the timed renders against a converged render of the walk, and in brackets "
            f"the light reflected to the camera over the walk's): {parts}. Against "
            f"{rungs[0]}, at {r0['spp']} spp and {r0['res']}² pixels, medians over the "
            f"cases: " + ", ".join(f"{rung} {median(rung, 'median_s'):.2f}x the time and "
                                   f"{median(rung, 'noise_relmse'):.2f}x the noise"
                                   for rung in rungs[1:]) + ".")


def walk(rows: list[dict]) -> str:
    """Per bundled scene, the walk's time, noise and time to the same noise
    over the directional lobe's, and single scattering's light over the walk's."""
    parts = []
    for name in dict.fromkeys(r["scene"] for r in rows):
        at = {r["rung"]: r for r in rows if r["scene"] == name}
        w, single = at["walk"], at["single"]
        parts.append(f"{name} ({w['bsdfs']} cook_torrance): the walk {w['time_vs_directional']:.2f}x "
                     f"the time, {w['noise_vs_directional']:.2f}x the noise, "
                     f"{w['time_to_noise_vs_directional']:.2f}x the time to the same noise; "
                     f"the directional lobe's light {at['directional']['light_vs_walk']:.4f} of "
                     f"the walk's, single scattering's {single['light_vs_walk']:.4f}")
    sizes = ", ".join(f"{r['scene']} {r['res']} pixels across, {r['spp']} spp"
                      for r in rows if r["rung"] == "walk")
    return (f"The walk against the directional lobe in the bundled scenes (HDR; {sizes}): "
            + "; ".join(parts) + ".")


def materials(rows: list[dict]) -> str:
    """Plugin vs built-in at the largest number of materials, beside the floor
    (a bare Python BSDF), and the tracing cost per material (slope of the warm
    render's tracing time over N)."""
    most = max(r["materials"] for r in rows)
    ratios = ", ".join(
        f"{r['name'].split(' vs ')[0]} {r['warm_ratio']:.2f}x (its floor, a bare Python "
        f"BSDF, {r['floor_warm_ratio']:.2f}x; first render {r['first_ratio']:.2f}x, kernel "
        f"execution {r['execution_ratio']:.2f}x, frozen replay {r['frozen_ratio']:.2f}x, "
        f"peak memory {r['plugin_peak_mib']:.0f} vs {r['builtin_peak_mib']:.0f} MiB)"
        for r in rows if r["materials"] == most)
    slopes = []
    for name in dict.fromkeys(r["name"] for r in rows):
        pair = [r for r in rows if r["name"] == name]
        if len(pair) > 1:
            n = [r["materials"] for r in pair]
            per = [1e3 * np.polyfit(n, [r[f"{side}_tracing_s"] for r in pair], 1)[0]
                   for side in ("plugin", "builtin", "floor")]
            slopes.append(f"{name} {per[0]:.2f} vs {per[1]:.2f} ms (floor {per[2]:.2f} ms)")
    return (f"{most} spheres, each with its own material: plugin / built-in warm render time "
            f"{ratios}. Tracing per material (plugin vs built-in): {', '.join(slopes)}.")


def frozen(rows: list[dict]) -> str:
    traced = {r["passes"]: r for r in rows if not r["frozen"]}
    replayed = {r["passes"]: r for r in rows if r["frozen"]}
    parts = ", ".join(f"{p} passes {traced[p]['first_vs_1_pass']:.2f}x traced and "
                      f"{r['first_vs_1_pass']:.2f}x frozen" for p, r in replayed.items())
    return (f"Rendering in passes ({rows[0]['materials']} cook_torrance materials, "
            f"{rows[0]['spp']} spp in all, the first render_passes call of a fresh process "
            f"as in mi-brdfs render), time against one pass: {parts}.")


def kernels(rows: list[dict]) -> str:
    parts = "; ".join(
        f"{name}: " + ", ".join(f"{r['method']} {r['ratio']:.2f}" for r in rows
                                if r["name"] == name)
        for name in dict.fromkeys(r["name"] for r in rows))
    return (f"BSDF kernels ({rows[0]['lanes']} direction pairs), plugin / built-in kernel "
            f"execution time: {parts}.")


def tracing(rows: list[dict]) -> str:
    name = rows[0]["name"]
    r = {row["method"]: row for row in rows if row["name"] == name}
    floor = lambda m: (f", the floor {r[m]['floor_ms']:.3f} ms" if "floor_ms" in r[m] else "")
    return (f"Tracing one call ({name}): sample {r['sample']['plugin_ms']:.3f} ms vs "
            f"{r['sample']['builtin_ms']:.3f} ms ({r['sample']['ratio']:.1f}x{floor('sample')}; "
            f"{r['sample']['plugin_vars']} Dr.Jit variables vs {r['sample']['builtin_vars']}), "
            f"eval_pdf {r['eval_pdf']['plugin_ms']:.3f} vs {r['eval_pdf']['builtin_ms']:.3f} ms "
            f"({r['eval_pdf']['ratio']:.1f}x{floor('eval_pdf')}). Tracing a path-traced render calls each "
            f"instance's sample {r['sample']['render_calls']} and eval_pdf "
            f"{r['eval_pdf']['render_calls']} times (eval and pdf "
            f"{r['eval']['render_calls_all']} times); one sample call makes "
            f"{r['sample']['texture_evals']} texture evaluations and builds "
            f"{r['sample']['microfacet_objects']} MicrofacetDistribution objects.")


def fit_time(rows: list[dict]) -> str | None:
    """How long a fit of one material takes, by settings, and the load it ran at."""
    done = [r for r in rows if r.get("median_s") is not None]
    if not done:
        return None
    return "A fit of one material against every course model: " + "; ".join(
        f"{r['fit']} settings {r['median_s']:.0f} s (median of {r['runs']}; the fits "
        f"{r['fits_s']:.0f} s, the costs {r['costs_s']:.0f} s; {r['models']} models) at load "
        f"average {r['load_before']:.1f}–{r['load_after']:.1f}" for r in done) + "."


def trade(rows: list[dict]) -> str | None:
    """The first-ranked model per material (by the image's FLIP, the cheaper
    of those within its tie band) and the cheaper model that looks the same,
    as the fit report's verdict names it (:func:`..fit.rank.cheaper_alternative`,
    the row's ``looks_same_cheaper``), with their render cost against the
    material's plugin."""
    done = [r for r in rows if not r["failed"] and r.get("rank") is not None]
    if not done:
        return None

    def fit(r):
        noise = r.get("time_to_noise")
        per_sample = f"{r.get('cost_ratio') or 0:.2f}x ({r.get('cost_low') or 0:.2f}-" \
                     f"{r.get('cost_high') or 0:.2f})"
        cost = ("" if r.get("cost_ratio") is None else f", time per sample {per_sample}"
                + ("" if noise is None else
                   f", time to the same noise {noise[0]:.2f}x ({noise[1]:.2f}-{noise[2]:.2f})"))
        return f"{r['model']} (FLIP {r['image_flip']:.3f}, BRDF error {r['brdf_error']:.3f}{cost})"

    parts = []
    for material in dict.fromkeys(r["material"] for r in done):
        mine = sorted((r for r in done if r["material"] == material), key=lambda r: r["rank"])
        best = mine[0]
        alt = next((r for r in mine if r.get("looks_same_cheaper")), None)
        parts.append(f"{material}: {fit(best)}" + (f", or cheaper and looking the same {fit(alt)}"
                                                   if alt else ", no cheaper model looks the same"))
    return ("Which model for which material (ranked by the image's FLIP over three standard "
            "views; BRDF error 0 = identical, 1 = black; render cost against the material's own "
            "plugin, a 90 % interval; the cheaper model is the fit report's: in a lower cost "
            "class, with a FLIP within the material's seed noise of the best): "
            + "; ".join(parts) + ". The fit report with every model's errors, renders and XML "
            "is in trade/index.html.")


# ----------------------------------------------------------------------------
#  The files
# ----------------------------------------------------------------------------

# A group's section title (the group's name, what --only takes, beside it)
TITLES = {
    "builtin": "Plugins against Mitsuba's built-ins",
    "models": "Render time of every model",
    "oren_nayar": "Oren-Nayar: the table against the exact formulas",
    "sampling": "Sampling strategies: error at equal time",
    "integrators": "Integrators against a converged reference",
    "convergence": "Error against samples per pixel",
    "scaling": "Render time against resolution and lights",
    "lobes": "A lobe switched off costs nothing",
    "energy": "What energy compensation costs",
    "ladder": "The multiple-scattering ladder",
    "walk": "The walk in the bundled scenes",
    "materials": "Many materials in one scene",
    "frozen": "Frozen passes",
    "kernels": "The BSDF methods' kernels",
    "tracing": "Tracing one call of each method",
    "explore": "The explorer's latency",
    "trade": "Which model for which material",
    "fit": "How long a fit takes",
}


def title(group: str) -> str:
    """A group's section title, e.g. "Frozen passes (``frozen``)"."""
    return f"{TITLES[group]} (`{group}`)" if group in TITLES else group


# A table's column header: the key's words as a reader says them, its unit in
# brackets. HEADERS names the columns whose key alone does not say what they
# hold; every other key is read word by word (WORDS), its suffix the unit.
HEADERS = {
    "name": "configuration",
    "ratio": "time ratio",
    "relmse": "relMSE",
    "efficiency": "efficiency, 1 / (relMSE × time) (1/s)",
    "efficiency_vs_first": "efficiency over the first strategy's",
    "relative_to_lambert": "time over lambert's",
    "per_spp_s": "time per sample per pixel (s)",
    "slope": "log-log slope",
    "table": "table",
    "n": "runs",
    "floor": "floor beside it",
    "note": "note",
    "relmse_vs_exact": "relMSE against the exact formula",
    "max_abs_vs_exact": "largest absolute difference from the exact formula",
    "off_s": "compensation off (s)",
    "on_s": "compensation on (s)",
    "ms_vs_floor": "time over the floor's",
    "median_s": "median time (s)",
    "median_ms": "median time (ms)",
    "max_ms": "largest time (ms)",
    "render_calls_all": "render calls, all",
    "config": "configuration",
    "fit": "settings",
    "fits_s": "of it the fits (s)",
    "costs_s": "of it the render costs (s)",
    "load_before": "load average before",
    "load_after": "load average after",
    "res": "pixels across",
    "noise_relmse": "noise: relMSE against its own mean",
    "flip": "FLIP (HDR) of one render against the converged walk",
    "flip_mean": "FLIP of the renders' mean",
    "light_vs_walk": "light over the walk's",
    "time_vs_single": "time over single scattering's",
    "bsdfs": "Cook-Torrance BSDFs on the rung",
    "time_vs_directional": "time over the directional lobe's",
    "noise_vs_directional": "noise over the directional lobe's",
    "time_to_noise_vs_directional": "time to the same noise over the directional lobe's",
}
WORDS = {"builtin": "built-in", "first": "first render", "warm": "warm render",
         "peak": "peak memory", "relmse": "relMSE", "vs": "over",
         "codegen": "code generation", "execution": "kernel execution", "ops": "operations",
         "vars": "variables", "1": "one", "mib": "", "ms": "", "s": ""}
UNITS = {"s": "s", "ms": "ms", "mib": "MiB"}


def header(key: str) -> str:
    """A column's header, e.g. ``builtin_compile_s`` -> "built-in compile (s)"."""
    if key in HEADERS:
        return HEADERS[key]
    words = key.split("_")
    unit = UNITS.get(words[-1]) if len(words) > 1 else None
    text = " ".join(w for w in (WORDS.get(w, w) for w in words) if w)
    return f"{text} ({unit})" if unit else text


# ----------------------------------------------------------------------------
#  A report of several runs
# ----------------------------------------------------------------------------

RUN_KEYS = ("date", "settings_name", "smoke_test", "settings", "machine")
WRITTEN = ("README.md", "results.json", "results.csv")       # written again from the rows


def is_bench_report(folder: str) -> bool:
    """Whether ``folder`` holds a previous bench report (its marker says so)."""
    from .. import destinations
    try:
        with open(os.path.join(folder, destinations.MARKER)) as f:
            return json.load(f).get("command") == "bench"
    except (OSError, ValueError, AttributeError):
        return False


def load(folder: str, option: str) -> dict:
    """The results of the bench report in ``folder`` (their runs recorded:
    :func:`with_runs`); ValueError on one line if there is none to read."""
    path = os.path.join(folder, "results.json")
    try:
        with open(path) as f:
            results = json.load(f)
        if not isinstance(results.get("groups"), dict):
            raise ValueError("no groups")
    except (OSError, ValueError, AttributeError) as error:
        reason = getattr(error, "strerror", None) or str(error)
        raise ValueError(f"{option} {folder}: cannot read the bench report's results.json "
                         f"({reason}); give a bench report folder") from None
    return with_runs(results)


def with_runs(results: dict) -> dict:
    """``results`` with ``runs``: the runs its groups come from, each with its
    date (None when not recorded), settings, machine and its groups' seconds.
    A report written before runs were recorded is one run."""
    if "runs" not in results:
        results = dict(results, runs=[{
            **{k: results.get(k) for k in RUN_KEYS},
            "group_seconds": {g: results.get("group_seconds", {}).get(g)
                              for g in results["groups"]}}])
    return results


def taken(source: dict, names: list[str]) -> dict:
    """The groups ``names`` of the report ``source``, as a report of their own."""
    runs = [dict(run, group_seconds={g: t for g, t in run["group_seconds"].items()
                                     if g in names}) for run in source["runs"]]
    return summary({g: source["groups"][g] for g in names},
                   {g: source.get("plots", {}).get(g, []) for g in names
                    if source.get("plots", {}).get(g)},
                   [run for run in runs if run["group_seconds"]])


def merge(old: dict, new: dict) -> dict:
    """The report ``old`` with the groups of ``new`` in place of its own (the
    groups in the bench's order, groups it no longer has at the end)."""
    from .groups import GROUPS
    groups = {**old["groups"], **new["groups"]}
    order = [g for g in GROUPS if g in groups] + [g for g in groups if g not in GROUPS]
    plot_files = {**{g: p for g, p in old.get("plots", {}).items() if g not in new["groups"]},
                  **new.get("plots", {})}
    runs = [dict(run, group_seconds={g: t for g, t in run["group_seconds"].items()
                                     if g not in new["groups"]}) for run in old["runs"]]
    runs = [run for run in runs if run["group_seconds"]] + new["runs"]
    return summary({g: groups[g] for g in order},
                   {g: plot_files[g] for g in order if g in plot_files}, runs)


def summary(groups: dict, plot_files: dict, runs: list[dict]) -> dict:
    """A report's results from its groups, plots and runs: the settings'
    name (or "mixed"), the smoke-test flag if any run was one, the newest
    run's settings and machine, every group's seconds."""
    names = {run["settings_name"] for run in runs}
    seconds = {g: t for run in runs for g, t in run["group_seconds"].items()}
    return {"settings_name": names.pop() if len(names) == 1 else "mixed",
            "smoke_test": any(run["smoke_test"] for run in runs),
            "settings": runs[-1]["settings"], "machine": runs[-1]["machine"],
            "groups": groups, "group_seconds": {g: seconds.get(g) for g in groups},
            "seconds": sum(t or 0 for t in seconds.values()), "plots": plot_files,
            "runs": runs}


def smoke_groups(results: dict) -> set[str]:
    """The groups measured by a quick run (a smoke test: no findings)."""
    return {g for run in results["runs"] if run["smoke_test"] for g in run["group_seconds"]}


def group_files(folder: str, results: dict, names) -> list[str]:
    """The files of the groups ``names`` in the report ``folder``: their
    plots and the folder named after the group (e.g. ``trade/``), as paths
    relative to ``folder``."""
    files = [p for g in names for p in results.get("plots", {}).get(g, [])]
    for g in names:
        for base, _, found in os.walk(os.path.join(folder, g)):
            rel = os.path.relpath(base, folder).replace(os.sep, "/")
            files += [f"{rel}/{name}" for name in found]
    return files


def kept_files(folder: str, old: dict, replaced) -> list[str]:
    """The files of the previous report in ``folder`` that a run bringing
    the groups ``replaced`` keeps: all its marker lists but the files written
    again and the replaced groups' files."""
    from .. import destinations
    dropped = set(WRITTEN) | set(group_files(folder, old, replaced))
    return [n for n in destinations.previous_report(folder) or [] if n not in dropped]


def copy_files(source: str, target: str, names: list[str]) -> None:
    """Copy the files ``names`` (relative paths) from ``source`` into ``target``."""
    for name in names:
        path = os.path.join(target, *name.split("/"))
        os.makedirs(os.path.dirname(path), exist_ok=True)
        shutil.copy2(os.path.join(source, *name.split("/")), path)


# ----------------------------------------------------------------------------
#  Writing the report
# ----------------------------------------------------------------------------

def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def write_csv(path: str, results: dict) -> None:
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["group", "row", "key", "value"])
        for group, rows in results["groups"].items():
            for i, row in enumerate(rows):
                for k, v in row.items():
                    if not isinstance(v, list):
                        w.writerow([group, i, k, v])


def run_line(run: dict) -> str:
    """One run: its settings, date, seconds per group and machine."""
    seconds = run["group_seconds"]
    return (f"{run['settings_name']} run" + (f" of {run['date']}" if run.get("date") else "")
            + f", {sum(t or 0 for t in seconds.values()):.0f} s ("
            + ", ".join(g if t is None else f"{g} {t:.0f} s" for g, t in seconds.items())
            + "). Machine: " + ", ".join(f"{k} {v}" for k, v in run["machine"].items()) + ".")


def markdown(results: dict, about: dict[str, str], images: str = "") -> str:
    """README.md: the run, the findings (or the smoke-test notice), and per
    group what it measures (``about``), its table and its plots (their paths
    prefixed with ``images``: the documentation site shows the committed
    results from another folder)."""
    runs = with_runs(results)["runs"]
    lines = ["# mi-brdfs bench results", ""]
    if len(runs) == 1:
        lines += [run_line(runs[0]), ""]
    else:
        lines += [f"The groups come from {len(runs)} runs, {results['seconds']:.0f} s in all "
                  "(a partial run, `bench --only`, replaces its groups and keeps the others):",
                  "",
                  *(f"- {run_line(run)}" for run in runs), ""]
    present = [g for g, rows in results["groups"].items() if rows]
    smoke = [g for g in present if g in smoke_groups(with_runs(results))]
    if smoke and smoke == present:
        lines += [f"**{SMOKE_TEST}**", ""]
    elif smoke:
        lines += [f"**{', '.join(smoke)}: quick run (--quick), a smoke test; their numbers are "
                  "not measurements and draw no findings.**", ""]
    lines += ["Timings are medians of repeated renders after a warm-up (compile) render, "
              "in one process (materials, frozen, kernels, tracing: in processes of their own, "
              "as Dr.Jit traces every BSDF instance alive in the process); errors are relative "
              "MSE against a converged reference.", ""]
    if results.get("findings"):
        lines += ["## Findings", "", *(f"- {line}" for line in results["findings"]), ""]
    for group, rows in results["groups"].items():
        if not rows:
            continue
        # every row's keys, in order (a row may lack some: e.g. no floor beside it)
        keys = [k for k in dict.fromkeys(k for r in rows for k in r)
                if not any(isinstance(r.get(k), list) for r in rows)]
        lines += [f"## {title(group)}", ""]
        if about.get(group):
            lines += [about[group], ""]
        lines += ["| " + " | ".join(header(k) for k in keys) + " |", "|" + "---|" * len(keys)]
        lines += ["| " + " | ".join(_fmt(r.get(k, "")) for k in keys) + " |" for r in rows]
        lines += ["", *(f"![{p}]({images}{p})" for p in results["plots"].get(group, [])), ""]
    return "\n".join(lines)


def write(out_dir: str, results: dict, about: dict[str, str]) -> None:
    """results.json, results.csv and README.md in ``out_dir`` (the report's
    temporary folder: outputs.report_dir moves it into place when complete)."""
    with open(os.path.join(out_dir, "results.json"), "w") as f:
        json.dump(results, f, indent=1)
    write_csv(os.path.join(out_dir, "results.csv"), results)
    with open(os.path.join(out_dir, "README.md"), "w") as f:
        f.write(markdown(results, about))
