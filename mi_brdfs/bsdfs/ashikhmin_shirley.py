r"""
``ashikhmin_shirley`` — Ashikhmin-Shirley: anisotropic Phong specular + coupled diffuse
========================================================================================

.. parameters::

Ashikhmin & Shirley 2000, "An Anisotropic Phong BRDF Model" (Journal of
Graphics Tools 5(2), 25-32): a specular lobe of Phong exponents n_u, n_v
about the normal in half-vector space, with Schlick's Fresnel (R_s its value
at normal incidence), and a diffuse term that takes only what the specular
layer lets through. With k_1 = w_r the viewer (``si.wi``), k_2 = d the light
(``wo``), n, u, v the shading frame (z, x, y), h = normalize(k_1 + k_2) and
k the direction of either (k·h = k_1·h = k_2·h), the paper's BRDF is

.. math::

    \rho_s &= \frac{\sqrt{(n_u + 1)(n_v + 1)}}{8\pi}\,
        \frac{(h\cdot n)^{\big(n_u (h\cdot u)^2 + n_v (h\cdot v)^2\big) / \big(1 - (h\cdot n)^2\big)}}
             {(k\cdot h)\,\max(k_1\cdot n,\; k_2\cdot n)}\,F(k\cdot h) \\
    F(k\cdot h) &= R_s + (1 - R_s)\,(1 - k\cdot h)^5 \\
    \rho_d &= \frac{28 R_d}{23\pi}\,(1 - R_s)
        \Big(1 - \big(1 - \tfrac{k_1\cdot n}{2}\big)^5\Big)
        \Big(1 - \big(1 - \tfrac{k_2\cdot n}{2}\big)^5\Big)

``eval`` returns, each lobe clamped per colour channel to [0, 1] in scanline
mode (the lecture's convention, as ``ward`` and ``cook_torrance``: the diffuse
term without its 1/pi, as the lecture's m_D·clamp(d·n); the specular one the
BRDF times d·n, as the lecture's Ward and Cook-Torrance terms)

.. math::

    \text{scanline:}\quad &\operatorname{clamp}_{[0,1]}\big(\pi\,\rho_d\,(d\cdot n)\big)
        + \operatorname{clamp}_{[0,1]}\big(\rho_s\,(d\cdot n)\big) \\
    \text{hdr:}\quad &(\rho_d + \rho_s)\,(d\cdot n)

Both terms are symmetric in k_1 and k_2: the hdr BRDF is reciprocal. The
exponent of h·n is the anisotropic Phong exponent n_u cos²phi_h + n_v sin²phi_h
(phi_h the azimuth of h); at h = n, where it is 0/0, the power is 1 for any
exponent. Where k·h falls below ``KH_MIN`` = 1e-12 (a viewer and a light
grazing the surface from opposite sides, where 1/(k·h) diverges) it is held
there, so that values and gradients stay finite. (h·n)^e is evaluated
accurately in float32 for exponents up to 1e8 (:mod:`mi_brdfs.bsdfs.powercos`).

Sampling: cosine hemisphere for the diffuse lobe; for the specular lobe the
paper's half-vector sampling: with psi = 2 pi u_1, the azimuth phi_h in the
quadrant of psi with tan phi_h = sqrt((n_u + 1)/(n_v + 1)) tan psi, then
cos theta_h = (1 - u_2)^(1 / (n_u cos²phi_h + n_v sin²phi_h + 1)), and
d = reflect(w_r, h). Densities (the paper's)

.. math::

    p_h(h) &= \frac{\sqrt{(n_u + 1)(n_v + 1)}}{2\pi}\,
        (h\cdot n)^{n_u \cos^2\phi_h + n_v \sin^2\phi_h} \\
    p(d) &= \frac{p_h(h)}{4\,(k\cdot h)}

Samples below the surface are discarded (the pdf over the hemisphere
integrates to less than 1). rho_s · (d·n) / p(d) = F(k·h) · min(1, (d·n)/(w_r·n))
<= 1: this is why the paper's normalisation is the one it is, and it bounds the
specular lobe's albedo by that of F. The lobes are picked in proportion to
mean(R_s + (1 - R_s)(1 - w_r·n)^5) (the specular) against
mean(R_d (1 - R_s)) · (1 - (1 - (w_r·n)/2)^5), times pi in scanline mode (the diffuse).

**No energy compensation.** The model is not a single-scattering microfacet
model losing a known multiple-scattering part (there is no microsurface whose
random walk would be the truth to compensate towards), and its split of the
energy is its own design: the specular layer reflects F, the diffuse term
28/(23 pi)·(1 - R_s)·... is normalised so that a white substrate (R_d = 1)
under a non-reflecting layer (R_s = 0) has albedo 1 - (1 - (w_r·n)/2)^5
(0.969 at normal incidence), and what the specular lobe does not reflect is,
in the paper's layered picture, what goes into the substrate. Adding the
Kulla-Conty lobe to the specular term would count that energy twice. The
albedo stays at most 1 (the bound above and the white furnace in the tests).

**Parameters.** ``exponent_u`` / ``exponent_v`` are the paper's n_u, n_v:
Phong exponents, as ``phong``'s and ``blinn``'s ``exponent``, with the
``_u``/``_v`` suffixes of Mitsuba's ``alpha_u``/``alpha_v`` (u the shading
frame's s axis). No roughness (alpha-like) names: the paper's formulas, its
sampler and its pdf are written in exponents, and any mapping to a roughness
would be a choice of ours, not the paper's. Both are always read (there is
no isotropic alias): the fit, which searches the parameters a plugin exposes
at its defaults, then fits the anisotropy too.

.. code-block:: xml

    <bsdf type="ashikhmin_shirley">
        <rgb name="diffuse_reflectance" value="0.5, 0.1, 0.1"/>
        <rgb name="specular_reflectance" value="0.05, 0.05, 0.05"/>
        <float name="exponent_u" value="1000"/>
        <float name="exponent_v" value="20"/>
    </bsdf>
"""
from __future__ import annotations

