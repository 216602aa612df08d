"""The renders of the plugin pages, made by the documentation build from each
model's ``cases().pictures`` (:class:`mi_brdfs.bsdfs.cases.Pictures`), in the
style of Mitsuba's own plugin pages (its "matpreview" scene): the material on
a unit sphere standing on a grey checkered floor, under an environment on a
neutral grey background, with a key light from the upper left.

Everything is made here, nothing is downloaded: the floor is Mitsuba's
procedural ``checkerboard`` texture on our ``lambert`` plugin, and the
environment a small latitude-longitude bitmap this module writes
(:func:`environment`): a neutral grey sky, lighter towards the zenith, a
darker ground below the horizon, and two soft white panels that give the
highlights a shape. In hdr mode it is path traced (Mitsuba's path tracer,
ACES tone mapping); in scan-line mode the scan-line integrator sums the key
light and the environment (one sample of it per pixel sample), each divided
by π (the lecture's scan-line Lambert term has no 1/π, so both modes show a
Lambert surface equally bright), and clamps to [0, 1]. Each render is kept
under a name made from everything it depends on (the plugin dictionary, the
scene's settings, the code and tables of the BSDFs and the renderer,
Mitsuba's version), so a rebuild renders only what changed.
"""
from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

RES = 256
SPP = {"scanline": 64, "hdr": 64}
TONEMAP = {"scanline": "clamp", "hdr": "aces"}      # mi_brdfs.render.tonemap operators
KEY_DIRECTION = [0.75, -0.6, -0.25]
KEY = {"scanline": 2.5 / math.pi, "hdr": 2.5}        # irradiance
ENV_SCALE = {"scanline": 1.0 / math.pi, "hdr": 1.0}  # the environment's radiance factor
ENV_SIZE = (64, 128)                                # the environment bitmap, rows × columns
FLOOR = {"color0": 0.2, "color1": 0.4, "squares": 16}   # reflectance, squares per side
LIGHTS = {"scanline": "the key light and the environment, each divided by π (the lecture's "
                      "scan-line Lambert term has no 1/π), summed by the scan-line "
                      "integrator, clamped to [0, 1]",
          "hdr": "the key light and the environment, path traced, ACES tone mapping"}
SCENE = ("a unit sphere on a grey checkered floor under a neutral grey environment with "
         "two soft white panels and a key light from the upper left (the scene is made "
         "by this site's build)")


@dataclass(frozen=True)
class Render:
    mode: str
    value: object       # the swept parameter's value
    path: Path          # the PNG
    label: str = ""     # what the render shows, when it is not one value of a sweep


def environment() -> np.ndarray:
    """The preview's environment, a latitude-longitude RGB image (radiance):
    grey, brighter towards the zenith (0.2 at the horizon to 0.45), the
    ground below the horizon 0.1, and two soft white panels of radiance 4
    up to the left and right of the camera, which the glossy renders
    reflect."""
    rows, cols = ENV_SIZE
    theta = (np.arange(rows) + 0.5) / rows * math.pi              # from the zenith
    phi = (np.arange(cols) + 0.5) / cols * 2.0 * math.pi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    up = np.cos(t)
    sky = np.where(up > 0, 0.2 + 0.25 * up, 0.1)
    image = np.repeat(sky[..., None], 3, axis=2)
    panels = ((0.6 * math.pi, 0.3 * math.pi), (1.4 * math.pi, 0.35 * math.pi))   # (φ, θ)
    for centre_phi, centre_theta in panels:
        d = ((p - centre_phi) / 0.35) ** 2 + ((t - centre_theta) / 0.2) ** 2
        image += 4.0 * np.exp(-d ** 4)[..., None]
    return image.astype(np.float32)


