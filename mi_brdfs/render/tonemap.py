"""Tone mapping g(): linear HDR radiance -> display values in [0, 1] -> 8-bit sRGB.

Every operator first scales by the exposure, x = 2^EV · L, maps x to [0, 1]
per colour channel, and the result is encoded with the sRGB transfer function
and quantised to 8 bits. NaN and negative inputs give 0, +Inf gives 1.

=========  ==========================================================  ===========
name       g(x)                                                        reference
=========  ==========================================================  ===========
clamp      min(max(x, 0), 1) — the scan-line behaviour                 the lecture
gamma      the same clamp, meant with an exposure (``--exposure``)     sRGB display
reinhard   x / (1 + x)                                                 Reinhard et al. 2002
aces       x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), clamped       Narkowicz 2015 (ACES fit)
=========  ==========================================================  ===========

(Narkowicz's own code pre-scales by 0.6; here that is ``exposure = log2(0.6)``.)
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

import mitsuba as mi

from .exr import write_atomically


def _clean(x: ArrayLike) -> np.ndarray:
    """NaN and negative values -> 0; +Inf stays (each operator maps it to 1)."""
    x = np.nan_to_num(np.asarray(x, dtype=np.float64), nan=0.0, posinf=np.inf, neginf=0.0)
    return np.maximum(x, 0.0)


def clamp(x: ArrayLike) -> np.ndarray:
    return np.clip(_clean(x), 0.0, 1.0)


def reinhard(x: ArrayLike) -> np.ndarray:
    x = _clean(x)
    with np.errstate(invalid="ignore"):
        y = x / (1.0 + x)
    return np.where(np.isinf(x), 1.0, y)


def aces(x: ArrayLike) -> np.ndarray:
    x = _clean(x)
    with np.errstate(invalid="ignore", over="ignore"):
        y = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)
    return np.clip(np.where(np.isinf(x), 1.0, y), 0.0, 1.0)


OPERATORS = {"clamp": clamp, "gamma": clamp, "reinhard": reinhard, "aces": aces}


def srgb_encode(v: ArrayLike) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) on values in [0, 1]."""
    v = np.clip(v, 0.0, 1.0)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1 / 2.4) - 0.055)


def tonemap(rgb: ArrayLike, operator: str = "clamp", exposure: float = 0.0) -> np.ndarray:
    """Linear RGB -> display-linear values in [0, 1] (before sRGB encoding)."""
    if operator not in OPERATORS:
        raise ValueError(f"unknown tone-mapping operator {operator!r}; "
                         f"valid: {', '.join(OPERATORS)}")
    x = _clean(rgb) * (2.0 ** exposure)
    return OPERATORS[operator](x)


def to_srgb8(rgb: ArrayLike, operator: str = "clamp", exposure: float = 0.0) -> np.ndarray:
    """Linear RGB -> 8-bit sRGB (uint8), through tonemap() and srgb_encode()."""
    encoded = srgb_encode(tonemap(rgb, operator, exposure))
    return np.round(encoded * 255.0).astype(np.uint8)


def write_png(path: str, rgb: ArrayLike, operator: str = "clamp", exposure: float = 0.0) -> None:
    """Tone-map a linear RGB image and write it as an 8-bit sRGB PNG, atomically."""
    data = to_srgb8(rgb, operator, exposure)
    bitmap = mi.Bitmap(data, mi.Bitmap.PixelFormat.RGB)
    write_atomically(path, lambda tmp: bitmap.write(tmp))
