"""
``cook_torrance`` — Cook-Torrance: Lambert diffuse + microfacet specular
=========================================================================

.. parameters::

With w_r the viewer (``si.wi``), d the light (``wo``), h = normalize(d + w_r),
and D, G, F as in :mod:`mi_brdfs.bsdfs.microfacet`, ``eval`` returns::

    scanline:  k · clamp01(m_D · clamp(d·n))
               + (1 - k) · clamp01(m_S · D F G / (4 clamp(w_r·n)))
    hdr:       (k · m_D / pi + (1 - k) · m_S · D F G / (4 (w_r·n)(d·n))) · (d·n)

The scanline form is the lecture's, per lobe and colour channel clamped to
[0, 1]: not energy conserving, on purpose. The hdr form is the radiometric
Cook-Torrance BRDF (times the cosine Mitsuba's ``eval`` includes).

Sampling: cosine hemisphere for the diffuse lobe; for the specular lobe the
visible normals of Beckmann and GGX (Mitsuba's ``MicrofacetDistribution``) and
D(m)·cos(theta_m) for Blinn; the lobe is picked in proportion to
k·mean(m_D) (pi·k·mean(m_D) in scanline mode, whose Lambert term has no 1/pi)
vs (1 - k)·mean(m_S)·Schlick(w_r·n). With k = 0 (or m_D = 0) there
is no diffuse lobe, with k = 1 (or m_S = 0) no specular one.

**Energy compensation** (``energy_compensation``): the reciprocal
multiple-scattering lobe of Kulla & Conty 2017 / Turquin 2019
(:mod:`mi_brdfs.bsdfs.energy`) whose albedo is what single scattering misses
of the random walk on the Smith microsurface (Heitz, Hanika, d'Eon &
Dachsbacher 2016) with Schlick's F at every bounce, tabulated over
(cos θ, α, F0) for every α (to ∞): the specular lobe reflects m_S·W(θ, α, F0),
W the walk's albedo (within 1.4 % for GGX and 2.0 % for Beckmann with Smith
G; Blinn's D and the V-cavity against the walk of the nearest Smith
microsurface, see ``docs/guide/energy.md``). A white surface (F0 = 1,
m_S = 1; and m_D = 1 if k > 0) reflects 1 at every angle, and m_S scales it
linearly, as ``roughconductor``'s ``specular_reflectance``; with k > 0 the
albedo is k·m_D + (1 - k)·(the compensated specular).

.. code-block:: xml

    <bsdf type="cook_torrance">
        <rgb name="diffuse_reflectance" value="0.6, 0.1, 0.1"/>
        <float name="k" value="0.3"/>
        <float name="alpha" value="0.2"/>
        <string name="distribution" value="ggx"/>
        <string name="geometry" value="smith"/>
    </bsdf>
"""
from __future__ import annotations

from dataclasses import replace

import drjit as dr
import mitsuba as mi

from . import energy, lambert, microfacet as mf
from .base import BRDF, Option, Param, Reader, Scaled, mean
from .grid import Axis


# ----------------------------------------------------------------------------
#  The formulas (local directions: wi = w_r the viewer, wo = d the light)
# ----------------------------------------------------------------------------

