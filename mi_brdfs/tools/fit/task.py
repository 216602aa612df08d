"""One fit, target × model, as a worker runs it (in a process of its own or
on a Dask worker): the model fitted to the target (:mod:`.optimise`), its
effective parameters and directional albedo (:mod:`.effective`), its lobe
slices, and its renders in the standard views against the target's
(:mod:`.scene`: FLIP and relMSE per view). The render cost is measured
afterwards, one process at a time (:mod:`.cost`): timings taken while other
fits run would measure the load.
"""
from __future__ import annotations

import os
import socket
import time
import traceback
from dataclasses import dataclass

import numpy as np

import mitsuba as mi

import mi_brdfs

from ..analysis import eval_at_viewer
from ..errors import one_line
from ..settings import Settings as SettingsBase
from . import effective, models as M, optimise, scene
from .work import prepare

SLICE_ANGLES = (0.0, 30.0, 60.0, 80.0)     # viewer angles of the lobe slices (degrees)
SLICE_POINTS = 181


@dataclass(frozen=True)
class Settings(SettingsBase):
    """How much work one fit does (:data:`QUICK`, :data:`FULL`)."""
    metric: str = "cosine"                   # the reported BRDF error (metric.METRICS)
    objective: str = "cbrt"                  # what the fit minimises (metric.OBJECTIVES)
    viewers: tuple[int, int] = (12, 6)       # viewer strata (cos θ, φ)
    uniform: tuple[int, int] = (12, 12)      # uniform light strata per viewer
    lobe: int = 36                           # mirror-guided lights per viewer and roughness
    scan: int = 48                           # candidate settings scanned (optimise.py)
    starts: int = 3                          # the best candidates refined
    steps: int = 150                         # residual evaluations per refinement, at most
    res: int = 128                           # the standard views
    spp: int = 64
    render: bool = True                      # renders and image errors (else: the fit only)
    cost: bool = True                        # render cost (mi_brdfs.tools.fit.cost)
    cost_rounds: tuple[int, int] = (3, 12)   # cost: at least, at most this many rounds
    cost_tolerance: float = 0.10             # cost: until the 90 % interval's high/low <= 1.10
    #   (as sure as the variance ratio, the time to the same noise's other factor: its
    #   intervals read high/low 1.03-1.29, median about 1.1; cost.py's docstring)
    cost_timing: str = "cpu"                 # cost: what a round times (cost.TIMINGS)
    cost_spp: int = 32                       # cost: samples per pixel of a timed render
    noise_seeds: int = 8                     # noise: renders at this many seeds per view
    noise_spp: int = 4                       # noise: at this many samples per pixel each


FULL = Settings()
QUICK = Settings(viewers=(8, 4), uniform=(8, 8), lobe=16, res=48,
                 spp=16, cost_rounds=(3, 6), cost_spp=16, noise_seeds=6)


def slices(bsdf) -> list[list[list[float]]]:
    """eval per channel in the plane of incidence at each SLICE_ANGLES viewer:
    [angle][channel][point]."""
    theta = np.radians(np.linspace(-89.5, 89.5, SLICE_POINTS))
    wo = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)
    return [eval_at_viewer(bsdf, a, wo).T.tolist() for a in SLICE_ANGLES]


# ----------------------------------------------------------------------------
#  One task
# ----------------------------------------------------------------------------

def fit_and_measure(target, model, settings: Settings, work=None) -> dict:
    """Fit ``model`` to ``target`` (a :class:`.targets.Target`) and measure it;
    ``work``: the target's :class:`.work.TargetWork` (computed here if None).
    Never raises: a failure is returned as a record with an ``error`` message."""
    try:
        return _fit_and_measure(target, model, settings, work)
    except Exception as error:                     # reported in the record, not lost
        return {"target": target.spec, "model": model.name, "plugin": model.plugin,
                "error": one_line(error), "traceback": traceback.format_exc(),
                "worker": worker_name()}


def worker_name() -> str:
    """host:pid of the process that ran a task (a re-run shows another)."""
    return f"{socket.gethostname()}:{os.getpid()}"


