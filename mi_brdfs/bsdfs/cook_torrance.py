"""
``cook_torrance`` — Cook-Torrance: Lambert diffuse + microfacet specular
=========================================================================

.. list-table::
   :header-rows: 1

   * - Parameter
     - Type
     - Description
     - Default
   * - ``diffuse_reflectance``
     - float, rgb or texture (∂)
     - m_D, >= 0 (above 1 allowed: scanline mode clamps).
     - 0.5
   * - ``specular_reflectance``
     - float, rgb or texture (∂)
     - m_S, >= 0.
     - 1.0
   * - ``k``
     - float in [0, 1] (∂)
     - weight of the diffuse lobe; the specular lobe gets 1 - k.
     - 0.5
   * - ``f0``
     - float in [0, 1] (∂)
     - F_0 of Schlick's Fresnel approximation.
     - 0.04
   * - ``alpha``
     - float or texture >= 0 (∂)
     - the lecture's roughness rho (<= 1 for ``blinn``); values below
       ``ALPHA_MIN`` = 1e-4 (including 0, the perfectly smooth surface) are
       clamped to it, as Mitsuba and pbrt do.
     - 0.3
   * - ``distribution``
     - string
     - D: ``"blinn"``, ``"beckmann"`` or ``"ggx"``.
     - ``"beckmann"``
   * - ``geometry``
     - string
     - G: ``"cook_torrance"`` (the lecture's V-cavity term) or ``"smith"``
       (G1(w_r)·G1(d): the lecture's g_GGX for ggx, the exact Smith Beckmann
       G1 for beckmann and blinn).
     - ``"cook_torrance"``
   * - ``sample_visible``
     - bool
     - Beckmann and GGX: sample the visible normals (else the full
       distribution D(m)·cos(theta_m)); Blinn always samples the latter.
     - true
   * - ``mode``
     - string
     - ``"hdr"`` or ``"scanline"``.
     - ``"hdr"``
   * - ``sampling``
     - string
     - ``"lobe"`` (the importance sampling below) or ``"cosine"`` (every
       lobe from the cosine hemisphere; for benchmarks).
     - ``"lobe"``

With w_r the viewer (``si.wi``), d the light (``wo``), h = normalize(d + w_r),
and D, G, F as in :mod:`mi_brdfs.microfacet`, ``eval`` returns::

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

import drjit as dr
import mitsuba as mi

from . import lambert, microfacet as mf
from .base import BRDF, Reader, is_zero, mean


# ----------------------------------------------------------------------------
#  The formulas (local directions: wi = w_r the viewer, wo = d the light)
# ----------------------------------------------------------------------------

def specular(wi, wo, alpha, f0, distribution: str, geometry: str):
    """D·F·G / (4 (w_r·n)): the specular lobe's eval value, the same in both modes.

    (The lecture's scanline f_specular is m_S·D F G / (4 clamp(w_r·n)); the hdr
    BRDF m_S·D F G / (4 (w_r·n)(d·n)) times Mitsuba's cos(theta_o) is the same.)
    """
    cos_i, cos_o = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(wo)
    h = mf.half_vector(wi, wo)
    cos_h, i_dot_h = mi.Frame3f.cos_theta(h), dr.dot(wi, h)
    d = mf.D[distribution](h, alpha)
    f = mf.fresnel_schlick(f0, i_dot_h)
    if geometry == "smith":
        g = mf.g_smith(distribution, wi, wo, alpha)
    else:
        g = mf.g_cook_torrance(cos_h, cos_i, cos_o, i_dot_h)
    return d * f * g / (4.0 * dr.fmax(cos_i, mf.TINY))


# ----------------------------------------------------------------------------
#  The plugin
# ----------------------------------------------------------------------------

MICROFACET_TYPE = {"beckmann": "Beckmann", "ggx": "GGX"}


class CookTorrance(BRDF):
    name = "cook_torrance"

    def read(self, reader: Reader) -> None:
        self.distribution = reader.choice("distribution", "beckmann", mf.DISTRIBUTIONS)
        self.geometry = reader.choice("geometry", "cook_torrance", mf.GEOMETRIES)
        self.m_diffuse = reader.texture("diffuse_reflectance", 0.5)      # m_D
        self.m_specular = reader.texture("specular_reflectance", 1.0)    # m_S
        self.m_k = reader.scalar("k", 0.5, 0.0, 1.0)                     # diffuse weight
        self.m_f0 = reader.scalar("f0", 0.04, 0.0, 1.0)                  # Schlick's F_0
        alpha_max = 1.0 if self.distribution == "blinn" else None        # Blinn: 2/rho²-2 >= 0
        self.m_alpha = reader.texture("alpha", 0.3, 0.0, alpha_max)      # rho
        self.sample_visible = bool(reader.props.get("sample_visible", True))

    def traverse(self, cb):
        flags = mi.ParamFlags.Differentiable
        cb.put("diffuse_reflectance", self.m_diffuse, flags)
        cb.put("specular_reflectance", self.m_specular, flags)
        cb.put("alpha", self.m_alpha, flags)
        cb.put("k", self.m_k, flags)
        cb.put("f0", self.m_f0, flags)

    # --- lobes ---------------------------------------------------------------
    def k_value(self) -> float:
        return float(self.m_k[0])

    def has_diffuse(self) -> bool:
        return self.k_value() > 0.0 and not is_zero(self.m_diffuse)

    def has_specular(self) -> bool:
        return self.k_value() < 1.0 and not is_zero(self.m_specular)

    def lobe_weights(self):
        return self.m_k, 1.0 - self.m_k

    def alpha(self, si, active):
        return dr.fmax(self.m_alpha.eval_1(si, active), mf.ALPHA_MIN)

    def lobes(self, si, wo, active):
        f_d = mi.Spectrum(0.0)
        f_s = mi.Spectrum(0.0)
        if self.diffuse:
            m_d = self.m_diffuse.eval(si, active)
            f_d = lambert.f(m_d, mi.Frame3f.cos_theta(wo), self.mode)
        if self.specular:
            m_s = self.m_specular.eval(si, active)
            f_s = m_s * specular(si.wi, wo, self.alpha(si, active), self.m_f0,
                                 self.distribution, self.geometry)
        return f_d, f_s

    def selection_weights(self, si, active):
        w_d = self.m_k * lambert.albedo(mean(self.m_diffuse.eval(si, active)), self.mode)
        fresnel = mf.fresnel_schlick(self.m_f0, mi.Frame3f.cos_theta(si.wi))
        w_s = (1.0 - self.m_k) * mean(self.m_specular.eval(si, active)) * fresnel
        return w_d, w_s

    # --- specular sampling ----------------------------------------------------
    def mitsuba_distribution(self, si, active):
        kind = getattr(mi.MicrofacetType, MICROFACET_TYPE[self.distribution])
        return mi.MicrofacetDistribution(kind, self.alpha(si, active), self.sample_visible)

    def sample_specular(self, si, sample2, active):
        # Sample m, the microfacet normal, then reflect the viewer about it.
        if self.distribution == "blinn":
            m = mf.sample_blinn(sample2, self.alpha(si, active))
        else:
            m, _ = self.mitsuba_distribution(si, active).sample(si.wi, sample2)
        return mi.reflect(si.wi, m)

    def pdf_specular(self, si, wo, active):
        h = mf.half_vector(si.wi, wo)
        jacobian = 1.0 / (4.0 * dr.fmax(dr.dot(wo, h), mf.TINY))   # dm/dwo
        if self.distribution == "blinn":
            pdf_m = mf.pdf_blinn(h, self.alpha(si, active))
        else:
            pdf_m = self.mitsuba_distribution(si, active).pdf(si.wi, h)
        return dr.select(dr.dot(wo, h) > 0, pdf_m * jacobian, 0.0)

    def describe(self) -> dict:
        return {"distribution": self.distribution, "geometry": self.geometry,
                "k": self.m_k, "f0": self.m_f0, "alpha": self.m_alpha,
                "diffuse_reflectance": self.m_diffuse,
                "specular_reflectance": self.m_specular}
