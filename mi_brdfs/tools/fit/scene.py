"""The standard scene of every fit report, its renders and their timing.

A unit sphere seen from +z, filling most of the frame, under an environment
map and a key light, path traced with direct light only (``max_depth`` 2:
a lone convex object receives nothing else), the emitters hidden (the black
background adds no error). The environment map is made here (:func:`sky`,
no file): a bright overcast sky over a darker ground, with two soft
rectangular "windows" whose reflections show the shape of a glossy lobe; the
key light is a directional light from the upper left.

Render cost is measured side by side: the target's scene and the model's are
loaded, rendered and released in turn (rounds alternating which goes first),
so that only one BSDF instance is alive at each render — Dr.Jit traces every
live BSDF instance at every render, and a second one alive would be counted
in both. Each load gets one untimed render (the first of a fresh scene also
initialises its sensor and emitters) and one timed render; the cost ratio is
the median model time over the median target time.
"""
from __future__ import annotations

import gc
import math
import statistics
import time

import numpy as np

from ..analysis import camera

FOV = 30.0                 # degrees: the unit sphere seen from 4.5 fills ~85 % of the frame
DISTANCE = 4.5
SKY_SIZE = (64, 128)       # equirectangular environment map (rows, columns)
KEY = {"direction": [0.6, -0.55, -0.6], "irradiance": 4.0}


def sky() -> np.ndarray:
    """The environment map (H, W, 3) in Mitsuba's equirectangular layout
    (row 0 the zenith)."""
    h, w = SKY_SIZE
    theta = (np.arange(h) + 0.5) / h * math.pi            # from the zenith
    phi = (np.arange(w) + 0.5) / w * 2 * math.pi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    up = np.cos(t)
    sky_rgb = np.stack([0.25 + 0.1 * up, 0.3 + 0.12 * up, 0.4 + 0.12 * up], -1)
    ground = np.array([0.1, 0.08, 0.06])
    image = np.where((up > 0)[..., None], sky_rgb, ground)
    for centre, bright in ((1.2, 4.0), (4.0, 2.0)):         # two windows (φ centre, radiance)
        window = (np.abs(p - centre) < 0.35) & (t > 0.9) & (t < 1.35)
        image[window] = bright
    return image.astype(np.float32)


def scene_dict(bsdf: dict, res: int) -> dict:
    import mitsuba as mi
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2, "hide_emitters": True},
        "sensor": camera(res, FOV, origin=(0.0, 0.0, DISTANCE)),
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "env": {"type": "envmap", "bitmap": mi.Bitmap(sky())},     # +y up, as the camera
        "key": {"type": "directional", "direction": KEY["direction"],
                "irradiance": {"type": "rgb", "value": KEY["irradiance"]}},
    }


def _render(scene, spp: int, seed: int) -> np.ndarray:
    import drjit as dr
    import mitsuba as mi
    image = mi.render(scene, spp=spp, seed=seed)
    dr.eval(image)
    dr.sync_thread()
    return np.array(image, dtype=np.float64)[..., :3]


def release() -> None:
    """Free every object no longer referenced (BSDF instances included)."""
    gc.collect()


def side_by_side(target, model, res: int, spp: int, rounds: int) -> dict:
    """Renders of both BSDFs (seed 0, the same samples) and their render
    times, measured alternately with one scene alive at a time. ``target``
    and ``model`` make the BSDF (a dictionary or a loaded BSDF) afresh for
    each scene. Returns images (target, model, target at seed 1: the noise
    floor), times and the cost ratio."""
    import mitsuba as mi
    times = {"target": [], "model": []}
    images = {}
    for r in range(max(1, rounds)):
        order = ("target", "model") if r % 2 == 0 else ("model", "target")
        for which in order:
            make = target if which == "target" else model
            scene = mi.load_dict(scene_dict(make(), res), parallel=False)
            first = _render(scene, spp, seed=0)           # untimed (initialises the scene)
            images.setdefault(which, first)
            start = time.perf_counter()
            again = _render(scene, spp, seed=1 + r)
            times[which].append(time.perf_counter() - start)
            if which == "target":
                images.setdefault("target_seed1", again)
            del scene
            release()
    return {"images": images, "times": times,
            "cost_ratio": statistics.median(times["model"]) / statistics.median(times["target"])}
