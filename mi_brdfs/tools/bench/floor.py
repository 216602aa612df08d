"""The floor: what a Python BSDF costs without any framework.

Two bare ``mi.BSDF`` subclasses, each the textbook form of one built-in in
Dr.Jit Python and nothing else (no parameter checks, no modes, no lobe
mixture, no guards for grazing angles or float32 extremes):

- ``bench_floor_ggx``: ``roughconductor`` with ``distribution="ggx"``,
  ``material="none"`` (F = 1): the GGX D, the separable Smith G of GGX,
  visible-normal sampling by spherical caps (Dupuy & Benyoub 2023) with the
  weight G1(wo), as Mitsuba's ``MicrofacetDistribution`` does;
- ``bench_floor_diffuse``: ``diffuse``.

They exist for the bench (the ``materials`` and ``tracing`` groups): measured
beside the plugins and the built-ins, in processes of their own, they show how
much of a plugin's cost is Python itself (each traced Dr.Jit operation called
from Python) and how much its framework adds. Registered by :func:`register`
in those processes only; never shipped as plugins.
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

NAMES = {"cook_torrance": "bench_floor_ggx", "lambert": "bench_floor_diffuse"}


def _floor_ggx(base):
    class FloorGGX(base):
        def __init__(self, props):
            base.__init__(self, props)
            self.m_alpha = props.get_texture("alpha", 0.1)
            self.m_reflectance = props.get_texture("specular_reflectance", 1.0)
            self.m_flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [self.m_flags]

        def traverse(self, cb):
            cb.put("alpha", self.m_alpha, mi.ParamFlags.Differentiable)
            cb.put("specular_reflectance", self.m_reflectance, mi.ParamFlags.Differentiable)

        @staticmethod
        def d(m, a2):
            t = m.x * m.x + m.y * m.y + m.z * m.z * a2
            return a2 / (dr.pi * t * t)

        @staticmethod
        def g1(v, a2):
            c2 = v.z * v.z
            return 2.0 * v.z / (v.z + dr.sqrt(c2 + a2 * (1.0 - c2)))

        def sample(self, ctx, si, sample1, sample2, active=True):
            wi = si.wi
            a = self.m_alpha.eval_1(si, active)
            # a visible normal: the viewer stretched, a point on a spherical cap
            v = dr.normalize(mi.Vector3f(a * wi.x, a * wi.y, wi.z))
            s, c = dr.sincos(dr.two_pi * sample2.x)
            z = dr.fma(1.0 - sample2.y, 1.0 + v.z, -v.z)
            r = dr.safe_sqrt(1.0 - z * z)
            m = dr.normalize(mi.Vector3f(a * (c * r + v.x), a * (s * r + v.y), z + v.z))
            wo = mi.reflect(wi, m)
            a2 = a * a
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = wo
            bs.pdf = self.g1(wi, a2) * self.d(m, a2) / (4.0 * wi.z)
            bs.eta = 1.0
            bs.sampled_type = +mi.BSDFFlags.GlossyReflection
            bs.sampled_component = 0
            active &= (wi.z > 0) & (wo.z > 0) & (bs.pdf > 0)
            weight = self.m_reflectance.eval(si, active) * self.g1(wo, a2)
            return bs, dr.select(active, weight, 0.0)

        def eval(self, ctx, si, wo, active=True):
            return self.eval_pdf(ctx, si, wo, active)[0]

        def pdf(self, ctx, si, wo, active=True):
            wi = si.wi
            a = self.m_alpha.eval_1(si, active)
            a2 = a * a
            m = dr.normalize(wi + wo)
            active &= (wi.z > 0) & (wo.z > 0)
            return dr.select(active, self.g1(wi, a2) * self.d(m, a2) / (4.0 * wi.z), 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            wi = si.wi
            a = self.m_alpha.eval_1(si, active)
            a2 = a * a
            m = dr.normalize(wi + wo)
            active &= (wi.z > 0) & (wo.z > 0)
            dg = self.d(m, a2) * self.g1(wi, a2) / (4.0 * wi.z)
            value = self.m_reflectance.eval(si, active) * (dg * self.g1(wo, a2))
            return dr.select(active, value, 0.0), dr.select(active, dg, 0.0)

        def to_string(self):
            return "FloorGGX[]"
    return FloorGGX


def _floor_diffuse(base):
    class FloorDiffuse(base):
        def __init__(self, props):
            base.__init__(self, props)
            self.m_reflectance = props.get_texture("reflectance", 0.5)
            self.m_flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
            self.m_components = [self.m_flags]

        def traverse(self, cb):
            cb.put("reflectance", self.m_reflectance, mi.ParamFlags.Differentiable)

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
            bs.pdf = mi.warp.square_to_cosine_hemisphere_pdf(bs.wo)
            bs.eta = 1.0
            bs.sampled_type = +mi.BSDFFlags.DiffuseReflection
            bs.sampled_component = 0
            active &= (si.wi.z > 0) & (bs.pdf > 0)
            return bs, dr.select(active, self.m_reflectance.eval(si, active), 0.0)

        def eval(self, ctx, si, wo, active=True):
            active &= (si.wi.z > 0) & (wo.z > 0)
            value = self.m_reflectance.eval(si, active) * (dr.inv_pi * wo.z)
            return dr.select(active, value, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            active &= (si.wi.z > 0) & (wo.z > 0)
            return dr.select(active, dr.inv_pi * wo.z, 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            active &= (si.wi.z > 0) & (wo.z > 0)
            pdf = dr.inv_pi * wo.z
            value = self.m_reflectance.eval(si, active) * pdf
            return dr.select(active, value, 0.0), dr.select(active, pdf, 0.0)

        def to_string(self):
            return "FloorDiffuse[]"
    return FloorDiffuse


def register() -> None:
    """Register both floors for the active variant (a bench worker's)."""
    for name, make in (("bench_floor_ggx", _floor_ggx), ("bench_floor_diffuse", _floor_diffuse)):
        cls = make(mi.BSDF)
        mi.register_bsdf(name, lambda props, cls=cls: cls(props))
