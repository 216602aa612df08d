"""The speed/accuracy benchmark: ``mi-brdfs bench [--quick] [--only GROUP] -o OUT_DIR``.

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
anything else is refused before any work. ``--quick`` is a smoke test that
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
        cache_dir: str | None = None, log=print) -> dict:
    """Run the groups (``only``, or all) and write the report to ``out_dir``;
    the results. Unknown groups, missing dependencies and an unusable report
    folder are refused before any work."""
    names = only or list(GROUPS)
    for name in names:
        if name not in GROUPS:
            raise ValueError(f"unknown bench group {name!r}; valid: {', '.join(GROUPS)}")
    require()
    cache = cache_dir or DEFAULT_CACHE
    settings = QUICK if quick else FULL
    refs = References(cache, settings.ref_spp)
    with destinations.report_dir(out_dir, "bench", [cache]) as tmp:     # checked first
        if quick:
            log(f"bench: {report.SMOKE_TEST}")
        start = time.perf_counter()
        results = {"settings_name": "quick" if quick else "full", "smoke_test": quick,
                   "settings": settings.as_dict(), "machine": machine(), "groups": {},
                   "group_seconds": {}}
        for name in names:
            log(f"bench: {name} ...")
            group_start = time.perf_counter()
            group = GROUPS[name]
            results["groups"][name] = group.run(settings, refs, *([tmp] if group.writes else []))
            results["group_seconds"][name] = time.perf_counter() - group_start
        results["seconds"] = time.perf_counter() - start
        groups = [(GROUPS[name], rows) for name, rows in results["groups"].items() if rows]
        findings = [] if quick else [g.finding(rows) for g, rows in groups if g.finding]
        results["findings"] = [f for f in findings if f]
        results["plots"] = {g.name: plots.save(tmp, g.plots(rows)) for g, rows in groups
                            if g.plots}
        report.write(tmp, results, {g.name: g.about for g, _ in groups})
    return results
