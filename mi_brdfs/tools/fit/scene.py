"""The standard views of every fit report and their renders.

A unit sphere seen from +z, filling most of the frame, path traced with
direct light only (``max_depth`` 2: a lone convex object receives nothing
else), the emitters hidden, in three lightings (:data:`VIEWS`):

- ``environment``: an environment map made here (:func:`sky`, no file): a
  bright overcast sky over a darker ground, with two soft rectangular
  "windows" whose reflections show the shape of a glossy lobe;
- ``grazing``: one directional key light 80° from the camera's axis, so that
  most of the visible surface is lit near the horizon and its highlight sits
  halfway to the rim;
- ``frontal``: one directional light 10° from the camera's axis: the
  highlight near the centre, viewer and light both grazing at the rim.

Image errors are taken over the sphere's pixels only (:func:`sphere_mask`:
the black background would dilute them alike for every model). The render
cost (:mod:`.cost`) is timed on the ``environment`` view, where a render
calls ``eval``, ``pdf`` and ``sample``.
"""
from __future__ import annotations

import gc
import math

import numpy as np

import mitsuba as mi

from .. import compare
from ..analysis import camera
from ..measures import render_waited

FOV = 30.0                 # degrees: the unit sphere seen from 4.5 fills ~85 % of the frame
DISTANCE = 4.5
SKY_SIZE = (64, 128)       # equirectangular environment map (rows, columns)
KEY_IRRADIANCE = 3.0


def light_from(theta_deg: float, up_deg: float) -> list[float]:
    """The direction light travels when it comes from θ off the camera's axis
    (+z), rotated ``up_deg`` above the image's horizontal."""
    t, a = math.radians(theta_deg), math.radians(up_deg)
    towards = (math.sin(t) * math.cos(a), math.sin(t) * math.sin(a), math.cos(t))
    return [-c for c in towards]


VIEWS = {                  # name: emitters besides none (the environment map is built in scene_dict)
    "environment": None,
    "grazing": light_from(80.0, 30.0),
    "frontal": light_from(10.0, 135.0),
}
COST_VIEW = "environment"


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


def scene_dict(bsdf, res: int, view: str = COST_VIEW) -> dict:
    """The sphere with ``bsdf`` (a dictionary or a loaded BSDF) in ``view``."""
    if view not in VIEWS:
        raise ValueError(f"unknown view {view!r}; valid: {', '.join(VIEWS)}")
    return sphere_scene(bsdf, res, VIEWS[view])


def sphere_scene(bsdf, res: int, light: list[float] | None) -> dict:
    """The standard views' sphere and camera with ``bsdf``, lit by the
    environment map (``light`` None) or by a directional light travelling
    along ``light`` (:func:`light_from`)."""
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2, "hide_emitters": True},
        "sensor": camera(res, FOV, origin=(0.0, 0.0, DISTANCE)),
        "sphere": {"type": "sphere", "bsdf": bsdf},
    }
    if light is None:
        scene["env"] = {"type": "envmap", "bitmap": mi.Bitmap(sky())}     # +y up, as the camera
    else:
        scene["key"] = {"type": "directional", "direction": light,
                        "irradiance": {"type": "rgb", "value": KEY_IRRADIANCE}}
    return scene


def render(scene, spp: int, seed: int) -> np.ndarray:
    """A render, evaluated and synchronised (H, W, 3) float64."""
    return np.array(render_waited(scene, spp, seed), dtype=np.float64)[..., :3]


def release() -> None:
    """Free every object no longer referenced (BSDF instances included):
    Dr.Jit traces every live BSDF instance at every render."""
    gc.collect()


def settle() -> None:
    """Once a worker process has imported Mitsuba, Dr.Jit and the plugins:
    collect, then move every object alive to the collector's permanent
    generation (``gc.freeze``), so that later collections walk only what the
    work allocates. Tracing a Python BSDF allocates many small objects, and
    each full collection walked the whole heap of the imported modules; in a
    fit's worker that was 40 % of its CPU time (gold α 0.1's 24 models at the
    quick settings, one process, one thread: 32 s -> 19 s; 171 calls of
    :func:`release` alone took 3.2 s). Objects frozen here are never freed by
    the collector; they are the imports, alive until the process ends."""
    gc.collect()
    gc.freeze()


def view_metrics(reference: dict, image: dict, res: int) -> dict[str, dict]:
    """HDR-FLIP and relMSE of ``image``'s renders against ``reference``'s over
    the sphere's pixels, per view (view: {"flip", "relmse"})."""
    mask = sphere_mask(res)
    out = {}
    for view in VIEWS:
        m = compare.metrics(reference[view], image[view], flip_mode="hdr", mask=mask)
        out[view] = {"flip": m["flip"], "relmse": m["relmse"]}
    return out


