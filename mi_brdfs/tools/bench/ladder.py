"""The multiple-scattering ladder: ``cook_torrance`` (GGX, Smith's G) with each
way the project has of treating the light that bounces between microfacets,
rendered on the same spheres under the same lights (the bench group
``ladder``, :func:`.groups.ladder`).

The rungs (:data:`RUNGS`), each a set of options of the plugin:

- ``single``: the microfacet model's single scattering, no compensation;
- ``separable``: ``energy_compensation`` with ``compensation="separable"``, the
  separable lobe g(ω_i) g(ω_o) that adds what single scattering misses of the
  walk's albedo;
- ``directional``: ``energy_compensation`` (its default lobe), the walk's
  bounces k >= 2 tabulated by pair of directions beside the height-correlated
  single scattering (:mod:`mi_brdfs.bsdfs.directional`);
- ``walk``: ``multiple_scattering="walk"``, the random walk on the Smith
  microsurface evaluated and sampled in the renderer: the truth, noisy.

A new rung is one more entry in :data:`RUNGS`.
The materials (:data:`MATERIALS`) are a rough gold and a rough white
conductor; the lightings (:data:`LIGHTINGS`) the fit's environment map
(:func:`..fit.scene.sky`), a directional light from behind the sphere, which
reaches the camera only near the silhouette, where viewer and light are both
grazing on either side of the normal (near the mirror pair), and one from
behind the camera, where at the silhouette they are both grazing on the same
side (near retro-reflection): the pairs where the separable lobe and the walk
differ most (issue 36).

The sphere and camera are the fit's standard views' (:mod:`..fit.scene`):
direct light only (a convex object receives nothing else), the emitters
hidden, and the errors taken over the sphere's pixels (:func:`..fit.scene.sphere_mask`).

The bench group ``walk`` (:func:`measure_scene`) puts the rungs of
:data:`SCENE_RUNGS` in the bundled scenes of :data:`SCENES` instead, each
``cook_torrance`` the walk takes changed in the scene's XML (:func:`scene_xml`).
"""
from __future__ import annotations

import statistics
import time
from dataclasses import dataclass

import numpy as np

import mitsuba as mi

from ..compare import masked_flip
from ..fit import scene as views
from ..measures import relmse
from .measure import References

# The plugin every rung is a setting of: GGX with Smith's G, a pure conductor
# (no diffuse lobe).
BASE = {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith", "k": 0.0,
        "mode": "hdr"}

RUNGS: list[tuple[str, dict]] = [            # name, the options that make the rung
    ("single", {}),
    ("separable", {"energy_compensation": True, "compensation": "separable"}),
    ("directional", {"energy_compensation": True}),
    ("walk", {"multiple_scattering": "walk"}),
]
TRUTH = "walk"                                # the rung the converged reference renders

MATERIALS: list[tuple[str, dict]] = [        # name, the material's parameters
    ("gold α 0.4", {"fresnel": "conductor", "material": "Au", "alpha": 0.4}),
    ("white α 0.8", {"fresnel": "schlick", "f0": 1.0, "alpha": 0.8}),
]

# name: the directional light's direction (fit.scene.light_from: θ off the camera's
# axis, turned this far above the image's horizontal, in degrees), or None: the
# environment map.
LIGHTINGS: dict[str, list[float] | None] = {
    "environment": None,
    "back light": views.light_from(160.0, 30.0),   # behind the sphere: seen only near the silhouette
    "front light": views.VIEWS["frontal"],         # behind the camera (the fit's frontal view)
}


def bsdf(material: str, rung: str) -> dict:
    """The plugin of ``material`` on ``rung``."""
    return {**BASE, **dict(MATERIALS)[material], **dict(RUNGS)[rung]}


def scene_dict(bsdf: dict, res: int, lighting: str) -> dict:
    """The fit's sphere and camera with ``bsdf`` in ``lighting``."""
    if lighting not in LIGHTINGS:
        raise ValueError(f"unknown ladder lighting {lighting!r}; valid: {', '.join(LIGHTINGS)}")
    return views.sphere_scene(bsdf, res, LIGHTINGS[lighting])


@dataclass
class Case:
    """One (material, lighting, rung): its row and its mean render."""
    row: dict
    mean: np.ndarray          # the mean of the timed renders (H, W, 3)


def reference(material: str, lighting: str, res: int, refs: References) -> np.ndarray:
    """The converged render of the walk (cached by ``refs``)."""
    image = refs.get(scene_dict(bsdf(material, TRUTH), res, lighting))
    views.release()
    return image


def timed_renders(scene, spp: int, repeats: int) -> tuple[list[np.ndarray], list[float]]:
    """``scene`` rendered once to compile (seed 0), then ``repeats`` times at
    ``spp`` (seeds 1, 2, ...): those renders and their times (s)."""
    images, seconds = [], []
    for seed in range(repeats + 1):
        start = time.perf_counter()
        images.append(views.render(scene, spp, seed))
        seconds.append(time.perf_counter() - start)
    return images[1:], seconds[1:]