def scene(bsdf: dict, mode: str) -> dict:
    """The preview scene of one plugin configuration in one mode."""
    import mitsuba as mi
    camera = mi.ScalarTransform4f().look_at(origin=[0, 1.6, 5.2], target=[0, -0.15, 0],
                                            up=[0, 1, 0])
    n = FLOOR["squares"]
    squares = mi.ScalarTransform4f().scale([n / 2, n / 2, 1])     # of the floor's uv square
    return {
        "type": "scene",
        "integrator": {"type": "course", "mode": mode},
        "sensor": {"type": "perspective", "fov": 36, "to_world": camera,
                   "film": {"type": "hdrfilm", "width": RES, "height": RES,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": SPP[mode]}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "floor": {"type": "rectangle",
                  "to_world": mi.ScalarTransform4f().translate([0, -1, 0])
                  @ mi.ScalarTransform4f().rotate([1, 0, 0], -90)
                  @ mi.ScalarTransform4f().scale(8),
                  "bsdf": {"type": "lambert", "mode": mode,
                           "reflectance": {"type": "checkerboard",
                                           "color0": {"type": "rgb", "value": FLOOR["color0"]},
                                           "color1": {"type": "rgb", "value": FLOOR["color1"]},
                                           "to_uv": squares}}},
        "key": {"type": "directional", "direction": KEY_DIRECTION,
                "irradiance": {"type": "rgb", "value": KEY[mode]}},
        "sky": {"type": "envmap", "bitmap": mi.Bitmap(environment() * ENV_SCALE[mode])},
    }


@lru_cache(maxsize=None)
def _code() -> str:
    """A digest of what a render depends on in the package: the BSDFs (their
    code and tables) and the renderer."""
    import mi_brdfs
    package = Path(mi_brdfs.__file__).parent
    digest = hashlib.sha256()
    for path in sorted([*(package / "bsdfs").rglob("*"), *(package / "render").rglob("*.py")]):
        if path.is_file() and path.suffix in (".py", ".npz"):
            digest.update(path.read_bytes())
    return digest.hexdigest()


def _name(plugin: str, bsdf: dict, mode: str) -> str:
    import mitsuba as mi
    scene_code = hashlib.sha256(Path(__file__).read_bytes()).hexdigest()   # this module
    key = json.dumps([bsdf, mode, scene_code, _code(), mi.__version__],
                     sort_keys=True, default=str)
    return f"{plugin}-{mode}-{hashlib.sha256(key.encode()).hexdigest()[:16]}.png"


def render(plugin: str, bsdf: dict, mode: str, folder: Path) -> Path:
    """The PNG of one configuration in one mode, rendered if not in ``folder`` already."""
    import mitsuba as mi

    from mi_brdfs.render.tonemap import write_png
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / _name(plugin, bsdf, mode)
    if not path.exists():
        image = mi.render(mi.load_dict(scene(bsdf, mode)), seed=0)
        write_png(str(path), image, TONEMAP[mode])
    return path


def renders(cls, folder: Path, pictures) -> list[Render]:
    """The renders of one sweep of a plugin's page (both modes, every value of
    the :class:`Pictures`' parameter)."""
    made = []
    for mode in ("scanline", "hdr"):
        for value in pictures.values:
            bsdf = {"type": cls.name, **pictures.config, pictures.parameter: value, "mode": mode}
            made.append(Render(mode, value, render(cls.name, bsdf, mode, folder)))
    return made


# ----------------------------------------------------------------------------
#  Gold under three Fresnel forms (the cook_torrance page)
# ----------------------------------------------------------------------------

GOLD_ROUGHNESS = {"distribution": "ggx", "geometry": "smith", "alpha": 0.15, "k": 0.0}


@dataclass(frozen=True)
class Gold:
    """Gold's exact reflectance (Mitsuba's ``Au`` data, RGB) at normal
    incidence and at F82-tint's angle, and the parameters of the lecture's
    forms made from them."""
    normal: tuple       # F(0°), the exact conductor Fresnel, per channel
    f82: tuple          # F(θ̄), θ̄ = acos(1/7) ≈ 81.8°, per channel
    f0: float           # Schlick's one number: the largest channel of F(0°)
    colour: tuple       # m_S = F(0°)/f0: Schlick and F82 give F(0°) at normal incidence
    tint: tuple         # f82_tint = F(θ̄)/(m_S F_Schlick(f0, θ̄)), held at 1 where above
    raised: tuple       # the channels whose tint was above 1 (F82 only lowers Schlick)


def gold() -> Gold:
    """Gold's parameters for the lecture's forms, from the exact conductor
    Fresnel (:func:`mi_brdfs.bsdfs.fresnel.conductor`) of η + iκ, the colour
    ``roughconductor`` makes of Mitsuba's ``Au`` data. ``f0`` is one number
    in ``cook_torrance`` (the colour comes from ``specular_reflectance``), so
    as a user would: f0 the largest channel of F(0°), m_S the rest, so that
    m_S·f0 = F(0°); then F82-tint's tint makes m_S·F82 = F(θ̄) at c̄ = 1/7
    (Hoffman 2023), where it can (≤ 1)."""
    import drjit as dr
    import mitsuba as mi

    from mi_brdfs.bsdfs import fresnel
    from mi_brdfs.bsdfs.cook_torrance import material_textures
    si = dr.zeros(mi.SurfaceInteraction3f)
    eta, kappa = (mi.Color3f(np.array(t.eval(si)).ravel()) for t in material_textures("Au"))

    def exact(c: float) -> np.ndarray:
        return np.array(fresnel.conductor(eta, kappa, mi.Float(c)), dtype=np.float64).ravel()
    normal, grazing = exact(1.0), exact(fresnel.F82_COS)
    f0 = float(normal.max())
    colour = normal / f0
    schlick = f0 + (1.0 - f0) * (1.0 - fresnel.F82_COS) ** 5
    tint = grazing / (colour * schlick)
    floats = lambda v: tuple(float(x) for x in v)           # noqa: E731
    return Gold(floats(normal), floats(grazing), f0, floats(colour),
                floats(np.minimum(tint, 1.0)), tuple(bool(t > 1.0) for t in tint))


def gold_configs(g: Gold) -> list[tuple[str, dict]]:
    """(label, cook_torrance dictionary) of the gold renders, the lecture's form first."""
    def rgb(v) -> dict:
        return {"type": "rgb", "value": [round(float(x), 4) for x in v]}
    return [("schlick", {**GOLD_ROUGHNESS, "fresnel": "schlick", "f0": round(g.f0, 4),
                         "specular_reflectance": rgb(g.colour)}),
            ("f82", {**GOLD_ROUGHNESS, "fresnel": "f82", "f0": round(g.f0, 4),
                     "specular_reflectance": rgb(g.colour), "f82_tint": rgb(g.tint)}),
            ("conductor", {**GOLD_ROUGHNESS, "fresnel": "conductor", "material": "Au"})]


def gold_renders(folder: Path, mode: str = "hdr") -> list[Render]:
    """Gold under the three Fresnel forms of :func:`gold_configs`, hdr mode."""
    return [Render(mode, label, render("cook_torrance", {"type": "cook_torrance", **config,
                                                        "mode": mode}, mode, folder), label)
            for label, config in gold_configs(gold())]