from typing import NamedTuple

import drjit as dr
import mitsuba as mi

from . import fresnel, powercos
from .base import BRDF, Effective, rgb_list, schlick
from .cases import THETAS_LOW, Cases, Chi2, Furnace, Pictures, rgb
from .microfacet import half_vector
from .mixture import Float, Scaled, Spectrum, mean
from .params import Param

MAX_EXPONENT = 1e8    # as phong's: the lobe is still 1000x the float32 direction spacing
KH_MIN = 1e-12        # smallest k·h in 1/(k·h) (grazing pairs from opposite sides)
S2_MIN = 1e-30        # (h·u)² + (h·v)² below this: h = n, where the exponent is 0/0
DIFFUSE_NORM = 28.0 / (23.0 * dr.pi)


# ----------------------------------------------------------------------------
#  The formulas (local directions: wi = k_1 the viewer, wo = k_2 the light)
# ----------------------------------------------------------------------------

def fifth(x):
    """x^5 by multiplication."""
    x2 = x * x
    return x2 * x2 * x


def phong_exponent(h, n_u, n_v):
    """(n_u (h·u)² + n_v (h·v)²) / (1 - (h·n)²), with 1 - (h·n)² = (h·u)² + (h·v)²
    (no cancellation); (n_u + n_v)/2 at h = n, where the power is 1 anyway."""
    x2, y2 = dr.square(h.x), dr.square(h.y)
    s2 = x2 + y2
    tilted = s2 > S2_MIN
    e = (n_u * x2 + n_v * y2) / dr.select(tilted, s2, 1.0)
    return dr.select(tilted, e, 0.5 * (n_u + n_v))


def half_vector_power(h, n_u, n_v):
    """(h·n)^(n_u cos²phi_h + n_v sin²phi_h), 0 where h·n <= 0."""
    cos_h, versin_h = powercos.cos_versin_z(h)
    return powercos.pow_cos(cos_h, versin_h, phong_exponent(h, n_u, n_v))


def normalisation(n_u, n_v):
    """sqrt((n_u + 1)(n_v + 1)), written so that it cannot overflow."""
    return dr.sqrt(n_u + 1.0) * dr.sqrt(n_v + 1.0)


def eval_specular(wi, wo, n_u, n_v):
    """rho_s / F · (d·n), the eval value of the specular lobe per unit Fresnel
    (the same in both modes), and k·h (Fresnel's cosine).

    1/max(k_1·n, k_2·n) · (k_2·n) is written (d·n)/max(...) <= 1."""
    h = half_vector(wi, wo)
    k_h = dr.fmax(dr.dot(wo, h), KH_MIN)
    cos_i, cos_o = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(wo)
    up = (cos_i > 0.0) & (cos_o > 0.0)
    cos_ratio = dr.select(up, cos_o, 0.0) / dr.select(up, dr.fmax(cos_i, cos_o), 1.0)
    shape = (normalisation(n_u, n_v) / (8.0 * dr.pi) * half_vector_power(h, n_u, n_v)
             / k_h * cos_ratio)
    return shape, k_h


