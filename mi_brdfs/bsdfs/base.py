"""What every mi_brdfs plugin does alike.

- reading and validating parameters (colours and scalars as Mitsuba textures,
  scalars as opaque differentiable Floats, string choices), with load-time errors
  that name the plugin, the parameter, the value and the valid range;
- the ``mode`` switch: ``"scanline"`` clamps each lobe per colour channel to
  [0, 1] (the lecture's scan-line BRDFs), ``"hdr"`` keeps them unclamped;
- the lobes: a diffuse lobe (cosine- or uniform-hemisphere sampling) and/or a glossy lobe
  (the model's own sampler), declared in ``m_flags`` only when present, picked
  in proportion to an estimate of their weight, with the mixture pdf;
- registration for the active variant (through :func:`mi_brdfs._binding.bind`).

A model subclasses :class:`BRDF` and supplies ``read(props)``,
``lobes(si, wo, active) -> (f_diffuse, f_specular)`` (eval convention, i.e.
including the lecture's clamp(d·n) in scanline mode and cos θ_o in hdr mode,
before the per-lobe clamp; lanes with wi or wo below the surface are zeroed
by the base, unless ``lit_from_behind()``), ``lobe_weights()`` (the constant factors that
multiply each clamped lobe, e.g. k and 1-k), ``selection_weights(si, active)``,
and, if it has a glossy lobe, ``sample_specular`` / ``pdf_specular``.
"""
from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from .._binding import bind

MODES = ("scanline", "hdr")
SAMPLINGS = ("lobe", "cosine")    # each lobe's own importance sampling, or cosine for all


class ParameterError(ValueError):
    """A plugin parameter has a bad value (raised at load time)."""


# ----------------------------------------------------------------------------
#  Parameter reading and validation
# ----------------------------------------------------------------------------

def _fmt_range(lo: float | None, hi: float | None) -> str:
    return f"[{'-inf' if lo is None else f'{lo:g}'}, {'inf' if hi is None else f'{hi:g}'}]"


def texture_range(tex) -> tuple[float, float] | None:
    """(min, max) of every numeric parameter of a texture, or None if it has none."""
    values = []
    for _, value in mi.traverse(tex).items():
        try:
            values.append(np.asarray(value, dtype=np.float64).ravel())
        except (TypeError, ValueError):
            continue
    if not values:
        return None
    allv = np.concatenate(values)
    return float(allv.min()), float(allv.max())


class Reader:
    """Reads one plugin's properties and raises ParameterError on bad values."""

    def __init__(self, plugin: str, props: mi.Properties):
        self.plugin, self.props = plugin, props

    def error(self, name: str, value, valid: str) -> ParameterError:
        return ParameterError(
            f"{self.plugin}: parameter '{name}' = {value!r} is invalid; valid: {valid}")

    def check(self, name: str, value, lo: float | None, hi: float | None) -> None:
        lo_ok = lo is None or value >= lo
        hi_ok = hi is None or value <= hi
        if not (lo_ok and hi_ok) or (isinstance(value, float) and math.isnan(value)):
            raise self.error(name, value, _fmt_range(lo, hi))

    def texture(self, name: str, default: float, lo: float | None = 0.0,
                hi: float | None = None):
        """A colour or scalar: float, rgb or any Mitsuba texture.

        Colours above 1 are accepted (``srgb`` with ``unbounded``), so the
        scanline mode's clamp is what limits them, as in the lecture.
        """
        props = self.props
        if name not in props:
            self.check(name, default, lo, hi)
            return mi.load_dict({"type": "uniform", "value": default})
        value = props[name]
        if isinstance(value, (int, float)):
            self.check(name, float(value), lo, hi)
            return mi.load_dict({"type": "uniform", "value": float(value)})
        if not isinstance(value, mi.Object):      # an rgb colour
            rgb = [float(c) for c in value]
            for c in rgb:
                self.check(name, c, lo, hi)
            return mi.load_dict({"type": "srgb", "color": rgb, "unbounded": True})
        tex = props.get_texture(name)            # a nested texture
        # Its parameters are its values in RGB and mono variants; spectral
        # variants store spectral-upsampling coefficients instead (unchecked).
        rng = None if mi.is_spectral else texture_range(tex)
        if rng is not None:
            self.check(name, rng[0], lo, hi)
            self.check(name, rng[1], lo, hi)
        return tex

    def scalar(self, name: str, default: float, lo: float | None, hi: float | None):
        """A plain scalar, stored as an opaque (differentiable, non-baked) Float."""
        value = float(self.props.get(name, default))
        self.check(name, value, lo, hi)
        return dr.opaque(mi.Float, value)

    def choice(self, name: str, default: str, options: tuple[str, ...]) -> str:
        value = str(self.props.get(name, default))
        if value not in options:
            raise self.error(name, value, "one of " + ", ".join(f'"{o}"' for o in options))
        return value


