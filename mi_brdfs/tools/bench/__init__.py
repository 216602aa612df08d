"""The speed/accuracy benchmark:
``mi-brdfs bench [--quick] [--only GROUP] [--merge REPORT] -o OUT_DIR``.

Timings are medians of repeated renders after a warm-up render, all in one
process so that ratios are meaningful on a noisy machine — except where the
number of BSDF instances alive matters (Dr.Jit traces every live instance at
every render): those groups measure in fresh processes. Errors are relative
MSE against converged references cached on disk. Every model's configuration
comes from the model's own cases (:mod:`mi_brdfs.bsdfs.cases`); the scenes
are the bench's (:mod:`.measure`, :mod:`.groups`).

The package, by concern:

- :mod:`.groups` — the groups, and :data:`GROUPS`, the one place a group is
  added (its runner, its finding, its plots);
- :mod:`.measure` — settings (:data:`QUICK`, :data:`FULL`), scenes, timing,
  errors, the reference cache;
- :mod:`.workers` — measurements in processes of their own
  (``python -m mi_brdfs.tools.bench --worker TASK OPTIONS_JSON``);
- :mod:`.anatomy` — what one traced call does (profiling);
- :mod:`.report` — results.json, results.csv, README.md and the findings;
- :mod:`.plots` — the figures.

OUT_DIR follows the rule of every report folder (:mod:`mi_brdfs.tools.destinations`):
new, empty, or a previous report (its marker file lists what it wrote);
anything else is refused before any work. A previous bench report there keeps
every group this run does not bring (``--only``: the lead's ``--only explore``
once deleted every other group's plots and the trade sweep); ``--merge
REPORT`` runs nothing and brings the groups of another bench report, as
they were measured (:mod:`.report`). ``--quick`` is a smoke test that
every group runs: it draws no findings, and says that its numbers are not
measurements.
"""
from __future__ import annotations

import os
import time

from .. import destinations
from . import plots, report
from .groups import GROUPS, Group
from .measure import (FULL, QUICK, References, Settings, efficiency, machine, scene_dict,
                      spheres_scene)
from .workers import in_subprocess

__all__ = ["run", "require", "GROUPS", "Group", "Settings", "QUICK", "FULL", "References",
           "efficiency", "scene_dict", "spheres_scene", "in_subprocess"]

DEFAULT_CACHE = os.path.join(os.path.expanduser("~"), ".cache", "mi_brdfs", "references")


def require() -> None:
    """Import what the bench needs beyond the plugins (matplotlib, for its
    plots) now, so that a missing one stops it before any group runs:
    ModuleNotFoundError names the module."""
    import matplotlib  # noqa: F401
    import matplotlib.figure  # noqa: F401


def run(out_dir: str, quick: bool = False, only: list[str] | None = None,
        cache_dir: str | None = None, log=print, merge: str | None = None) -> dict:
    """Run the groups (``only``, or all) and write the report to ``out_dir``;
    the report's results. With ``merge`` (a bench report folder) no group
    runs: its groups (``only``, or all of them) are taken as they were
    measured. A previous bench report in ``out_dir`` keeps the groups this run
    does not write (their rows, plots and folders; see :mod:`.report`).
    Unknown groups, missing dependencies, an unusable report folder and an
    unreadable previous report are refused before any work."""
    source = report.load(merge, "--merge") if merge else None
    names = only or (list(source["groups"]) if source else list(GROUPS))
    for name in names:
        if name not in GROUPS:
            raise ValueError(f"unknown bench group {name!r}; valid: {', '.join(GROUPS)}")
        if source and name not in source["groups"]:
            raise ValueError(f"--merge {merge} has no group {name!r}; it has: "
                             f"{', '.join(source['groups'])}")
    require()
    destinations.check_report_dir(out_dir, [] if merge else [cache_dir or DEFAULT_CACHE])
    previous = report.load(out_dir, "-o") if report.is_bench_report(out_dir) else None
    cache = cache_dir or DEFAULT_CACHE
    settings = QUICK if quick else FULL
    refs = References(cache, settings.ref_spp)
    with destinations.report_dir(out_dir, "bench", [] if merge else [cache]) as tmp:
        if source:
            results = report.taken(source, names)
            report.copy_files(merge, tmp, report.group_files(merge, source, names))
        else:
            results = measure(tmp, names, quick, settings, refs, log)
        if previous:
            kept = report.kept_files(out_dir, previous, results["groups"])
            report.copy_files(out_dir, tmp, kept)
            results = report.merge(previous, results)
        finish(tmp, results)
    return results


def measure(tmp: str, names: list[str], quick: bool, settings: Settings, refs: References,
            log) -> dict:
    """Run the groups ``names`` (writing into ``tmp``, the report's temporary
    folder, the groups that write files, and their plots): the results of one run."""
    if quick:
        log(f"bench: {report.SMOKE_TEST}")
    start = time.perf_counter()
    results = {"settings_name": "quick" if quick else "full", "smoke_test": quick,
               "settings": settings.as_dict(), "machine": machine(), "groups": {},
               "group_seconds": {}, "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    for name in names:
        log(f"bench: {name} ...")
        group_start = time.perf_counter()
        group = GROUPS[name]
        results["groups"][name] = group.run(settings, refs, *([tmp] if group.writes else []))
        results["group_seconds"][name] = time.perf_counter() - group_start
    results["seconds"] = time.perf_counter() - start
    results["plots"] = {}
    for name, rows in results["groups"].items():
        group = GROUPS[name]
        if rows and (group.plots or group.drawn):
            results["plots"][name] = ((plots.save(tmp, group.plots(rows)) if group.plots else [])
                                      + list(group.drawn))
    return report.with_runs(results)


def finish(tmp: str, results: dict) -> None:
    """The findings of every group measured by a full run (a quick run's are
    a smoke test's), drawn from its rows, then results.json, results.csv and
    README.md."""
    smoke = report.smoke_groups(results)
    results["findings"] = []
    for name, rows in results["groups"].items():
        group = GROUPS.get(name)
        if rows and group and group.finding and name not in smoke:
            finding = group.finding(rows)
            if finding:
                results["findings"].append(finding)
    report.write(tmp, results, {name: GROUPS[name].about for name, rows in
                                results["groups"].items() if rows and name in GROUPS})