def measure(material: str, lighting: str, rung: str, res: int, spp: int, repeats: int,
            truth: np.ndarray) -> Case:
    """Render ``rung`` of ``material`` in ``lighting`` once to compile, then
    ``repeats`` times at ``spp`` (seeds 1, 2, ...), the only BSDF alive in the
    process (Dr.Jit traces every live instance at every render).

    The row: the median render time; the noise, the expected relMSE of one
    render against its own expectation (the per-pixel variance over the
    renders, weighed by the converged walk ``truth`` as relMSE weighs a
    render: (truth + 0.01)²); one render's relMSE and HDR-FLIP against
    ``truth``; the FLIP of the renders' mean (mostly what the rung gets
    wrong, less its noise); and the light it reflects towards the camera, the
    sum of that mean over the sphere's pixels, against the walk's."""
    scene = mi.load_dict(scene_dict(bsdf(material, rung), res, lighting), parallel=False)
    images, seconds = timed_renders(scene, spp, repeats)
    del scene
    views.release()
    stack = np.stack(images)
    mean = stack.mean(axis=0)
    on = ~views.sphere_mask(res)
    weight = 1.0 / (truth[on] + 0.01) ** 2
    row = {"material": material, "lighting": lighting, "rung": rung, "res": res, "spp": spp,
           "median_s": statistics.median(seconds),
           "noise_relmse": float(np.mean(stack.var(axis=0, ddof=1)[on] * weight)),
           "relmse": relmse(images[0][on], truth[on]),
           "flip": masked_flip(truth, images[0], "hdr", ~on)[0],
           "flip_mean": masked_flip(truth, mean, "hdr", ~on)[0],
           "light_vs_walk": float(mean[on].sum() / truth[on].sum())}
    return Case(row, mean)


# ----------------------------------------------------------------------------
#  The rungs in the bundled scenes
# ----------------------------------------------------------------------------

# The bundled scenes with a cook_torrance the walk can stand for, and the
# parameters (-D) they are rendered with: path traced (HDR), as a user renders them.
SCENES: list[tuple[str, dict]] = [
    ("cook_torrance", {"mode": "hdr"}),
    ("course", {"mode": "hdr"}),
]
SCENE_RUNGS = ("single", "directional", "walk")
WALKABLE = ("ggx", "beckmann")     # the D the walk and the directional lobe are for


def scene_xml(name: str, rung: str) -> tuple[str, int]:
    """The bundled scene ``name``'s XML with each ``cook_torrance`` of a GGX or
    Beckmann D given Smith's G and ``rung``'s options (the others, Blinn's D,
    as they are); and how many BSDFs were changed."""
    import xml.etree.ElementTree as ET
    from ... import scenes
    root = ET.parse(scenes.path(name)).getroot()
    options = {"geometry": "smith", **dict(RUNGS)[rung]}
    changed = 0
    for bsdf in root.iter("bsdf"):
        if bsdf.get("type") != "cook_torrance":
            continue
        named = {child.get("name"): child for child in bsdf}
        distribution = named["distribution"].get("value") if "distribution" in named else "beckmann"
        if distribution not in WALKABLE:
            continue
        for key, value in options.items():
            if key in named:
                bsdf.remove(named[key])
            tag = "boolean" if isinstance(value, bool) else "string"
            ET.SubElement(bsdf, tag, name=key, value=str(value).lower() if tag == "boolean"
                          else str(value))
        changed += 1
    return ET.tostring(root, encoding="unicode"), changed


def measure_scene(name: str, res: int | None, spp: int | None, repeats: int) -> list[dict]:
    """Each rung of :data:`SCENE_RUNGS` in the bundled scene ``name`` (at
    ``res`` pixels across and ``spp``, or the scene's own where None): rendered
    once to compile, then ``repeats`` times (seeds 1, 2, ...), the scene the
    only one alive. Per rung: the median render time; the noise, the
    expected relMSE of one render against its own expectation (the per-pixel
    variance over the renders, weighed by the walk's mean as relMSE weighs a
    render: (mean + 0.01)², the same weight for every rung); the light
    reflected to the camera (the image's sum) over the walk's; and the
    time, the noise and the time to the same noise (time × noise) over the
    directional lobe's."""
    defines = dict(SCENES)[name] | {k: str(v) for k, v in (("res", res), ("spp", spp))
                                    if v is not None}
    stacks, rows = {}, []
    for rung in SCENE_RUNGS:
        text, changed = scene_xml(name, rung)
        scene = mi.load_string(text, parallel=False, **defines)
        res = scene.sensors()[0].film().size()[0]
        spp = scene.sensors()[0].sampler().sample_count()
        images, seconds = timed_renders(scene, spp, repeats)
        del scene
        views.release()
        stacks[rung] = np.stack(images)
        rows.append({"scene": name, "rung": rung, "bsdfs": changed, "res": res, "spp": spp,
                     "median_s": statistics.median(seconds)})
    walk = stacks["walk"].mean(axis=0)
    weight = 1.0 / (walk + 0.01) ** 2
    for row in rows:
        stack = stacks[row["rung"]]
        row["noise_relmse"] = float(np.mean(stack.var(axis=0, ddof=1) * weight))
        row["light_vs_walk"] = float(stack.mean(axis=0).sum() / walk.sum())
    at = {row["rung"]: row for row in rows}
    for row in rows:
        row["time_vs_directional"] = row["median_s"] / at["directional"]["median_s"]
        row["noise_vs_directional"] = row["noise_relmse"] / at["directional"]["noise_relmse"]
        row["time_to_noise_vs_directional"] = row["time_vs_directional"] * row["noise_vs_directional"]
    return rows
