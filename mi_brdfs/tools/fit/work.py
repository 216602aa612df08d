"""What every fit of one target shares, computed once per target and handed
to its tasks (:func:`.task.fit_and_measure`) instead of once per model: the
metric's direction pairs, the target's values there, its lobe slices and
directional albedo, its renders in the standard views (seed 0) and the noise
floor of those renders (seed 1 against seed 0: FLIP and relMSE per view).

The noise floor alone was a third of a fit's time: three HDR-FLIP calls per
model on images that do not depend on the model. Everything here is NumPy
(it crosses to worker processes and Dask workers by pickling).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import effective, metric, scene


@dataclass
class TargetWork:
    """The per-target inputs of a fit (module docstring)."""
    pairs: metric.Pairs
    values: np.ndarray                  # (N, 3) the target's eval at the pairs
    slices: list                        # task.slices of the target
    albedo: list                        # effective.albedo of the target
    reference: dict | None = None       # view: (res, res, 3) float64 render, seed 0
    noise: dict | None = None           # view: {"flip", "relmse"} seed 1 against seed 0


def pairs_of(settings):
    return metric.pairs(settings.metric, settings.viewers, settings.uniform, settings.lobe)


def noise_floor(reference: dict, again: dict, res: int) -> dict:
    """FLIP and relMSE over the sphere's pixels of a second render of the
    target against the first, per view."""
    return scene.view_metrics(reference, again, res)


def prepare(target, settings) -> TargetWork:
    """:class:`TargetWork` of a :class:`.targets.Target` (the renders only
    when ``settings.render``); the variant must be set."""
    from .optimise import eval_pairs
    from .task import slices
    pairs = pairs_of(settings)
    bsdf = target.load()
    work = TargetWork(pairs, eval_pairs(bsdf, pairs.wi, pairs.wo), slices(bsdf),
                      effective.albedo(bsdf))
    del bsdf
    if settings.render:
        scene.release()
        work.reference = scene.target_views(target, settings.res, settings.spp, seed=0)
        again = scene.target_views(target, settings.res, settings.spp, seed=1)
        work.noise = noise_floor(work.reference, again, settings.res)
    return work