def is_zero(tex) -> bool:
    """True for a texture that is a constant 0 everywhere (its lobe can be dropped)."""
    rng = texture_range(tex)
    return (rng is not None and rng == (0.0, 0.0)
            and not tex.is_spatially_varying())


def mean(spectrum) -> mi.Float:
    """Channel mean of a spectrum: the scalar weight used for lobe selection."""
    return dr.mean(spectrum, axis=0)


def clamp01(x):
    """The lecture's clamp() per colour channel; NaN-free (fmin/fmax drop NaN)."""
    return dr.fmin(dr.fmax(x, 0.0), 1.0)


# ----------------------------------------------------------------------------
#  The shared BSDF logic
# ----------------------------------------------------------------------------

class BRDF:
    """Base of every mi_brdfs plugin (plain Python; bound to mi.BSDF by bind())."""

    name = "brdf"                     # the registered plugin name

    def __init__(self, props: mi.Properties):
        mi.BSDF.__init__(self, props)
        reader = Reader(self.name, props)
        self.mode = reader.choice("mode", "hdr", MODES)
        # "cosine" samples every lobe from the cosine hemisphere: for measuring
        # what importance sampling gains (mi-brdfs bench), not for rendering.
        self.sampling = reader.choice("sampling", "lobe", SAMPLINGS)
        self.read(reader)
        self.update_lobes()

    # --- what a model provides -------------------------------------------------
    def read(self, reader: Reader) -> None:
        raise NotImplementedError

    def has_diffuse(self) -> bool:
        return False

    def has_specular(self) -> bool:
        return False

    def diffuse_sampling(self) -> str:
        """How the diffuse lobe is sampled: "cosine" (for lobes carrying a
        cos theta_o, the Lambert-like ones) or "uniform" (for a lobe that is
        constant over the hemisphere, like toon's, where cosine sampling would
        give weights 1/cos theta_o of infinite variance)."""
        return "cosine"

    def sample_diffuse(self, sample2):
        if self.diffuse_sampling() == "uniform":
            return mi.warp.square_to_uniform_hemisphere(sample2)
        return mi.warp.square_to_cosine_hemisphere(sample2)

    def pdf_diffuse(self, wo):
        if self.diffuse_sampling() == "uniform":
            return mi.warp.square_to_uniform_hemisphere_pdf(wo)
        return mi.warp.square_to_cosine_hemisphere_pdf(wo)

    def lit_from_behind(self) -> bool:
        """True if eval() must see lights below the surface (cos_o <= 0), e.g.
        the toon model's dark side; lobes() then zeroes what must be zero."""
        return False

    def lobe_weights(self):
        return 1.0, 1.0

    def selection_weights(self, si, active):
        return mi.Float(1.0), mi.Float(1.0)

    def sample_specular(self, si, sample2, active):
        raise NotImplementedError

    def pdf_specular(self, si, wo, active):
        raise NotImplementedError

    # --- flags -----------------------------------------------------------------
    def update_lobes(self) -> None:
        """Declare exactly the lobes present: an absent lobe is never traced."""
        self.diffuse, self.specular = self.has_diffuse(), self.has_specular()
        components = []
        if self.diffuse:
            components.append(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
        if self.specular:
            components.append(mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide)
        self.diffuse_index = 0
        self.specular_index = len(components) - 1
        flags = mi.BSDFFlags.Empty
        for c in components:
            flags |= c
        self.m_components = components
        self.m_flags = flags

    def parameters_changed(self, keys=[]):
        self.update_lobes()

    def enabled(self, ctx):
        """(diffuse, specular) lobes that exist and that ctx asks for."""
        d = self.diffuse and ctx.is_enabled(mi.BSDFFlags.DiffuseReflection,
                                            self.diffuse_index)
        s = self.specular and ctx.is_enabled(mi.BSDFFlags.GlossyReflection,
                                             self.specular_index)
        return d, s

    def specular_probability(self, si, use_d, use_s, active):
        """Probability of sampling the glossy lobe: proportional to its weight."""
        if not use_s:
            return mi.Float(0.0)
        if not use_d:
            return mi.Float(1.0)
        wd, ws = self.selection_weights(si, active)
        total = wd + ws
        return dr.select(total > 0, ws / dr.select(total > 0, total, 1.0), 0.5)

    # --- the BSDF interface --------------------------------------------------
    def sample(self, ctx, si, sample1, sample2, active=True):
        use_d, use_s = self.enabled(ctx)
        bs = dr.zeros(mi.BSDFSample3f)
        cos_i = mi.Frame3f.cos_theta(si.wi)
        active = mi.Bool(active) & (cos_i > 0)
        if not (use_d or use_s):
            return bs, mi.Spectrum(0.0)

        p_s = self.specular_probability(si, use_d, use_s, active)
        pick_s = mi.Bool(sample1 < p_s)
        if self.sampling == "cosine":
            wo = mi.warp.square_to_cosine_hemisphere(sample2)
        elif use_d and use_s:
            wo = dr.select(pick_s,
                           self.sample_specular(si, sample2, active & pick_s),
                           self.sample_diffuse(sample2))
        elif use_s:
            wo = self.sample_specular(si, sample2, active)
        else:
            wo = self.sample_diffuse(sample2)

        value, pdf = self.eval_pdf(ctx, si, wo, active)
        active &= (pdf > 0) & (mi.Frame3f.cos_theta(wo) > 0)
        diffuse_t = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
        glossy_t = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
        bs.wo = dr.select(active, wo, 0.0)      # no NaN from inactive lanes either
        bs.pdf = dr.select(active, pdf, 0.0)
        bs.eta = 1.0
        bs.sampled_type = dr.select(pick_s, glossy_t, diffuse_t)
        bs.sampled_component = dr.select(pick_s, mi.UInt32(self.specular_index),
                                         mi.UInt32(self.diffuse_index))
        weight = value / dr.select(active, pdf, 1.0)
        return bs, dr.select(active, weight, 0.0)

    def eval(self, ctx, si, wo, active=True):
        use_d, use_s = self.enabled(ctx)
        cos_i = mi.Frame3f.cos_theta(si.wi)
        cos_o = mi.Frame3f.cos_theta(wo)
        # A viewer or light below (or exactly on) the surface gets no reflection.
        active = mi.Bool(active) & (cos_i > 0)
        if not self.lit_from_behind():
            active &= cos_o > 0
        f_d, f_s = self.lobes(si, wo, active)
        w_d, w_s = self.lobe_weights()
        if self.mode == "scanline":
            f_d, f_s = clamp01(f_d), clamp01(f_s)
        value = mi.Spectrum(0.0)
        if use_d:
            value += w_d * f_d
        if use_s:
            value += w_s * f_s
        return dr.select(active, value, 0.0)

    def pdf(self, ctx, si, wo, active=True):
        use_d, use_s = self.enabled(ctx)
        cos_i = mi.Frame3f.cos_theta(si.wi)
        cos_o = mi.Frame3f.cos_theta(wo)
        active = mi.Bool(active) & (cos_i > 0) & (cos_o > 0)
        if self.sampling == "cosine":
            return dr.select(active, mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)
        p_s = self.specular_probability(si, use_d, use_s, active)
        pdf = mi.Float(0.0)
        if use_d:
            pdf += (1.0 - p_s) * self.pdf_diffuse(wo)
        if use_s:
            pdf += p_s * self.pdf_specular(si, wo, active)
        return dr.select(active, pdf, 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def to_string(self):
        fields = ", ".join(f"{k}={v}" for k, v in self.describe().items())
        return f"{type(self).__name__}[mode={self.mode}, {fields}]"

    def describe(self) -> dict:
        return {}


# ----------------------------------------------------------------------------
#  Registration
# ----------------------------------------------------------------------------

def register_plugin(cls: type) -> None:
    """Register ``cls`` under ``cls.name`` for the active variant."""
    bound = bind(cls)
    mi.register_bsdf(cls.name, lambda props: bound(props))
