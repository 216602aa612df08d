"""The BSDF interface over a plugin's lobes, written once: every step Dr.Jit
traces of ``sample``, ``eval``, ``pdf`` and ``eval_pdf``, and the hooks a model
implements for them, documented on their defaults.

A plugin has up to three lobes (:class:`Lobes`): a diffuse one, a specular
one (the model's highlight: Mitsuba's glossy reflection) and, with energy
compensation, the multiple-scattering lobe (:mod:`.compensation`), which
counts as the kind of the lobe it belongs to. :class:`Mixture`, the parent of
:class:`.base.BRDF`, reads what the base decided at load time
(``self.state``: the lobes present and the :class:`Plan` of a call, the
compensation) and combines the lobes:

- each used lobe is picked in proportion to an estimate of its albedo
  (``selection_weights``; the multiple-scattering lobe by its colour times
  g(ω_i)), and ``pdf`` is the exact mixture of the lobes' samplers;
- a single lobe is sampled by its own sampler with nothing to pick; its
  weight is the closed form the model gives (:attr:`Scaled.ratio`) or eval / pdf;
- a lobe's value stays colour · shape (:class:`Scaled`) until the end, so
  that masks, weights and guards act on one Float per lane instead of one per
  colour channel; in scan-line mode each lobe is clamped per colour channel to
  [0, 1] before its weight (:func:`weighted`);
- a viewer below (or on) the surface gets no reflection; a sampled direction
  is a fixed point for the derivatives (as Mitsuba's differentiable
  integrators treat it).

**Traced**: everything here runs inside ``sample``/``eval``/``pdf``/
``eval_pdf``, which Dr.Jit traces symbolically: Dr.Jit arithmetic only (no
``dr.any``, no printing, no NumPy), masks with ``dr.select``; Python-side
decisions read only what was fixed at load time (options, the lobes present,
``self.switch``). Local directions throughout: ``si.wi`` the viewer, ``wo``
the light, n = +z (the shading frame; x = s, y = t).
"""
from __future__ import annotations

from typing import Any, NamedTuple

import drjit as dr
import mitsuba as mi


PDF_FLOOR = 1e-37                 # 1/pdf stays finite in float32 (the weight's scaling)
WEIGHT_MAX = 1e12                 # sample weights above this are float32 failures (sample)
# "On the surface": a viewer or light with cos θ <= HORIZON gets no reflection.
# Above it every value is exact; below it the derivatives of near-mirror lobes
# (alpha 1e-4: d pdf/d alpha ~ 1/(2 pi alpha³ cos θ)) would exceed float32.
HORIZON = 1e-20

ALL = int(mi.BSDFFlags.All)       # a context's type mask that enables every lobe type
ANY = 2**32 - 1                   # its component (-1): every component
GLOSSY = int(mi.BSDFFlags.GlossyReflection)      # a specular sample's type
DIFFUSE = int(mi.BSDFFlags.DiffuseReflection)

Spectrum = Any           # an mi.UnpolarizedSpectrum (per colour channel)
Float = Any              # an mi.Float (one value per lane)


# ----------------------------------------------------------------------------
#  What a call reads: the lobes and the plan
# ----------------------------------------------------------------------------

class Lobes(NamedTuple):
    """Which lobes a call evaluates (Python booleans: decided at trace time)."""
    diffuse: bool
    specular: bool
    multiple: bool            # energy compensation's multiple-scattering lobe


class Plan(NamedTuple):
    """What every traced call of an instance reads, decided with its lobes
    (:meth:`.base.BRDF.update_lobes`) so that a call reads it once."""
    lobes: Lobes          # the lobes present
    scanline: bool        # mode == "scanline"
    cosine: bool          # sampling == "cosine": every lobe sampled from the cosine hemisphere
    uniform: bool         # the diffuse lobe sampled from the uniform hemisphere
    behind: bool          # lit_from_behind()


