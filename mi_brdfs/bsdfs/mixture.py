"""The BSDF interface over a plugin's lobes: ``sample``, ``eval``, ``pdf`` and
``eval_pdf`` for every mi_brdfs plugin, written once.

:class:`Mixture` is the parent of :class:`.base.BRDF`; it reads what the base
decided (``self.state``: the lobes present, the plan of a call, the
compensation) and the model's hooks (:mod:`.model`), and combines the lobes:

- each used lobe is picked in proportion to an estimate of its albedo
  (``selection_weights``; the multiple-scattering lobe by its colour times
  g(ω_i)), and ``pdf`` is the exact mixture of the lobes' samplers;
- a single lobe is sampled by its own sampler with nothing to pick; its
  weight is the closed form the model gives (``Scaled.ratio``) or eval / pdf;
- a lobe's value stays colour · shape (:class:`.lobes.Scaled`) until the end,
  so that masks, weights and guards act on one Float per lane;
- a viewer below (or on) the surface gets no reflection; a sampled direction
  is a fixed point for the derivatives (as Mitsuba's differentiable
  integrators treat it).
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .compensation import ms_lobe
from .lobes import (DIFFUSE, GLOSSY, HORIZON, PDF_FLOOR, WEIGHT_MAX, Lobes, Scaled, as_type,
                    facing, mean, mixed, one, product, total, weighted)


class Mixture:
    """sample / eval / pdf / eval_pdf over the lobes a :class:`.base.BRDF` declares."""

    def probabilities(self, inp, ms, si, use: Lobes):
        """(p_d, p_g, p_ms): each used lobe picked in proportion to its weight;
        None when a single lobe is used (nothing to choose: nothing traced)."""
        count = sum(use)
        if count <= 1:
            return None
        w_d, w_g = self.selection_weights(inp, si)
        w_ms = mi.Float(0.0)
        if use.multiple:
            g_i, _, colour = ms
            w = self.lobe_weights(inp)[0 if self.state.compensation.lobe == "diffuse" else 1]
            w_ms = w * mean(colour) * g_i
        weights = [w if u else mi.Float(0.0) for u, w in zip(use, (w_d, w_g, w_ms))]
        total_w = weights[0] + weights[1] + weights[2]
        ok = total_w > 0
        inv = 1.0 / dr.select(ok, total_w, 1.0)
        return tuple(dr.select(ok, w * inv, (1.0 / count) if u else 0.0)
                     for u, w in zip(use, weights))

    # --- the BSDF interface (see the module's docstring) -------------------------
    def sample(self, ctx, si, sample1, sample2, active=True):
        sample1, sample2 = as_type(sample1, mi.Float), as_type(sample2, mi.Point2f)
        use = self.enabled(ctx)
        if not any(use):
            return dr.zeros(mi.BSDFSample3f), self.spectrum(mi.UnpolarizedSpectrum(0.0))
        plan = self.state.plan
        active = facing(si, active)
        inp, ms = self.inputs(si, active)
        probs = self.probabilities(inp, ms, si, use)
        modelled = False                 # wo from the model's own sampler (else a warp of sample2)
        if probs is None:              # one lobe, its own sampler (or cosine): nothing to pick
            glossy = use.glossy                              # a Python constant
            if plan.cosine or not (use.glossy or plan.uniform):
                wo = mi.warp.square_to_cosine_hemisphere(sample2)
            elif use.glossy:
                wo, modelled = self.sample_glossy(inp, si, sample2), True
            else:
                wo = mi.warp.square_to_uniform_hemisphere(sample2)
            own = not plan.cosine or not (use.glossy or plan.uniform)
        else:
            # Pick a lobe (comparisons, not ~: scalar variants' masks are Python bools).
            p_d, p_g, _ = probs
            wo = mi.warp.square_to_cosine_hemisphere(sample2)      # diffuse and multiple
            if not plan.cosine:
                if use.diffuse and plan.uniform:
                    wo = dr.select(mi.Bool(sample1 < p_d),
                                   mi.warp.square_to_uniform_hemisphere(sample2), wo)
                if use.glossy:
                    pick_g = (mi.Bool(sample1 >= p_d) & (sample1 < p_d + p_g)) if use.multiple \
                        else mi.Bool(sample1 >= p_d)
                    wo = dr.select(pick_g, self.sample_glossy(inp, si, sample2), wo)
                    modelled = True
            # the multiple-scattering lobe counts as the kind of the lobe it belongs to
            glossy = (mi.Bool(sample1 >= p_d) & (sample1 < p_d + p_g)) \
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
        if type(glossy) is bool:                       # the picked lobe is known
            bs.sampled_type = mi.UInt32(GLOSSY if glossy else DIFFUSE)
            bs.sampled_component = mi.UInt32(index["glossy"] if glossy else index["diffuse"])
        else:
            bs.sampled_type = dr.select(glossy, mi.UInt32(GLOSSY), mi.UInt32(DIFFUSE))
            bs.sampled_component = dr.select(glossy, mi.UInt32(index["glossy"]),
                                             mi.UInt32(index["diffuse"]))
        if type(weight) is not mi.UnpolarizedSpectrum:
            weight = mi.UnpolarizedSpectrum(weight)
        return bs, self.spectrum(weight)

    def eval(self, ctx, si, wo, active=True):
        wo = as_type(wo, mi.Vector3f)
        use = self.enabled(ctx)
        if not any(use):
            return self.spectrum(mi.UnpolarizedSpectrum(0.0))
        active = facing(si, active)
        inp, ms = self.inputs(si, active)
        values, _, up = self.lobes(use, None, inp, ms, si, wo, active, pdf=False)
        return self.spectrum(total(values, active if self.state.plan.behind else up))

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
            return self.spectrum(mi.UnpolarizedSpectrum(0.0)), mi.Float(0.0)
        active = facing(si, active)
        inp, ms = self.inputs(si, active)
        values, pdf, up = self.lobes(use, self.probabilities(inp, ms, si, use), inp, ms, si, wo,
                                     active)
        return self.spectrum(total(values, active if self.state.plan.behind else up)), pdf

    # --- the lobes, summed --------------------------------------------------------
    def lobes(self, use: Lobes, probs, inp, ms, si, wo, active, value=True, pdf=True):
        """(values, pdf, up) of the used lobes at wo, ``active`` holding the
        viewer above the surface: ``values`` the list of the lobes' weighted
        values (:func:`.lobes.weighted`; summed and masked by
        :func:`.lobes.total`), ``pdf`` the mixture of the lobes' samplers with
        the selection probabilities ``probs`` (None: a single lobe's own
        density), 0 where the light is below the surface; ``up`` where it is
        above. Either of the first two is None when not asked for."""
        plan = self.state.plan
        up = active & (wo.z > HORIZON)
        w_d, w_g = self.lobe_weights(inp) if value else (None, None)
        values = [] if value else None
        p = None
        lobe_pdfs = pdf
        if pdf and plan.cosine:
            p, lobe_pdfs = mi.warp.square_to_cosine_hemisphere_pdf(wo), False
        p_d, p_g, p_ms = probs if probs is not None else (1.0, 1.0, 1.0)
        if use.diffuse:
            if value:
                values.append(weighted(self.f_diffuse(inp, si, wo), w_d, plan.scanline))
            if lobe_pdfs:
                p = mixed(p, p_d, mi.warp.square_to_uniform_hemisphere_pdf(wo) if plan.uniform
                          else mi.warp.square_to_cosine_hemisphere_pdf(wo))
        if use.glossy:
            if value and lobe_pdfs:
                f_g, p_g_wo = self.f_pdf_glossy(inp, si, wo)
                values.append(weighted(f_g, w_g, plan.scanline))
                p = mixed(p, p_g, p_g_wo)
            elif value:
                values.append(weighted(self.f_glossy(inp, si, wo), w_g, plan.scanline))
            elif lobe_pdfs:
                p = mixed(p, p_g, self.pdf_glossy(inp, si, wo))
        if use.multiple:                 # hdr only
            if value:
                g_i, g_avg, colour = ms
                g_o = self.state.compensation.albedo(inp, wo, self.m_ms)
                f_ms = ms_lobe(colour, g_i, g_o, g_avg, mi.Frame3f.cos_theta(wo))
                values.append(weighted(f_ms, w_d if self.state.compensation.lobe == "diffuse"
                                       else w_g, False))
            if lobe_pdfs:
                p = mixed(p, p_ms, mi.warp.square_to_cosine_hemisphere_pdf(wo))
        return values, (dr.select(up, p, 0.0) if pdf else None), up

    @staticmethod
    def spectrum(value):
        """What eval/sample return: the value itself, or a depolarizing Mueller
        matrix in polarized variants (as Mitsuba's ``diffuse`` does)."""
        return mi.depolarizer(value) if mi.is_polarized else value