def _fit_and_measure(target, model, settings: Settings, work) -> dict:
    if mi.variant() != "llvm_ad_rgb":
        mi.set_variant("llvm_ad_rgb")
        mi_brdfs.register()
        scene.settle()                       # the worker's first task: the imports are done
    start = time.perf_counter()
    if work is None:
        work = prepare(target, settings)
    prob = optimise.problem_from_values(work.values, work.pairs, settings.objective)
    if not prob.norm > 0:
        raise ValueError(f"target {target.spec} reflects no light at the metric's pairs")
    fit = optimise.fit_model(model, prob, settings)
    fitted = mi.load_dict(M.load_dict(fit["parameters"]))
    model_slices = slices(fitted)
    model_albedo = effective.albedo(fitted)
    del fitted, prob
    record = {"target": target.spec, "target_name": target.name, "model": model.name,
              "plugin": model.plugin, "parameters": fit["parameters"],
              "brdf_error": fit["brdf_error"], "metric": settings.metric,
              "objective": settings.objective, "objective_error": fit["objective"],
              "image_relmse": None, "image_flip": None, "image_noise_relmse": None,
              "image_noise_flip": None, "cost_ratio": None, "cost_low": None,
              "cost_high": None, "ops_ratio": None, "noise_ratio": None,
              "noise_low": None, "noise_high": None,
              "effective": effective.parameters(model.plugin, fit["parameters"]),
              "albedo": model_albedo, "target_albedo": work.albedo,
              "starts": fit["starts"], "worker": worker_name(),
              "slices": {"angles": list(SLICE_ANGLES), "target": work.slices,
                         "model": model_slices}}
    if settings.render:
        scene.release()
        record.update(images(target, fit["parameters"], settings, work))
    record["seconds"] = time.perf_counter() - start
    return record


NOISE_SEEDS = {"target": 1000, "model": 2000}   # the first seed of each one's noise renders


def noise_seeds(who: str, settings: Settings) -> range:
    return range(NOISE_SEEDS[who], NOISE_SEEDS[who] + settings.noise_seeds)


def variance(target, properties: dict, settings: Settings, reference: dict,
             image: dict) -> dict:
    """The fitted model's pixel variance over the target's at equal samples,
    with its 90 % interval (:func:`.scene.variance_ratio`), from
    ``noise_seeds`` renders of each per view at ``noise_spp``, each weighed by
    its own render at ``spp`` (``reference`` the target's, ``image`` the
    model's, per view; the target's noise renders are kept per process:
    :func:`.scene.target_seed_views`); the model's seeds are not the
    target's, so a model that is the target reads about 1, not exactly 1."""
    own = scene.target_seed_views(target, settings.res, settings.noise_spp,
                                  noise_seeds("target", settings))
    model = scene.seed_views(lambda: M.load_dict(properties), settings.res, settings.noise_spp,
                             noise_seeds("model", settings))
    ratio, low, high = scene.variance_ratio(model, own, image, reference,
                                            scene.sphere_mask(settings.res))
    return {"noise_ratio": ratio, "noise_low": low, "noise_high": high,
            "noise_seeds": settings.noise_seeds, "noise_spp": settings.noise_spp}


def images(target, properties: dict, settings: Settings, work=None) -> dict:
    """The fitted model's renders against the target's in every view: FLIP
    and relMSE over the sphere's pixels per view, and their means; its pixel
    variance over the target's (:func:`variance`). The target's renders and its
    noise floor come from ``work``, or are rendered here."""
    if work is None or work.reference is None:
        from .work import noise_floor
        reference = scene.target_views(target, settings.res, settings.spp, seed=0)
        again = scene.target_views(target, settings.res, settings.spp, seed=1)
        noise = noise_floor(reference, again, settings.res)
    else:
        reference, noise = work.reference, work.noise
    model = scene.render_views(lambda: M.load_dict(properties), settings.res, settings.spp, 0)
    views = scene.view_metrics(reference, model, settings.res)
    mean = lambda d, k: float(np.mean([v[k] for v in d.values()]))
    return {**variance(target, properties, settings, reference, model),
            "image_flip": mean(views, "flip"), "image_relmse": mean(views, "relmse"),
            "image_noise_flip": mean(noise, "flip"), "image_noise_relmse": mean(noise, "relmse"),
            "image_views": views,
            "images": {"target": {v: a.astype(np.float32) for v, a in reference.items()},
                       "model": {v: a.astype(np.float32) for v, a in model.items()}},
            "render": {"res": settings.res, "spp": settings.spp, "seed": 0,
                       "views": list(scene.VIEWS)}}