def eval_diffuse(cos_i, cos_o, mode: str):
    """rho_d / (R_d (1 - R_s)) · (d·n): 28/(23 pi) · (1 - (1 - k_1·n/2)^5)
    · (1 - (1 - k_2·n/2)^5) · (d·n), times pi in scanline mode; 0 below the surface."""
    up = (cos_i > 0.0) & (cos_o > 0.0)
    c_i, c_o = dr.select(up, cos_i, 0.0), dr.select(up, cos_o, 0.0)
    shape = DIFFUSE_NORM * (1.0 - fifth(1.0 - 0.5 * c_i)) * (1.0 - fifth(1.0 - 0.5 * c_o)) * c_o
    return shape * (dr.pi if mode == "scanline" else 1.0)


# ----------------------------------------------------------------------------
#  The paper's half-vector sampling
# ----------------------------------------------------------------------------

def sample_half_vector(sample2, n_u, n_v):
    """h with density p_h: phi_h from tan phi_h = sqrt((n_u+1)/(n_v+1)) tan psi
    (psi = 2 pi u_1, same quadrant), then cos theta_h = (1 - u_2)^(1/(e + 1))."""
    sin_psi, cos_psi = dr.sincos(dr.two_pi * sample2.x)
    a, b = dr.sqrt(n_v + 1.0) * cos_psi, dr.sqrt(n_u + 1.0) * sin_psi
    r = dr.rsqrt(dr.fmax(a * a + b * b, 1e-30))
    cos_phi, sin_phi = a * r, b * r
    e = n_u * dr.square(cos_phi) + n_v * dr.square(sin_phi)
    # log cos theta_h = log(1 - u_2)/(e + 1); sin² from expm1 (no cancellation near n)
    y = dr.log(dr.fmax(1.0 - sample2.y, powercos.U_MIN)) / (e + 1.0)
    cos_t = dr.exp(y)
    sin_t = dr.sqrt(dr.fmax(-powercos.expm1(2.0 * y), powercos.TINY))
    return mi.Vector3f(sin_t * cos_phi, sin_t * sin_phi, cos_t)


def pdf_half_vector(h, n_u, n_v):
    """p_h(h) = sqrt((n_u + 1)(n_v + 1)) / (2 pi) · (h·n)^e(phi_h)."""
    return normalisation(n_u, n_v) * dr.inv_two_pi * half_vector_power(h, n_u, n_v)


def sample_specular(wi, sample2, n_u, n_v):
    """Sample h, then reflect the viewer about it."""
    return mi.reflect(wi, sample_half_vector(sample2, n_u, n_v))


def pdf_specular(wi, wo, n_u, n_v):
    """The density of :func:`sample_specular` at wo: p_h(h) / (4 k·h), 0 where k·h <= 0."""
    h = half_vector(wi, wo)
    k_h = dr.dot(wo, h)
    p = pdf_half_vector(h, n_u, n_v) / (4.0 * dr.fmax(k_h, KH_MIN))
    return dr.select(k_h > 0.0, p, 0.0)


# ----------------------------------------------------------------------------
#  The plugin
# ----------------------------------------------------------------------------

class Inputs(NamedTuple):
    """What one call evaluates at its point."""
    colour_s: Spectrum              # R_s, Schlick's F0 (the specular lobe is always present)
    transmitted: Spectrum | None    # R_d (1 - R_s), where the diffuse lobe is present
    n_u: Float                      # the exponent along u
    n_v: Float                      # ... and along v