def lobe(wi, wo, alpha, distribution: str, f0=None, geometry: str = "smith",
         visible: bool = True, value: bool = True, pdf: bool = True):
    """(specular value, sampling density, their ratio) at wo: each None when not
    asked for (the ratio is known in closed form for Smith's G with visible
    normals only); they share the half vector, D and G1(w_r)/cos θ_r.

    The value is D·F·G / (4 (w_r·n)), the same in both modes (the lecture's
    scanline f_specular is m_S·D F G / (4 clamp(w_r·n)); the hdr BRDF
    m_S·D F G / (4 (w_r·n)(d·n)) times Mitsuba's cos θ_o is the same). Smith:
    D F G1(d) · G1(w_r)/(4 w_r·n), with G1/cos computed without a division by
    the cosine (-> 0 at grazing). V-cavity: its own 1/(4 w_r·n) growth at a
    grazing mirror pair, stopped at cos = ``COS_FLOOR`` (1e-12).

    The density is that of :func:`sample_lobe`: pdf(m) / (4 wo·m), m the half
    vector, pdf(m) the visible normals' G1(w_r)/cos θ_r · (w_r·m) D(m), where
    w_r·m = wo·m cancels (D(m) G1(w_r)/(4 cos θ_r), as Heitz 2018), or the full
    distribution's D(m) cos θ_m. The ratio value / density of visible normals
    with Smith's G is F·G1(d) (no D, no division: bounded by 1).
    """
    h = mf.half_vector(wi, wo)
    d = mf.D[distribution](h, alpha)
    visible = visible and distribution != "blinn"
    smith = geometry == "smith"
    g1_i = mf.G1_OVER_COS[distribution](wi, alpha) if (value and smith) or (pdf and visible) \
        else None
    f = p = ratio = None
    if value:
        i_dot_h = dr.fma(wi.x, h.x, dr.fma(wi.y, h.y, wi.z * h.z))
        fresnel = mf.fresnel_schlick(f0, i_dot_h)
        if smith:
            f_g1_o = fresnel * mf.g1(distribution, wo, alpha)
            f = d * f_g1_o * (g1_i * 0.25)
            ratio = f_g1_o if visible else None
        else:
            cos_i = mi.Frame3f.cos_theta(wi)
            g = mf.g_cook_torrance(mi.Frame3f.cos_theta(h), cos_i,
                                   mi.Frame3f.cos_theta(wo), i_dot_h)
            f = d * fresnel * (g / (4.0 * dr.fmax(cos_i, mf.COS_FLOOR)))
    if pdf:
        # (D is 0 for the zero half vector of wo = -wi, where m·wo = 0)
        if visible:
            p = d * (g1_i * 0.25)
        else:
            o_dot_h = dr.fma(wo.x, h.x, dr.fma(wo.y, h.y, wo.z * h.z))
            p = d * dr.fmax(h.z, 0.0) / (4.0 * dr.fmax(o_dot_h, mf.TINY))
    return f, p, ratio


def specular(wi, wo, alpha, f0, distribution: str, geometry: str):
    """D·F·G / (4 (w_r·n)): the specular lobe's eval value (see :func:`lobe`)."""
    return lobe(wi, wo, alpha, distribution, f0, geometry, pdf=False)[0]


def sample_lobe(wi, sample2, alpha, distribution: str, visible: bool = True):
    """A light direction for the specular lobe: sample m, the microfacet normal
    (the visible normals of Beckmann and GGX, or D(m) cos(theta_m), always for
    Blinn; :mod:`.microfacet`), and reflect w_r about it."""
    if visible and distribution != "blinn":
        m = mf.sample_visible(distribution, wi, sample2, alpha)
    else:
        m = mf.sample_full(distribution, sample2, alpha)
    return mi.reflect(wi, m)


def pdf_lobe(wi, wo, alpha, distribution: str, visible: bool = True):
    """Density of sample_lobe() at wo (see :func:`lobe`)."""
    return lobe(wi, wo, alpha, distribution, visible=visible, value=False)[1]


# ----------------------------------------------------------------------------
#  The plugin
# ----------------------------------------------------------------------------

