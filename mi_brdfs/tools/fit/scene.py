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

from ..analysis import camera
from ..measures import render_waited

FOV = 30.0                 # degrees: the unit sphere seen from 4.5 fills ~85 % of the frame
DISTANCE = 4.5
SKY_SIZE = (64, 128)       # equirectangular environment map (rows, columns)
KEY_IRRADIANCE = 3.0


def _from(theta_deg: float, up_deg: float) -> list[float]:
    """The direction light travels when it comes from θ off the camera's axis
    (+z), rotated ``up_deg`` above the image's horizontal."""
    t, a = math.radians(theta_deg), math.radians(up_deg)
    towards = (math.sin(t) * math.cos(a), math.sin(t) * math.sin(a), math.cos(t))
    return [-c for c in towards]


VIEWS = {                  # name: emitters besides none (the environment map is built in scene_dict)
    "environment": None,
    "grazing": _from(80.0, 30.0),
    "frontal": _from(10.0, 135.0),
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
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2, "hide_emitters": True},
        "sensor": camera(res, FOV, origin=(0.0, 0.0, DISTANCE)),
        "sphere": {"type": "sphere", "bsdf": bsdf},
    }
    if VIEWS[view] is None:
        scene["env"] = {"type": "envmap", "bitmap": mi.Bitmap(sky())}     # +y up, as the camera
    else:
        scene["key"] = {"type": "directional", "direction": VIEWS[view],
                        "irradiance": {"type": "rgb", "value": KEY_IRRADIANCE}}
    return scene


def render(scene, spp: int, seed: int) -> np.ndarray:
    """A render, evaluated and synchronised (H, W, 3) float64."""
    return np.array(render_waited(scene, spp, seed), dtype=np.float64)[..., :3]


def release() -> None:
    """Free every object no longer referenced (BSDF instances included):
    Dr.Jit traces every live BSDF instance at every render."""
    gc.collect()


def render_views(make, res: int, spp: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Renders of every view; ``make()`` makes the BSDF afresh for each scene,
    and each scene is released before the next is loaded."""
    images = {}
    for view in VIEWS:
        scene = mi.load_dict(scene_dict(make(), res, view))
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