def render_views(make, res: int, spp: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Renders of every view; ``make()`` makes the BSDF afresh for each scene,
    and each scene is released before the next is loaded."""
    images = {}
    for view in VIEWS:
        scene = mi.load_dict(scene_dict(make(), res, view), parallel=False)   # as tools/render.py
        images[view] = render(scene, spp, seed)
        del scene
        release()
    return images


_TARGET_IMAGES: dict[tuple, dict] = {}       # a worker renders each target once per seed


def target_views(target, res: int, spp: int, seed: int = 0) -> dict[str, np.ndarray]:
    """:func:`render_views` of a :class:`.targets.Target`, cached in this process."""
    key = (target.spec, target.xml, res, spp, seed)
    if key not in _TARGET_IMAGES:
        make = (lambda: target.as_dict()) if target.xml is None else target.load
        _TARGET_IMAGES[key] = render_views(make, res, spp, seed)
    return _TARGET_IMAGES[key]


def sphere_mask(res: int) -> np.ndarray:
    """(res, res) True where the pixel's centre ray misses the sphere (the
    background, left out of the image errors)."""
    half = math.tan(math.radians(FOV) / 2)
    c = ((np.arange(res) + 0.5) / res * 2 - 1) * half
    x, y = np.meshgrid(c, c)
    d = np.stack([x, y, -np.ones_like(x)], -1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    along = -DISTANCE * d[..., 2]                        # o·d with o = (0, 0, DISTANCE)
    return DISTANCE ** 2 - along ** 2 >= 1.0


# ----------------------------------------------------------------------------
#  Noise: the variance at equal samples
# ----------------------------------------------------------------------------

NOISE_CONFIDENCE = 0.90
NOISE_BOOTSTRAP = 1000     # resamples of the pixels for the variance ratio's interval
NOISE_BLOCKS = 512         # ... resampled in at most this many runs of consecutive pixels
RELMSE_OFFSET = 0.01       # as relMSE's (measures.relmse): (ref + 0.01)² in the denominator


def seed_views(make, res: int, spp: int, seeds) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per view, the mean and the per-pixel sample variance (ddof 1) of
    renders at each of ``seeds`` (each scene loaded once): (H, W, 3) each.
    The views' sampler is ``independent`` and their filter a box
    (:func:`..analysis.camera`), so the renders are independent and a pixel's
    variance is its samples' variance over ``spp``."""
    seeds = list(seeds)
    if len(seeds) < 2:
        raise ValueError(f"fit noise: seeds {seeds} is fewer than 2; a variance needs 2 or more")
    out = {}
    for view in VIEWS:
        scene = mi.load_dict(scene_dict(make(), res, view), parallel=False)
        images = np.stack([render(scene, spp, s) for s in seeds])
        out[view] = (images.mean(axis=0), images.var(axis=0, ddof=1))
        del scene, images
        release()
    return out


_TARGET_NOISE: dict[tuple, dict] = {}


def target_seed_views(target, res: int, spp: int, seeds) -> dict:
    """:func:`seed_views` of a :class:`.targets.Target`, cached in this process."""
    key = (target.spec, target.xml, res, spp, tuple(seeds))
    if key not in _TARGET_NOISE:
        make = (lambda: target.as_dict()) if target.xml is None else target.load
        _TARGET_NOISE[key] = seed_views(make, res, spp, seeds)
    return _TARGET_NOISE[key]


def variance_ratio(model: dict, target: dict, model_image: dict, target_image: dict,
                   mask: np.ndarray, boots: int = NOISE_BOOTSTRAP,
                   confidence: float = NOISE_CONFIDENCE, rng_seed: int = 0
                   ) -> tuple[float, float, float]:
    """(ratio, low, high): the model's relative pixel variance over the
    target's at equal samples, and its ``confidence`` interval (percentile
    bootstrap over the sphere's pixels, the views' pixels resampled together
    in at most :data:`NOISE_BLOCKS` runs of consecutive pixels: the pixels
    are independent, and 512 sums resample in hundredths of a second where
    30 000 pixels took 1.4 s, to the same interval within 0.003).

    ``model`` and ``target`` are :func:`seed_views` results. Each one's
    variance is taken as relMSE's noise term against its own image: per pixel
    and channel var / (image + 0.01)², summed over the sphere's pixels
    (``mask``: True off the sphere, :func:`sphere_mask`) of every view, with
    ``model_image`` and ``target_image`` renders of each (per view). The
    expected relMSE of a render against its own converged image is that sum
    over the pixels / spp, so the ratio is the factor of samples the model
    needs to be as clean, relative to what it shows, as the target's render
    (a darker model is not cleaner for being dark). The images must be
    renders of their own: weighed by the mean of the noise renders
    themselves, a variance reads low (a pixel whose samples came out high has
    a larger variance and a smaller weight; measured: a model against itself
    read 1.05-1.11). The views are pooled, not averaged: the noise of the set
    is its sum, which the environment view, where ``sample`` matters,
    dominates."""
    keep = ~mask
    num, den = [], []
    for view in VIEWS:
        for out, noise, image in ((num, model, model_image), (den, target, target_image)):
            weight = 1.0 / (image[view][keep] + RELMSE_OFFSET) ** 2
            out.append((noise[view][1][keep] * weight).sum(axis=-1))
    num, den = np.concatenate(num), np.concatenate(den)
    if not den.sum() > 0:
        return math.nan, math.nan, math.nan
    ratio = float(num.sum() / den.sum())
    edges = np.linspace(0, len(num), min(len(num), NOISE_BLOCKS) + 1).astype(int)[:-1]
    num, den = np.add.reduceat(num, edges), np.add.reduceat(den, edges)
    pick = np.random.default_rng(rng_seed).integers(0, len(num), (boots, len(num)))
    ratios = num[pick].sum(axis=1) / np.maximum(den[pick].sum(axis=1), 1e-300)
    tail = (1.0 - confidence) / 2 * 100
    low, high = np.percentile(ratios, [tail, 100 - tail])
    return ratio, float(low), float(high)