# Energy compensation (:mod:`.energy`): the single-scattering albedo of each
# D x G with F = 1 and with F0 = 0 (E_ss is linear in F0) over (mu, alpha), and
# the random walk's W over (mu, alpha, F0) of the Smith microsurfaces. alpha
# reaches infinity (Blinn's alpha <= 1: its tables extrapolate beyond).
MU_AXIS = Axis("mu", 0.0, 1.0, 33, "sqrt")
# (the "root" warp: nodes between alpha 10 and 1000 follow the V-cavity's late
# fall at grazing angles, E(85°) = 0.46, 0.12, 0.013 at alpha 10, 30, 100)
ALPHA_AXIS = Axis("alpha", 0.0, float("inf"), 57, "root", smooth=True)
F0_AXIS = Axis("f0", 0.0, 1.0, 25, smooth=True)
ALBEDO_AXES = (MU_AXIS, ALPHA_AXIS)
WALK_AXES = (MU_AXIS, ALPHA_AXIS, F0_AXIS)
# The Smith microsurface whose random walk is the truth for each D (Blinn's
# exponent 2/alpha² - 2 is Walter's mapping onto Beckmann at the same alpha).
WALK_DISTRIBUTION = {"ggx": "ggx", "beckmann": "beckmann", "blinn": "beckmann"}


def spec(distribution: str, geometry: str, f0: float = 1.0) -> energy.AlbedoSpec:
    """The single-scattering albedo table of D x G with Schlick's F0 (1 or 0);
    Blinn's beyond alpha = 1 extrapolated (its alpha <= 1)."""
    hi = 1.0 if distribution == "blinn" else float("inf")
    alpha = lambda a: dr.fmin(dr.fmax(a, mf.ALPHA_MIN), hi)
    name = f"cook_torrance/{distribution}/{geometry}" + ("" if f0 == 1.0 else f"/f0={f0:g}")
    return energy.AlbedoSpec(
        name, ALBEDO_AXES,
        f=lambda wi, wo, a: specular(wi, wo, alpha(a), f0, distribution, geometry),
        sample=lambda wi, u, a: sample_lobe(wi, u, alpha(a), distribution),
        pdf=lambda wi, wo, a: pdf_lobe(wi, wo, alpha(a), distribution),
        valid_up_to=None if distribution != "blinn" else 1.0)


def walk_spec(distribution: str) -> energy.WalkSpec:
    """The random walk's albedo table of the Smith microsurface nearest to D."""
    smith = WALK_DISTRIBUTION[distribution]
    return energy.WalkSpec(f"walk/{smith}", smith, WALK_AXES)


def compensation(distribution: str, geometry: str) -> energy.Table:
    """g(mu, alpha, F0) = W - E_ss (see :func:`.energy.microfacet`)."""
    return energy.microfacet(spec(distribution, geometry), spec(distribution, geometry, 0.0),
                             walk_spec(distribution))


