"""The material-preview scene: a unit sphere under an environment made here at
start-up (no file), plus a key light.

The environment is a studio in latitude-longitude (Mitsuba's ``envmap``
convention: u = φ/2π with φ = atan2(x, -z), v = θ/π from +y): a sky that
brightens towards the horizon, a dark floor, and two bright soft boxes whose
reflections show a glossy lobe's width. The key light is a ``directional``
emitter from the upper right, exact in both integrators (the scan-line one
estimates the environment from one sample per pixel sample).
"""
from __future__ import annotations

import numpy as np

import mitsuba as mi

ENV_SIZE = (256, 128)                  # width, height of the environment image
KEY_DIRECTION = (-1.0, -1.1, -1.4)     # the key light travels this way (from upper right front)
KEY_IRRADIANCE = 2.5
CAMERA = {"origin": [0.0, 0.35, 4.2], "target": [0.0, 0.0, 0.0], "fov": 30.0}


def _boxes(x, y, z) -> np.ndarray:
    """Two soft boxes: a large one at the upper left behind the camera, a strip on the right."""
    def box(centre, size, width):
        cx, cy, cz = np.asarray(centre) / np.linalg.norm(centre)
        # angular distance from the box's centre, squashed into a rounded rectangle
        d = np.arccos(np.clip(x * cx + y * cy + z * cz, -1.0, 1.0))
        return 1.0 / (1.0 + np.exp((d - size) / width))
    return 7.0 * box((-0.8, 0.7, 0.9), 0.35, 0.04) + 4.0 * box((1.0, 0.15, -0.2), 0.18, 0.03)


def environment() -> np.ndarray:
    """The environment's radiance, (height, width, 3) float32."""
    width, height = ENV_SIZE
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    phi, theta = np.meshgrid(2.0 * np.pi * u, np.pi * v)
    x, y, z = np.sin(phi) * np.sin(theta), np.cos(theta), -np.cos(phi) * np.sin(theta)
    zenith, horizon = np.array([0.30, 0.42, 0.70]), np.array([0.95, 0.92, 0.88])
    up = np.clip(y, 0.0, 1.0)[..., None] ** 0.6
    sky = horizon * (1.0 - up) + zenith * up
    floor = np.array([0.16, 0.145, 0.13]) * (0.6 + 0.4 * np.clip(1.0 + y, 0.0, 1.0))[..., None]
    blend = (1.0 / (1.0 + np.exp(-y / 0.02)))[..., None]          # a soft horizon
    radiance = sky * blend + floor * (1.0 - blend) + _boxes(x, y, z)[..., None]
    return radiance.astype(np.float32)


def scene_dict(bsdf, res: int, integrator: dict, env, light: float = 1.0) -> dict:
    """The preview scene with ``bsdf`` (a loaded BSDF, shared with whoever
    else holds it) at ``res`` × ``res`` pixels; ``env`` an ``mi.Bitmap`` of
    :func:`environment`; ``light`` scales every emitter."""
    look = mi.ScalarTransform4f().look_at(origin=CAMERA["origin"], target=CAMERA["target"],
                                          up=[0.0, 1.0, 0.0])
    return {
        "type": "scene",
        "integrator": integrator,
        "sensor": {"type": "perspective", "fov": CAMERA["fov"], "to_world": look,
                   "film": {"type": "hdrfilm", "width": res, "height": res,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent"}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "environment": {"type": "envmap", "bitmap": env, "scale": light},
        "key": {"type": "directional", "direction": list(KEY_DIRECTION),
                "irradiance": {"type": "rgb", "value": [KEY_IRRADIANCE * light] * 3}},
    }
