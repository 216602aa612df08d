"""Which course model represents a material, how well, at what cost:
``mi-brdfs fit TARGET [TARGET ...] -o DIR [--models NAME ...] [--quick]
[--metric cosine|ngan] [-j N] [--scheduler ADDRESS]``.

Each target (any Mitsuba BSDF: :mod:`.targets`) is fitted by every course
model (:mod:`.models`: each plugin in hdr mode, each D × G of
``cook_torrance``, each with and without energy compensation), on a
compressed BRDF-space objective (:mod:`.metric`), by a scan of the shape
parameters with the colours solved by least squares, then Levenberg-Marquardt
with Dr.Jit's AD (:mod:`.optimise`). Each fit is rendered against the target
in three standard views (:mod:`.scene`); the models are ranked by the
images' FLIP (:mod:`.rank`), and each one's render cost is measured against
the target's in processes of their own until its interval is tight, beside a
count of its traced operations (:mod:`.cost`). The fits run through a
``concurrent.futures`` executor — local processes or a Dask cluster
(:mod:`.sweep`) — and the report folder (:mod:`.report`) holds
``fits.json``, ``fits.csv``, ``index.html`` and each fitted material as XML.
:mod:`.effective` gives what the parameters mean (effective colours, albedo)
and the target's features no course model has; :mod:`.trade` is the fixed
sweep behind the "which model for which material" table; :mod:`.scenefit`
answers per scene (``mi-brdfs fit --scene``).

Ngan, Durand & Matusik 2005, "Experimental Analysis of BRDF Models" (EGSR)
fitted models to measured materials and ranked them; this is that, for the
course's models, with the render cost beside the error.
"""
from __future__ import annotations

import os
import sys
import time

from .. import compare, destinations
from . import cost, effective, metric, models, report, sweep, targets, work
from .task import FULL, QUICK, Settings

__all__ = ["fit", "FULL", "QUICK", "Settings", "metric", "models", "targets"]


def _stderr(message: str) -> None:
    print(f"mi-brdfs fit: warning: {message}", file=sys.stderr)


def fit(specs: list[str], out_dir: str, model_names: list[str] | None = None,
        quick: bool = False, metric_name: str = "cosine", jobs: int | None = None,
        scheduler: str | None = None, show=None, command: str = "mi-brdfs fit",
        settings: Settings | None = None, also=None, warn=_stderr,
        worker_timeout: float | None = None) -> list[dict]:
    """Fit every model to every target and write the report to ``out_dir``.
    Everything is checked before any fit starts: the report folder, the
    report dependencies, the models, the targets (each loaded once; a
    repeated one is fitted once, with ``warn``) and the scheduler (reachable,
    with a worker within ``worker_timeout`` seconds). ``also(folder,
    records)`` may add files to the report. ``jobs``: local fits at once
    (None: :func:`.sweep.default_jobs`). Returns the records (see
    :mod:`.report`)."""
    if metric_name not in metric.METRICS:
        raise ValueError(f"--metric {metric_name} is unknown; valid: {', '.join(metric.METRICS)}")
    chosen = models.select(model_names)
    parsed, repeated = targets.unique(targets.parse(specs))
    files = [t.spec for t in parsed if t.xml is not None]
    destinations.check_report_dir(out_dir, files)
    compare.require_reports()
    settings = (settings or (QUICK if quick else FULL)).replace(metric=metric_name)
    if settings.objective not in metric.OBJECTIVES:
        raise ValueError(f"objective {settings.objective} is unknown; valid: "
                         f"{', '.join(metric.OBJECTIVES)}")
    for spec in repeated:
        warn(f"target {spec} is given more than once; it is fitted once")
    found = {}
    for t in parsed:
        targets.check(t)
        found[t.name] = effective.target_features(t, settings)
    timeout = sweep.WORKER_TIMEOUT if worker_timeout is None else worker_timeout
    client = sweep.connect(scheduler, timeout) if scheduler else None
    names = {m.name for m in chosen}
    tasks = [(t, m) for t in parsed
             for m in chosen + [e for e in effective.extended_models(found[t.name],
                                                                     rungs=not model_names)
                                if e.name not in names]]
    measuring = settings.render and settings.cost
    total = len(tasks)                 # models fitted, then models timed (show: per phase)
    start = time.perf_counter()
    works = {t.name: prepared(t, settings) for t in parsed}
    try:
        records = sweep.run_fits(tasks, settings, jobs=jobs,
                                 scheduler=scheduler, show=show,
                                 client=client, worker_timeout=timeout, total=total, start=start,
                                 works=works)
    finally:
        if client is not None:
            client.close()
    if measuring:
        cost.measure_all(parsed, records, settings, show, total=total, start=start)
    with destinations.report_dir(out_dir, "fit", files) as tmp:
        records = report.write(tmp, records, settings, command, found)
        if also:
            also(tmp, records)
    for r in records:
        r.pop("images", None)
    return records


def prepared(target, settings: Settings):
    """The target's :class:`.work.TargetWork`, once for all its fits; None if
    it fails (each task then tries again and records the error)."""
    try:
        return work.prepare(target, settings)
    except Exception:                  # the tasks report it, one record each
        return None


def report_path(out_dir: str) -> str:
    return os.path.join(out_dir, "index.html")
