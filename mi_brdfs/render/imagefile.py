"""Writing a render to the file its extension names.

==============  ==============================================================
extension       what is written
==============  ==============================================================
``.exr``        every film channel (RGB and AOVs such as an ``aov``
                integrator's depth or normals) as float32, with metadata
                (scene file, the spp and passes rendered, seed, variant,
                versions)
``.png``        the RGB channels tone-mapped (:mod:`.tonemap`) to 8-bit sRGB
``.jpg/.jpeg``  the same, as JPEG
==============  ==============================================================

Any other extension is refused (:func:`check_extension`) before rendering.
PNG and JPEG go through Mitsuba's ``mi.Bitmap``; EXR through OpenEXR's own
writer (:func:`.exr.write_channels`), because ``mi.Bitmap``'s EXR writer
deadlocks when Dr.Jit runs a single thread (``-t 1``; Mitsuba 3.9, measured).
Every file is written atomically (:func:`.exr.write_atomically`).
"""
from __future__ import annotations

import os
from typing import Mapping, Sequence

import numpy as np

import mitsuba as mi

from . import tonemap
from .exr import write_atomically, write_channels

FORMATS = {".exr": "OpenEXR", ".png": "PNG", ".jpg": "JPEG", ".jpeg": "JPEG"}


def check_extension(path: str) -> str:
    """The format of ``path`` by its extension; ValueError for an unknown one."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in FORMATS:
        raise ValueError(f"-o {path}: unknown extension {ext or '(none)'!r}; "
                         f"valid: {', '.join(FORMATS)}")
    return FORMATS[ext]


def channel_names(film_names: Sequence[str], count: int) -> list[str]:
    """Names of the ``count`` channels ``mi.render`` returned, from the film's
    channels (``film.bitmap()`` after rendering).

    Usually they are the same list. Mitsuba's ``aov`` integrator differs: its
    film holds R, G, B(, A) (Y in mono variants), then each nested
    integrator's ``NAME.R/G/B/A``, then the AOVs, but ``mi.render`` returns
    each nested integrator's image in the film's base channels (R, G, B(, A)
    or Y) followed by the AOVs. The first nested image is the render itself
    and is named as the base channels; the others keep ``NAME.``. Any other
    mismatch gives generic names ``C0, C1, ...``."""
    names = list(film_names)
    if len(names) == count:
        return names
    base = [n for n in names[:4] if n in ("R", "G", "B", "A", "Y")]
    rest, groups = names[len(base):], []
    while len(rest) >= 4 and rest[0].endswith(".R"):
        prefix = rest[0][:-2]
        if rest[:4] != [prefix + c for c in (".R", ".G", ".B", ".A")]:
            break
        groups.append(prefix)
        rest = rest[4:]
    out = []
    for i, prefix in enumerate(groups):
        out += [c if i == 0 else f"{prefix}.{c}" for c in base]
    out += rest
    return out if len(out) == count else [f"C{i}" for i in range(count)]


def rgb_of(image: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """The (H, W, 3) colour of a multi-channel image: its R, G, B channels, or
    its luminance Y repeated (mono variants). ValueError if it has neither."""
    names = list(names)
    if all(c in names for c in "RGB"):
        return np.stack([image[..., names.index(c)] for c in "RGB"], axis=-1)
    if "Y" in names:
        return np.repeat(image[..., names.index("Y")][..., None], 3, axis=-1)
    raise ValueError(f"the render has no R, G, B channels to tone-map "
                     f"(channels: {', '.join(names)}); write it as .exr")


def write(path: str, image: np.ndarray, names: Sequence[str],
          metadata: Mapping[str, object] | None = None,
          operator: str = "clamp", exposure: float = 0.0) -> None:
    """Write an (H, W, C) render with channel ``names`` to ``path`` by its extension."""
    image = np.asarray(image, dtype=np.float32)
    if check_extension(path) == "OpenEXR":
        # OpenEXR's own writer: mi.Bitmap's EXR writer deadlocks with one
        # Dr.Jit thread (-t 1) in Mitsuba 3.9.
        write_channels(path, {name: image[..., i] for i, name in enumerate(names)}, metadata)
        return
    data = tonemap.to_srgb8(rgb_of(image, names), operator, exposure)
    bitmap = mi.Bitmap(np.ascontiguousarray(data), mi.Bitmap.PixelFormat.RGB)
    write_atomically(path, lambda tmp: bitmap.write(tmp))