class CookTorrance(BRDF):
    name = "cook_torrance"
    compensable = True
    OPTIONS = (
        Option("distribution", "beckmann", mf.DISTRIBUTIONS, doc="D, the distribution term."),
        Option("geometry", "cook_torrance", mf.GEOMETRIES,
               doc='G: ``"cook_torrance"`` is the lecture\'s microfacet (V-cavity) term, '
                   '``"smith"`` G1(ω_r)·G1(d): the lecture\'s g_GGX for ggx, the Smith '
                   "Beckmann G1 for beckmann (a rational fit of its erf form, within 5.5e-6), "
                   "and for blinn the Smith G1 of the Blinn "
                   "distribution itself, tabulated (:mod:`mi_brdfs.bsdfs.microfacet`)."),
        Option("sample_visible", True,
               doc="Beckmann and GGX: sample the visible normals (else the full distribution "
                   "D(m)·cos θ_m); Blinn always samples the latter."),
    )
    PARAMS = (
        Param("diffuse_reflectance", 0.5, doc="m_D; above 1 allowed (scanline mode clamps)."),
        Param("specular_reflectance", 1.0, doc="m_S, a factor on the specular lobe (as "
              "Mitsuba's ``specular_reflectance``); the Fresnel term is the reflectance."),
        Param("k", 0.5, 0.0, 1.0, kind="float", role="weight",
              doc="the weight of the diffuse lobe; the specular lobe gets 1 - k."),
        Param("f0", 0.04, 0.0, 1.0, kind="float", role="weight",
              doc="F_0 of Schlick's Fresnel approximation."),
        Param("alpha", 0.3, 0.0, None, kind="scalar", role="shape", upper=1.0,
              doc="the lecture's roughness ρ (<= 1 for ``blinn``); values below "
                  "``ALPHA_MIN`` = 1e-4 (0, the perfectly smooth surface, included) are "
                  "clamped to it, as Mitsuba and pbrt do, and values above ``ALPHA_MAX`` = "
                  "1e6 to that (the lobe's limit: it reflects nothing by itself)."),
    )

    def read(self, reader: Reader) -> None:
        for p in self.PARAMS:
            if p.name == "alpha" and self.distribution == "blinn":
                p = replace(p, hi=1.0)                       # Blinn: 2/rho² - 2 >= 0
            self.read_param(reader, p)
        if self.distribution == "blinn" and self.geometry == "smith":
            self.m_g1_blinn = mf.g1_blinn_grid().data        # traversed: frozen functions

    @classmethod
    def albedo_specs(cls) -> list:
        return ([spec(d, g, f0) for d in mf.DISTRIBUTIONS for g in mf.GEOMETRIES
                 for f0 in (1.0, 0.0)] + [walk_spec(d) for d in ("ggx", "beckmann")])

    # --- lobes ---------------------------------------------------------------
    def has_diffuse(self) -> bool:
        return not (self.off("k", 0.0) or self.off("diffuse_reflectance"))

    def has_specular(self) -> bool:
        return not (self.off("k", 1.0) or self.off("specular_reflectance"))

    def eval_textures(self, si, active):
        return self.with_colours(si, active,
                                 alpha=dr.fmin(dr.fmax(self.m_alpha.eval_1(si, active),
                                                       mf.ALPHA_MIN), mf.ALPHA_MAX))

    def lobe_weights(self, inp):
        k = self.switch("k")
        return k, 1.0 - k

    def f_diffuse(self, inp, si, wo):
        return lambert.f(inp.colour_d, mi.Frame3f.cos_theta(wo), self.mode)

    def f_specular(self, inp, si, wo):
        return Scaled(inp.colour_s, specular(si.wi, wo, inp.alpha, self.switch("f0"),
                                             self.distribution, self.geometry))

    def selection_weights(self, inp, si):
        w_d = w_s = mi.Float(0.0)
        if self.diffuse:
            w_d = self.m_k * lambert.albedo(mean(inp.colour_d), self.mode)
        if self.specular:
            fresnel = mf.fresnel_schlick(self.m_f0, mi.Frame3f.cos_theta(si.wi))
            w_s = (1.0 - self.m_k) * mean(inp.colour_s) * fresnel
        return w_d, w_s

    # --- specular sampling ----------------------------------------------------
    def sample_specular(self, inp, si, sample2):
        return sample_lobe(si.wi, sample2, inp.alpha, self.distribution, self.sample_visible)

    def pdf_specular(self, inp, si, wo):
        return pdf_lobe(si.wi, wo, inp.alpha, self.distribution, self.sample_visible)

    def f_pdf_specular(self, inp, si, wo):
        f, p, ratio = lobe(si.wi, wo, inp.alpha, self.distribution, self.switch("f0"),
                           self.geometry, self.sample_visible)
        return Scaled(inp.colour_s, f, ratio), p

    # --- energy compensation ----------------------------------------------------
    def albedo_spec(self) -> energy.AlbedoSpec:
        return spec(self.distribution, self.geometry)

    def compensation(self) -> energy.Table:
        return compensation(self.distribution, self.geometry)

    def table_parameters(self, inp):
        return (inp.alpha, self.m_f0)

    def table_sources(self):
        return ("alpha", "f0")

    def ms_colour(self, inp):
        return inp.colour_s
