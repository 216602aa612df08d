"""The renders of the plugin pages, made by the documentation build from each
model's ``cases().pictures`` (:class:`mi_brdfs.bsdfs.cases.Pictures`).

A unit sphere seen from the front against a black background, lit by a key
light from the upper left: in scan-line mode with a dim fill light from the
right (the scan-line integrator sums point and directional lights exactly),
in hdr mode with a uniform grey environment (Mitsuba's path tracer). The hdr
key light is π times brighter: the lecture's scan-line Lambert term has no
1/π, so both modes show a Lambert surface equally bright. Small and cheap:
128² pixels, 16 (scan-line) or 128 (hdr) samples per pixel. Each render is
kept under a name made from everything it depends on (the plugin dictionary,
the scene's settings, the code and tables of the BSDFs and the renderer,
Mitsuba's version), so a rebuild renders only what changed.
"""
from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

RES = 128
SPP = {"scanline": 16, "hdr": 128}
TONEMAP = {"scanline": "clamp", "hdr": "aces"}      # mi_brdfs.render.tonemap operators
KEY_DIRECTION = [0.55, -0.5, -0.65]
KEY = {"scanline": 0.8, "hdr": 0.8 * math.pi}        # irradiance
FILL = {"type": "directional", "direction": [-0.8, 0.1, -0.6],
        "irradiance": {"type": "rgb", "value": 0.2}}
SKY = {"type": "constant", "radiance": {"type": "rgb", "value": 0.2}}
LIGHTS = {"scanline": "a key light from the upper left and a dim fill light from the right, "
                      "summed by the scan-line integrator, clamped to [0, 1]",
          "hdr": "the key light π times brighter (the hdr Lambert term has the 1/π the "
                 "lecture's lacks) and a uniform grey environment, path traced, ACES tone "
                 "mapping"}


@dataclass(frozen=True)
class Render:
    mode: str
    value: object       # the swept parameter's value
    path: Path          # the PNG


def scene(bsdf: dict, mode: str) -> dict:
    """The preview scene of one plugin configuration in one mode."""
    import mitsuba as mi
    camera = mi.ScalarTransform4f().look_at(origin=[0, 0, 4.4], target=[0, 0, 0], up=[0, 1, 0])
    return {
        "type": "scene",
        "integrator": {"type": "course", "mode": mode, "hide_emitters": True},
        "sensor": {"type": "perspective", "fov": 30, "to_world": camera,
                   "film": {"type": "hdrfilm", "width": RES, "height": RES,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": SPP[mode]}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "key": {"type": "directional", "direction": KEY_DIRECTION,
                "irradiance": {"type": "rgb", "value": KEY[mode]}},
        **({"fill": FILL} if mode == "scanline" else {"sky": SKY}),
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
    key = json.dumps([bsdf, mode, RES, SPP, TONEMAP, KEY_DIRECTION, KEY, FILL, SKY, _code(),
                      mi.__version__],
                     sort_keys=True, default=str)
    return f"{plugin}-{mode}-{hashlib.sha256(key.encode()).hexdigest()[:16]}.png"


def renders(cls, folder: Path, pictures) -> list[Render]:
    """The renders of one sweep of a plugin's page (both modes, every value of
    the :class:`Pictures`' parameter), made if not in ``folder`` already."""
    import mitsuba as mi

    from mi_brdfs.render.tonemap import write_png
    folder.mkdir(parents=True, exist_ok=True)
    made = []
    for mode in ("scanline", "hdr"):
        for value in pictures.values:
            bsdf = {"type": cls.name, **pictures.config, pictures.parameter: value, "mode": mode}
            path = folder / _name(cls.name, bsdf, mode)
            if not path.exists():
                image = mi.render(mi.load_dict(scene(bsdf, mode)), seed=0)
                write_png(str(path), image, TONEMAP[mode])
            made.append(Render(mode, value, path))
    return made
