"""The numbers the reports share, defined once: the relative MSE of an image
against a reference, the Pareto front of (cost, error) points, and a render
waited for (what a timing needs).

``compare`` reports the relative MSE among its metrics, ``bench`` measures
errors against converged references with it, and ``bench`` and ``fit`` draw
Pareto fronts of cost against error.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

import drjit as dr
import mitsuba as mi

RELMSE_OFFSET = 0.01     # keeps black reference pixels from dominating (pbrt's relative MSE)


def relmse(test: np.ndarray, ref: np.ndarray, axis=None):
    """mean((test - ref)² / (ref + 0.01)²) over ``axis``: a Python float over
    every element (the default), an array over one axis."""
    d = test - ref
    mean = np.mean(d * d / (ref + RELMSE_OFFSET) ** 2, axis=axis)
    return float(mean) if axis is None else mean


def pareto(points: Sequence[tuple[float, float]]) -> list[bool]:
    """For (cost, error) points: True where no other point is at least as cheap
    and as accurate and strictly better in one of the two."""
    front = []
    for i, (t, e) in enumerate(points):
        dominated = any(t2 <= t and e2 <= e and (t2 < t or e2 < e)
                        for j, (t2, e2) in enumerate(points) if j != i)
        front.append(not dominated)
    return front


def render_waited(scene, spp: int, seed: int):
    """``mi.render``, evaluated and waited for: its time is the render's."""
    image = mi.render(scene, spp=spp, seed=seed)
    dr.eval(image)
    dr.sync_thread()
    return image