# ----------------------------------------------------------------------------
#  Lobe values
# ----------------------------------------------------------------------------

class Scaled(NamedTuple):
    """A lobe's value as ``colour · shape``, what most lobes are: the colour (a
    spectrum) is multiplied last, so that masks, weights and guards act on one
    Float per lane instead of one per colour channel.

    ``ratio``: shape / pdf of the lobe's own sampler, where it is known in
    closed form (Lambert's lobe under cosine sampling: 1, :func:`.lambert.eval_diffuse`);
    a sample of that lobe alone then weighs ``colour · ratio``, without the
    division and without the float32 guards that the division needs."""
    colour: object
    shape: object
    ratio: object = None


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


def facing(si, active):
    """``active`` where the viewer is above the surface: a viewer below (or on)
    it gets no reflection."""
    up = si.wi.z > HORIZON
    return up if active is True else up & active


def spectrum(value):
    """What eval/sample return: the value itself, or a depolarizing Mueller
    matrix in polarized variants (as Mitsuba's ``diffuse`` does)."""
    return mi.depolarizer(value) if mi.is_polarized else value


class Mixture:
    """sample / eval / pdf / eval_pdf over the lobes a :class:`.base.BRDF`
    declares, and the traced hooks a model implements (their defaults here)."""

    # --- the model's traced hooks -------------------------------------------------
    def eval_textures(self, si, active) -> Any:
        """Every texture the lobes need, evaluated once per call at ``si``: the
        model's own ``Inputs`` (a NamedTuple declared in its module), which
        every other hook receives as ``inp``. Default: nothing."""
        return ()

    def eval_diffuse(self, inp, si, wo) -> Spectrum | Scaled:
        """The diffuse lobe in eval convention (f·cos θ_o in hdr mode, the
        lecture's clamp(d·n) factor in scan-line mode), before the per-lobe
        clamp: a spectrum, or a colour times a shape (:class:`Scaled`). A model
        with a diffuse lobe implements it."""
        raise NotImplementedError(f"{type(self).__name__} has no eval_diffuse")

    def eval_specular(self, inp, si, wo) -> Spectrum | Scaled:
        """The specular lobe, likewise. A model with a specular lobe implements
        it, with :meth:`sample_specular` and :meth:`pdf_specular`."""
        raise NotImplementedError(f"{type(self).__name__} has no eval_specular")

    def sample_specular(self, inp, si, sample2) -> Any:
        """A light direction from the specular lobe's own sampler."""
        raise NotImplementedError(f"{type(self).__name__} has no sample_specular")

    def pdf_specular(self, inp, si, wo) -> Float:
        """The density of :meth:`sample_specular` at ``wo``."""
        raise NotImplementedError(f"{type(self).__name__} has no pdf_specular")

    def eval_pdf_specular(self, inp, si, wo) -> tuple[Spectrum | Scaled, Float]:
        """Both at once. Default: the two hooks (Dr.Jit merges the operations
        they share into one kernel; a model overrides it only where tracing
        them once pays, as the bench's tracing group measures)."""
        return self.eval_specular(inp, si, wo), self.pdf_specular(inp, si, wo)

    def lobe_weights(self, inp) -> tuple[Any, Any]:
        """The factors multiplying the (clamped) diffuse and specular lobes,
        e.g. Cook-Torrance's k and 1 - k; Python numbers where constant.
        Default (1, 1)."""
        return 1.0, 1.0

    def selection_weights(self, inp, si) -> tuple[Float, Float]:
        """Estimates of each lobe's albedo (weights included): a sample picks a
        lobe in proportion. Default (1, 1)."""
        return mi.Float(1.0), mi.Float(1.0)

    # --- what a call needs, once -------------------------------------------------
    def colour(self, name: str, lobe: str, si, active):
        """Colour parameter ``name`` evaluated at ``si`` where its ``lobe``
        ("diffuse" or "specular") is present, else None (for eval_textures)."""
        if not getattr(self.state.plan.lobes, lobe):
            return None
        return getattr(self, "m_" + name).eval(si, active)

    def enabled(self, ctx) -> Lobes:
        """The lobes that exist and that ctx asks for."""
        lobes = self.state.plan.lobes
        if ctx.type_mask == ALL and ctx.component == ANY:         # (the usual context)
            return lobes
        index = self.state.index
        d = lobes.diffuse and ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, index["diffuse"])
        s = lobes.specular and ctx.is_enabled(mi.BSDFFlags.GlossyReflection, index["specular"])
        ms = self.state.compensation
        return Lobes(d, s, lobes.multiple and (s if ms.lobe == "specular" else d))

    def inputs(self, si, active):
        """Everything a call needs at ``si``, each texture evaluated once: the
        model's inputs and, with compensation, (g(ω_i), G_avg, C)."""
        inp = self.eval_textures(si, active)
        ms = self.state.compensation
        if ms is None or not self.state.plan.lobes.multiple:
            return inp, None
        return inp, (ms.albedo(inp, si.wi, self.m_ms), ms.average(inp, self.m_ms),
                     ms.colour(inp))

    def probabilities(self, inp, ms, si, use: Lobes):
        """(p_d, p_s, p_ms): each used lobe picked in proportion to its weight;
        None when a single lobe is used (nothing to choose: nothing traced)."""
        count = sum(use)
        if count <= 1:
            return None
        w_d, w_s = self.selection_weights(inp, si)
        w_ms = mi.Float(0.0)
        if use.multiple:
            g_i, _, colour = ms
            w = self.lobe_weights(inp)[0 if self.state.compensation.lobe == "diffuse" else 1]
            w_ms = w * mean(colour * g_i)          # (g per channel for a coloured F)
        weights = [w if u else mi.Float(0.0) for u, w in zip(use, (w_d, w_s, w_ms))]
        total_w = weights[0] + weights[1] + weights[2]
        ok = total_w > 0
        inv = 1.0 / dr.select(ok, total_w, 1.0)
        return tuple(dr.select(ok, w * inv, (1.0 / count) if u else 0.0)
                     for u, w in zip(use, weights))

    # --- the BSDF interface (see the module's docstring) -------------------------
    def own_sample(self, ctx):
        """The sampler of a plugin whose lobe weighs its own samples, not by
        eval/pdf (a stochastic lobe: ``cook_torrance``'s walk,
        :func:`.walk.sample_bsdf`), called as ``sample`` is; None (the
        default): :meth:`sample` below."""
        return None

    def sample(self, ctx, si, sample1, sample2, active=True):
        own = self.own_sample(ctx)
        if own is not None:
            return own(self, ctx, si, sample1, sample2, active)
        sample1, sample2 = as_type(sample1, mi.Float), as_type(sample2, mi.Point2f)
        use = self.enabled(ctx)
        if not any(use):
            return dr.zeros(mi.BSDFSample3f), spectrum(mi.UnpolarizedSpectrum(0.0))
        plan = self.state.plan
        active = facing(si, active)
        inp, ms = self.inputs(si, active)
        probs = self.probabilities(inp, ms, si, use)
        modelled = False                 # wo from the model's own sampler (else a warp of sample2)
        if probs is None:              # one lobe, its own sampler (or cosine): nothing to pick
            specular = use.specular                          # a Python constant
            if plan.cosine or not (use.specular or plan.uniform):
                wo = mi.warp.square_to_cosine_hemisphere(sample2)
            elif use.specular:
                wo, modelled = self.sample_specular(inp, si, sample2), True
            else:
                wo = mi.warp.square_to_uniform_hemisphere(sample2)
            own = not plan.cosine or not (use.specular or plan.uniform)
        else:
            # Pick a lobe (comparisons, not ~: scalar variants' masks are Python bools).
            p_d, p_s, _ = probs
            wo = mi.warp.square_to_cosine_hemisphere(sample2)      # diffuse and multiple
            if not plan.cosine:
                if use.diffuse and plan.uniform:
                    wo = dr.select(mi.Bool(sample1 < p_d),
                                   mi.warp.square_to_uniform_hemisphere(sample2), wo)
                if use.specular:
                    pick_s = (mi.Bool(sample1 >= p_d) & (sample1 < p_d + p_s)) if use.multiple \
                        else mi.Bool(sample1 >= p_d)
                    wo = dr.select(pick_s, self.sample_specular(inp, si, sample2), wo)
                    modelled = True
            # the multiple-scattering lobe counts as the kind of the lobe it belongs to
            specular = (mi.Bool(sample1 >= p_d) & (sample1 < p_d + p_s)) \
                if use.multiple and self.state.compensation.lobe == "diffuse" \
                else mi.Bool(sample1 >= p_d)
            own = False

        # The sampled direction is a fixed point for the derivatives (as Mitsuba's
        # differentiable integrators treat it): the weight's gradient is that of
        # eval/pdf there, not of the sampler's warping (which depends on the
        # parameters: a warp of sample2 does not).
        if modelled and dr.grad_enabled(wo):
            wo = dr.detach(wo)
        values, pdf, up = self.lobes(use, probs, inp, ms, si, wo, active)
        active = up & (pdf > 0)                         # (a failed sample: pdf 0)
        lone = values[0] if len(values) == 1 and type(values[0]) is Scaled else None
        closed = lone is not None and own and lone.ratio is not None
        if closed:
            # f / pdf in closed form (e.g. Lambert: its colour): no division, no guard
            weight = dr.select(active, lone.colour, 0.0) if one(lone.ratio) \
                else lone.colour * dr.select(active, lone.ratio, 0.0)
        else:
            # A weight beyond WEIGHT_MAX is no sample of the model but float32
            # failing it: a near-mirror lobe at a grazing viewer (alpha 1e-4, cos
            # 1e-30) puts wo = reflect(wi, m) so close to -wi that wi + wo no longer
            # holds m, and eval and pdf are taken about another half vector. Discarded.
            # (A lone lobe is judged by its shape: its colour is a finite factor.)
            value = lone.shape if lone is not None else product(values[0])
            for v in values[1:]:
                value = value + product(v)
            active &= (value if lone is not None else mean(value)) <= WEIGHT_MAX * pdf
            # weight = value / pdf, both scaled by a detached 1/pdf first: the same
            # value, and derivatives without pdf² (which underflows for the tiny pdfs
            # of grazing samples and would turn the gradient into inf - inf).
            p = dr.select(active, pdf, 1.0)
            value = dr.select(active, value, 0.0)
            scale = dr.detach(1.0 / dr.fmax(p, PDF_FLOOR))
            weight = dr.select(active, (value * scale) / (p * scale), 0.0)
            if lone is not None:
                weight = lone.colour * weight
        # no NaN from inactive lanes either (a warp of sample2 has none anywhere)
        bs = mi.BSDFSample3f(dr.select(active, wo, 0.0) if modelled else wo)
        # (0 already wherever a closed-form weight is: the pdf is 0 below the surface)
        bs.pdf = pdf if closed else dr.select(active, pdf, 0.0)
        bs.eta = 1.0
        index = self.state.index
        if type(specular) is bool:                     # the picked lobe is known
            bs.sampled_type = mi.UInt32(GLOSSY if specular else DIFFUSE)
            bs.sampled_component = mi.UInt32(index["specular"] if specular else index["diffuse"])
        else:
            bs.sampled_type = dr.select(specular, mi.UInt32(GLOSSY), mi.UInt32(DIFFUSE))
            bs.sampled_component = dr.select(specular, mi.UInt32(index["specular"]),
                                             mi.UInt32(index["diffuse"]))
        if type(weight) is not mi.UnpolarizedSpectrum:
            weight = mi.UnpolarizedSpectrum(weight)
        return bs, spectrum(weight)

    def eval(self, ctx, si, wo, active=True):
        wo = as_type(wo, mi.Vector3f)
        use = self.enabled(ctx)
        if not any(use):
            return spectrum(mi.UnpolarizedSpectrum(0.0))
        active = facing(si, active)
        inp, ms = self.inputs(si, active)
        values, _, up = self.lobes(use, None, inp, ms, si, wo, active, pdf=False)
        return spectrum(total(values, active if self.state.plan.behind else up))

    def pdf(self, ctx, si, wo, active=True):
        wo = as_type(wo, mi.Vector3f)
        use = self.enabled(ctx)
        if not any(use):
            return mi.Float(0.0)
        active = facing(si, active)
        inp, ms = self.inputs(si, active)
        return self.lobes(use, self.probabilities(inp, ms, si, use), inp, ms, si, wo, active,
                          value=False)[1]

    def eval_pdf(self, ctx, si, wo, active=True):
        wo = as_type(wo, mi.Vector3f)
        use = self.enabled(ctx)
        if not any(use):
            return spectrum(mi.UnpolarizedSpectrum(0.0)), mi.Float(0.0)
        active = facing(si, active)
        inp, ms = self.inputs(si, active)
        values, pdf, up = self.lobes(use, self.probabilities(inp, ms, si, use), inp, ms, si, wo,
                                     active)
        return spectrum(total(values, active if self.state.plan.behind else up)), pdf

    # --- the lobes, summed --------------------------------------------------------
    def lobes(self, use: Lobes, probs, inp, ms, si, wo, active, value=True, pdf=True):
        """(values, pdf, up) of the used lobes at wo, ``active`` holding the
        viewer above the surface: ``values`` the list of the lobes' weighted
        values (:func:`weighted`; summed and masked by :func:`total`), ``pdf``
        the mixture of the lobes' samplers with the selection probabilities
        ``probs`` (None: a single lobe's own density), 0 where the light is
        below the surface; ``up`` where it is above. Either of the first two is
        None when not asked for."""
        plan = self.state.plan
        up = active & (wo.z > HORIZON)
        w_d, w_s = self.lobe_weights(inp) if value else (None, None)
        values = [] if value else None
        p = None
        lobe_pdfs = pdf
        if pdf and plan.cosine:
            p, lobe_pdfs = mi.warp.square_to_cosine_hemisphere_pdf(wo), False
        p_d, p_s, p_ms = probs if probs is not None else (1.0, 1.0, 1.0)
        if use.diffuse:
            if value:
                values.append(weighted(self.eval_diffuse(inp, si, wo), w_d, plan.scanline))
            if lobe_pdfs:
                p = mixed(p, p_d, mi.warp.square_to_uniform_hemisphere_pdf(wo) if plan.uniform
                          else mi.warp.square_to_cosine_hemisphere_pdf(wo))
        if use.specular:
            if value and lobe_pdfs:
                f_s, p_s_wo = self.eval_pdf_specular(inp, si, wo)
                values.append(weighted(f_s, w_s, plan.scanline))
                p = mixed(p, p_s, p_s_wo)
            elif value:
                values.append(weighted(self.eval_specular(inp, si, wo), w_s, plan.scanline))
            elif lobe_pdfs:
                p = mixed(p, p_s, self.pdf_specular(inp, si, wo))
        if use.multiple:                 # hdr only
            if value:
                f_ms = self.state.compensation.value(inp, si.wi, wo, ms, self.m_ms)
                values.append(weighted(f_ms, w_d if self.state.compensation.lobe == "diffuse"
                                       else w_s, False))
            if lobe_pdfs:
                p = mixed(p, p_ms, mi.warp.square_to_cosine_hemisphere_pdf(wo))
        return values, (dr.select(up, p, 0.0) if pdf else None), up