class AshikhminShirley(BRDF):
    __doc__ = __doc__                  # the module's documentation, for help()
    name = "ashikhmin_shirley"
    PARAMS = (
        Param("diffuse_reflectance", 0.5,
              doc="R_d, the substrate's colour (the diffuse term's reflectance); above 1 "
                  "allowed (scanline mode clamps)."),
        Param("specular_reflectance", 0.05, 0.0, 1.0, role="weight",
              doc="R_s, the specular layer's reflectance at normal incidence (Schlick's "
                  "F0), per colour channel: 0.04-0.05 for plastics, up to 1 for metals. "
                  "The diffuse term is weighted by 1 - R_s, so R_s is at most 1. R_s = 0 "
                  "keeps a specular lobe: F = (1 - k·h)^5 towards grazing."),
        Param("exponent_u", 100.0, 0.0, MAX_EXPONENT, kind="scalar", role="shape",
              discontinuous=True,
              doc="n_u, the Phong exponent along u (the shading frame's s axis, local x, "
                  "along dp/du): the larger, the narrower the highlight along u."),
        Param("exponent_v", 100.0, 0.0, MAX_EXPONENT, kind="scalar", role="shape",
              discontinuous=True,
              doc="n_v, the Phong exponent along v (local y). n_u = n_v: an isotropic "
                  "lobe."),
    )

    # --- lobes ---------------------------------------------------------------
    def has_diffuse(self) -> bool:
        return not self.off("diffuse_reflectance")

    def has_specular(self) -> bool:
        return True                    # R_s = 0 still reflects (1 - k·h)^5 towards grazing

    def eval_textures(self, si, active) -> Inputs:
        r_s = self.m_specular_reflectance.eval(si, active)
        r_d = self.colour("diffuse_reflectance", "diffuse", si, active)
        return Inputs(r_s, None if r_d is None else r_d * (1.0 - r_s),
                      self.m_exponent_u.eval_1(si, active), self.m_exponent_v.eval_1(si, active))

    def eval_diffuse(self, inp, si, wo):
        cos_i, cos_o = mi.Frame3f.cos_theta(si.wi), mi.Frame3f.cos_theta(wo)
        return Scaled(inp.transmitted, eval_diffuse(cos_i, cos_o, self.options.mode))

    def eval_specular(self, inp, si, wo):
        shape, k_h = eval_specular(si.wi, wo, inp.n_u, inp.n_v)
        return Scaled(fresnel.schlick(inp.colour_s, k_h), shape)

    def selection_weights(self, inp, si):
        lobes = self.state.plan.lobes
        cos_i = dr.clip(mi.Frame3f.cos_theta(si.wi), 0.0, 1.0)
        if lobes.diffuse:
            w_d = mean(inp.transmitted) * (1.0 - fifth(1.0 - 0.5 * cos_i))
            if self.options.mode == "scanline":
                w_d = w_d * dr.pi
        else:
            w_d = mi.Float(0.0)
        w_s = mean(fresnel.schlick(inp.colour_s, cos_i)) if lobes.specular else mi.Float(0.0)
        return w_d, w_s

    @classmethod
    def effective(cls, values: dict, cos_theta: float) -> Effective:
        """R_d (1 - R_s), and Schlick's F of R_s at θ."""
        r_s = rgb_list(values["specular_reflectance"])
        r_d = rgb_list(values["diffuse_reflectance"])
        return Effective([d * (1.0 - s) for d, s in zip(r_d, r_s)], schlick(r_s, cos_theta))

    # --- specular sampling --------------------------------------------------------
    def sample_specular(self, inp, si, sample2):
        return sample_specular(si.wi, sample2, inp.n_u, inp.n_v)

    def pdf_specular(self, inp, si, wo):
        return pdf_specular(si.wi, wo, inp.n_u, inp.n_v)

    # --- what runs of it: the tests, the validation report, the bench, the pictures ---
    @classmethod
    def cases(cls) -> Cases:
        a = {"type": cls.name}

        def ex(n_u, n_v, **kw):
            return {**a, "exponent_u": n_u, "exponent_v": n_v, **kw}
        # viewers at azimuth 30°: neither along u nor along v (the lobe is asymmetric)
        chi2 = [Chi2(ex(n_u, n_v, diffuse_reflectance=r_d), (0, 30, 60, 85), phi=30.0, ires=32,
                     quick=(n_u, n_v, r_d) in ((1000.0, 20.0, 0.5), (100.0, 100.0, 0.0)))
                for n_u, n_v in ((1.0, 1.0), (100.0, 100.0), (1000.0, 20.0), (20.0, 1000.0))
                for r_d in (0.0, 0.5)]
        # a lobe 0.01 rad wide: not at the pole of the χ² grid, whose cells there
        # integrate the pdf to 1.05 at ires 32 and 1.01 at 64 (as phong's γ = 1e4)
        chi2 += [Chi2(ex(1e4, 1e4, diffuse_reflectance=0.0), (30, 60, 85), phi=30.0, ires=64)]
        chi2 += [Chi2(ex(200.0, 10.0, mode="scanline", diffuse_reflectance=rgb([0.9, 0.2, 0.1]),
                         specular_reflectance=rgb([0.9, 0.5, 0.04])), (45,), phi=30.0, ires=32),
                 Chi2(ex(0.0, 0.0, specular_reflectance=0.5), (20, 75), phi=30.0, ires=32)]
        white_s = {**a, "diffuse_reflectance": 0.0, "specular_reflectance": 1.0}
        return Cases(
            chi2=chi2,
            consistency=[dict(a), ex(0.0, 0.0), ex(1e4, 10.0, diffuse_reflectance=0.0),
                         ex(1e6, 1e6, specular_reflectance=0.9),
                         ex(50.0, 500.0, mode="scanline", diffuse_reflectance=rgb([1.0, 0.3, 0.0]),
                            specular_reflectance=rgb([0.9, 0.9, 0.2])),
                         {**a, "specular_reflectance": 0.0},
                         {**a, "diffuse_reflectance": 0.0}],
            furnace=[Furnace("R_d = 0, R_s = 1, n 100 × 100", {**white_s, "exponent_u": 100.0,
                                                               "exponent_v": 100.0}),
                     Furnace("R_d = 0, R_s = 1, n 10 × 1000",
                             {**white_s, "exponent_u": 10.0, "exponent_v": 1000.0},
                             phis=(0.0, 90.0)),
                     Furnace("R_d = 1, R_s = 0.05, n 100 × 100",
                             {**a, "diffuse_reflectance": 1.0, "specular_reflectance": 0.05}),
                     Furnace("R_d = 1, R_s = 0",
                             {**a, "diffuse_reflectance": 1.0, "specular_reflectance": 0.0},
                             thetas=THETAS_LOW)],
            # the report's rows: lobes its quick quadrature (256 x 1024) resolves at 89°
            # (n_v = 1000: 0.5165 against 0.5058 at 1024 x 4096, beyond its 0.01)
            report_furnace=[("R_d = 0, R_s = 1, n 10 × 10", ex(10.0, 10.0, **white_s)),
                            ("R_d = 0, R_s = 1, n 10 × 50", ex(10.0, 50.0, **white_s)),
                            ("R_d = 1, R_s = 0.05, n 100 × 100",
                             {**a, "diffuse_reflectance": 1.0, "specular_reflectance": 0.05})],
            extremes=[ex(n_u, n_v, mode=mode, diffuse_reflectance=r_d, specular_reflectance=r_s)
                      for n_u, n_v in ((0.0, 0.0), (0.0, 1e8), (1e8, 1e8), (1.0, 1e4), (100.0, 100.0))
                      for mode in ("hdr", "scanline")
                      for r_d, r_s in ((0.5, 0.05), (0.0, 1.0), (1.0, 0.0))],
            interior=[ex(30.0, 120.0, diffuse_reflectance=0.4, specular_reflectance=0.3),
                      ex(500.0, 8.0, diffuse_reflectance=0.7, specular_reflectance=0.6)],
            negative=(ex(100.0, 1000.0, diffuse_reflectance=0.0),
                      ex(100.0, 1100.0, diffuse_reflectance=0.0), 45),
            negative_phi=30.0,
            lobe_width=0.2,
            reciprocity=[ex(n_u, n_v, diffuse_reflectance=rgb([0.8, 0.5, 0.2]),
                            specular_reflectance=rgb([0.9, 0.3, 0.05]))
                         for n_u, n_v in ((1.0, 1.0), (30.0, 300.0), (1e3, 10.0))],
            lobe=ex(20.0, 200.0, diffuse_reflectance=0.3, specular_reflectance=0.3),
            costs=[(cls.name, ex(50.0, 500.0))],
            sampling=[("ashikhmin_shirley 50 x 500", ex(50.0, 500.0, diffuse_reflectance=0.0,
                                                        specular_reflectance=0.9),
                       [("lobe", {}), ("cosine", {"sampling": "cosine"})])],
            pictures=Pictures("exponent_v", (10.0, 100.0, 1000.0),
                              {"exponent_u": 1000.0, "diffuse_reflectance": 0.3,
                               "specular_reflectance": 0.2}),
            fits=[{"diffuse_reflectance": [0.5, 0.3, 0.2], "specular_reflectance": [0.3, 0.3, 0.25],
                   "exponent_u": 40.0, "exponent_v": 200.0},
                  {"diffuse_reflectance": [0.1, 0.3, 0.5], "specular_reflectance": [0.5, 0.4, 0.2],
                   "exponent_u": 300.0, "exponent_v": 30.0}],
            mitsuba=("roughplastic", "roughconductor"),
            checked="its sampler's closed-form weight; its diffuse term's closed-form albedo; "
                    "white furnace",
        )
