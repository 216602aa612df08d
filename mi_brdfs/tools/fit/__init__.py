"""Which course model represents a material, how well, at what cost:
``mi-brdfs fit TARGET [TARGET ...] -o DIR [--models NAME ...] [--quick]
[--metric cosine|ngan] [-j N] [--scheduler ADDRESS]``.

Each target (any Mitsuba BSDF: :mod:`.targets`) is fitted by every course
model (:mod:`.models`: each plugin in hdr mode, each D × G of
``cook_torrance``, each with and without energy compensation) with Dr.Jit's
AD and Adam, from several starts within each parameter's range, minimising a
BRDF-space metric (:mod:`.metric`); each fit is then rendered and timed
against the target in a standard scene (:mod:`.scene`). The fits run through
a ``concurrent.futures`` executor — local processes or a Dask cluster
(:mod:`.sweep`) — and the report folder (:mod:`.report`) holds
``fits.json``, ``fits.csv``, ``index.html`` and each fitted material as XML.
:mod:`.trade` is the fixed sweep behind the "which model for which
material" table.

Ngan, Durand & Matusik 2005, "Experimental Analysis of BRDF Models" (EGSR)
fitted models to measured materials and ranked them; this is that, for the
course's models, with the render cost beside the error.
"""
from __future__ import annotations

import os

from . import metric, models, targets
from .task import FULL, QUICK, Settings

__all__ = ["fit", "FULL", "QUICK", "Settings", "metric", "models", "targets"]


def fit(specs: list[str], out_dir: str, model_names: list[str] | None = None,
        quick: bool = False, metric_name: str = "cosine", jobs: int = 1,
        scheduler: str | None = None, show=None, command: str = "mi-brdfs fit",
        settings: Settings | None = None, also=None) -> list[dict]:
    """Fit every model to every target and write the report to ``out_dir``.
    Everything is checked before any fit starts: the report folder, the
    report dependencies, the models, the targets (each loaded once) and the
    scheduler. ``also(folder, records)`` may add files to the report.
    Returns the records (see :mod:`.report`)."""
    from .. import compare, outputs
    from . import report, sweep

    if metric_name not in metric.METRICS:
        raise ValueError(f"--metric {metric_name} is unknown; valid: {', '.join(metric.METRICS)}")
    chosen = models.select(model_names)
    parsed = targets.parse(specs)
    files = [t.spec for t in parsed if t.xml is not None]
    outputs.check_report_dir(out_dir, files)
    compare.require_reports()
    for t in parsed:
        targets.check(t)
    settings = (settings or (QUICK if quick else FULL)).replace(metric=metric_name)
    if scheduler:
        sweep.connect(scheduler).close()          # reachable, before any work
    records = sweep.run(parsed, chosen, settings, jobs=jobs, scheduler=scheduler, show=show)
    with outputs.report_dir(out_dir, "fit", files) as tmp:
        report.write(tmp, records, settings, command)
        if also:
            also(tmp, records)
    for r in records:
        r.pop("images", None)
    return records


def report_path(out_dir: str) -> str:
    return os.path.join(out_dir, "index.html")
