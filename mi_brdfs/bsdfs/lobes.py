"""The lobe algebra every plugin shares: lobe values, their sum, the mixture pdf.

A plugin has up to three lobes (:class:`Lobes`): a diffuse one, a glossy one
(the model's highlight, whatever the lecture calls it) and, with energy
compensation, the multiple-scattering lobe, which counts as the kind of the
lobe it belongs to. A lobe's value is most often a colour times a shape
(:class:`Scaled`): the colour is multiplied last, so that masks, weights and
guards act on one Float per lane instead of one per colour channel. In
scan-line mode each lobe is clamped per colour channel to [0, 1] before its
weight (:func:`weighted`). Sampling picks a lobe in proportion to an
estimate of its albedo (:class:`.mixture.Mixture`) and the pdf is the exact mixture of
the lobes' densities (:func:`mixed`).
"""
from __future__ import annotations

from typing import NamedTuple

import drjit as dr
import mitsuba as mi

PDF_FLOOR = 1e-37                 # 1/pdf stays finite in float32 (the weight's scaling)
WEIGHT_MAX = 1e12                 # sample weights above this are float32 failures (mixture.sample)
# "On the surface": a viewer or light with cos θ <= HORIZON gets no reflection.
# Above it every value is exact; below it the derivatives of near-mirror lobes
# (alpha 1e-4: d pdf/d alpha ~ 1/(2 pi alpha³ cos θ)) would exceed float32.
HORIZON = 1e-20


def as_type(x, kind: type):
    """``x`` as a ``kind`` (a Dr.Jit type): a direct call from Python may pass
    a list, a tuple or a number, as Mitsuba's own bindings accept them."""
    return x if type(x) is kind or isinstance(x, kind) else kind(x)


def mean(spectrum) -> mi.Float:
    """Channel mean of a spectrum: the scalar weight used for lobe selection."""
    return dr.sum(spectrum, axis=0) * (1.0 / dr.size_v(spectrum))


def clamp01(x):
    """The lecture's clamp() per colour channel; NaN-free (fmin drops NaN). At
    x = 0 (a black colour) the derivative is the one from above, 1: an
    optimiser starting from black can leave it."""
    return dr.fmin(dr.select(x >= 0.0, x, 0.0), 1.0)


class Scaled(NamedTuple):
    """A lobe's value as ``colour · shape``, what most lobes are: the colour (a
    spectrum) is multiplied last, so that the base's masks, weights and guards
    act on one Float per lane instead of one per colour channel.

    ``ratio``: shape / pdf of the lobe's own sampler, where it is known in
    closed form (Lambert's lobe under cosine sampling: 1, :func:`.lambert.f`);
    a sample of that lobe alone then weighs ``colour · ratio``, without the
    division and without the float32 guards that the division needs."""
    colour: object
    shape: object
    ratio: object = None


def product(value):
    """A lobe's value as a spectrum (a :class:`Scaled` multiplied out)."""
    return value.colour * value.shape if type(value) is Scaled else value


def one(x) -> bool:
    """True for the Python number 1 (a factor that needs no multiplication)."""
    return (type(x) is float or type(x) is int) and x == 1.0


def weighted(value, w, scanline: bool):
    """w times a lobe's value, clamped per channel to [0, 1] first in scanline
    mode (the lecture's clamp01(lobe)); a :class:`Scaled` value stays one in hdr mode."""
    if scanline:
        value = clamp01(product(value))
    elif type(value) is Scaled:
        if one(w):
            return value
        return Scaled(value.colour, w * value.shape,
                      None if value.ratio is None else w * value.ratio)
    return value if one(w) else w * value


def mixed(p, prob, density):
    """The mixture density p plus one lobe's density picked with probability prob
    (p None: the first lobe; prob the number 1: a lobe alone)."""
    term = density if one(prob) else prob * density
    return term if p is None else p + term


def total(values, mask):
    """The sum of lobe values, 0 where ``mask`` is off, as a spectrum: a
    :class:`Scaled` value is masked on its shape and multiplied by its colour last."""
    f = None
    for v in values:
        v = v.colour * dr.select(mask, v.shape, 0.0) if type(v) is Scaled \
            else dr.select(mask, v, 0.0)
        f = v if f is None else f + v
    return f if type(f) is mi.UnpolarizedSpectrum else mi.UnpolarizedSpectrum(f)


class Lobes(NamedTuple):
    """Which lobes a call evaluates (Python booleans: decided at trace time)."""
    diffuse: bool
    glossy: bool
    multiple: bool            # energy compensation's multiple-scattering lobe


class Plan(NamedTuple):
    """What every traced call of an instance reads, decided with its lobes
    (:meth:`.base.BRDF.update_lobes`) so that a call reads it once."""
    lobes: Lobes          # the lobes present
    scanline: bool        # mode == "scanline"
    cosine: bool          # sampling == "cosine": every lobe sampled from the cosine hemisphere
    uniform: bool         # the diffuse lobe sampled from the uniform hemisphere
    behind: bool          # lit_from_behind()


ALL = int(mi.BSDFFlags.All)       # a context's type mask that enables every lobe type
ANY = 2**32 - 1                   # its component (-1): every component
GLOSSY = int(mi.BSDFFlags.GlossyReflection)      # a sample's type
DIFFUSE = int(mi.BSDFFlags.DiffuseReflection)


def facing(si, active):
    """``active`` where the viewer is above the surface: a viewer below (or on)
    it gets no reflection."""
    up = si.wi.z > HORIZON
    return up if active is True else up & active
