r"""
``blinn`` — Lambert diffuse + Blinn(-Phong) specular reflection
================================================================

.. parameters::

With w_r the viewer (``si.wi``), d the light (``wo``), n the normal and the
half vector h = normalize(d + w_r), ``eval`` returns

.. math::

    \text{scanline:}\quad &\operatorname{clamp}_{[0,1]}\big(m_D \max(0, d\cdot n)\big)
        + \operatorname{clamp}_{[0,1]}\big(m_S \max(0, n\cdot h)^\gamma\big) \\
    \text{hdr:}\quad &\Big(\frac{m_D}{\pi} + m_S\,N(\gamma)\max(0, n\cdot h)^\gamma\Big)
        \,(d\cdot n), \qquad
    N(\gamma) = \frac{(\gamma + 2)(\gamma + 4)}{8\pi\,(2^{-\gamma/2} + \gamma)}

The scanline form is the lecture's, each lobe clamped per colour channel to
[0, 1]. The hdr form is reciprocal (h is symmetric in d and w_r).

The normalisation N(gamma) is the *exact normal-incidence* one (F. Giesen,
"Derivation of Phong and Blinn-Phong BRDF normalization factors", 2009): it
makes the specular albedo exactly m_S for a viewer on the normal. There
theta_h = theta_o / 2; with c = cos(theta_o / 2), cos(theta_o) = 2c² - 1 and
sin(theta_o) d(theta_o) = -4c dc, so

    integral cos^gamma(theta_h) cos(theta_o) dw_o
      = 2 pi · integral_{1/sqrt 2}^{1} c^gamma (2c² - 1) 4c dc
      = 8 pi [2 c^(gamma+4)/(gamma+4) - c^(gamma+2)/(gamma+2)]_{1/sqrt 2}^{1}
      = 8 pi (gamma + 2^(-gamma/2)) / ((gamma + 2)(gamma + 4))  =  1 / N(gamma).

Away from the normal the albedo decreases monotonically (the lobe, mapped from
half vectors to light directions by dw_o = 4 (d·h) dw_h, is squeezed and cut
by the horizon; measured by the project's white-furnace test of Blinn), so with
m_D + m_S <= 1 the surface never reflects more than it receives. At gamma = 0,
N = 1/pi and the lobe is Lambert's; for large gamma N ~ (gamma + 6)/(8 pi).
The popular (gamma + 8)/(8 pi) exceeds N for every gamma > 0 (their ratio minus
1 is (2 gamma - 8 + (gamma + 8) 2^(-gamma/2)) / ((gamma + 2)(gamma + 4)) > 0),
so its albedo overshoots: 1.075 at gamma = 10 and normal incidence.

Sampling: cosine hemisphere for the diffuse lobe; for the specular lobe the
half vector with density (gamma + 2)/(2 pi) cos^(gamma+1)(theta_h) (the lobe
times cos(theta_h), normalised), reflected about h: the light direction's
density is that over 4 (d·h). Reflections below the surface are discarded.
The specular lobe is picked in proportion to its albedo at normal incidence
against the diffuse one: m_S vs m_D in hdr mode,
8 (1 - 2^(-(gamma+2)/2))/(gamma + 2) · m_S vs m_D in scanline mode (channel
means). With m_D = 0 there is no diffuse lobe, with m_S = 0 no specular one.

**Energy compensation** (``energy_compensation``): as Phong's
(:mod:`mi_brdfs.bsdfs.phong`), with E(μ, γ) tabulated from Blinn's own hdr lobe.

.. code-block:: xml

    <bsdf type="blinn">
        <rgb name="diffuse_reflectance" value="0.1, 0.2, 0.6"/>
        <rgb name="specular_reflectance" value="0.4, 0.4, 0.4"/>
        <float name="exponent" value="400"/>
        <string name="mode" value="scanline"/>
    </bsdf>
"""
from __future__ import annotations

from dataclasses import replace

import drjit as dr
import mitsuba as mi

from . import microfacet as mf, powercos
from .cases import Cases
from .phong import Formulas, Phong


# ----------------------------------------------------------------------------
#  The formulas (local directions: wi = w_r the viewer, wo = d the light)
# ----------------------------------------------------------------------------

def cos_h(wi, wo):
    """(n·h, 1 - n·h) of h = normalize(d + w_r) (scale-safe: exact for grazing
    pairs, whose |d + w_r|² underflows); (0, 1) when d = -w_r."""
    return powercos.cos_versin_z(mf.half_vector(wi, wo))


def normalisation(gamma):
    """N(gamma) = (gamma+2)(gamma+4) / (8 pi (2^(-gamma/2) + gamma)): albedo m_S
    at normal incidence (see the module docstring)."""
    return (gamma + 2.0) * (gamma + 4.0) / (8.0 * dr.pi * (dr.exp2(-0.5 * gamma) + gamma))


def eval_specular(wi, wo, gamma, mode: str):
    """The specular lobe at wo: the lecture's clamp(n·h)^gamma (scanline), or
    N(gamma) · clamp(n·h)^gamma · cos(theta_o) (hdr)."""
    c, versin = cos_h(wi, wo)
    lobe = powercos.pow_cos(c, versin, gamma)
    if mode == "scanline":
        return lobe
    cos_o = dr.fmax(mi.Frame3f.cos_theta(wo), 0.0)
    return normalisation(gamma) * lobe * cos_o


def specular_weight(gamma, mode: str):
    """The specular lobe's albedo at normal incidence per unit m_S, relative to a
    diffuse lobe's (1 per unit m_D): 1 in hdr mode; in scanline mode the integral
    of cos^gamma(theta_o / 2) over the hemisphere, 8 pi (1 - 2^(-(gamma+2)/2))/(gamma+2),
    over pi."""
    if mode == "hdr":
        return 1.0
    return 8.0 * (1.0 - dr.exp2(-0.5 * gamma - 1.0)) / (gamma + 2.0)


def sample_specular(wi, sample2, gamma):
    """Sample h with density (gamma+2)/(2 pi) cos^(gamma+1)(theta_h), reflect w_r about it."""
    h = powercos.sample(sample2, gamma + 1.0)
    return mi.reflect(wi, h)


def pdf_specular(wi, wo, gamma):
    """The density of :func:`sample_specular` at wo: pdf(h) / (4 d·h), 0 where d·h <= 0."""
    h = mf.half_vector(wi, wo)
    c, versin = powercos.cos_versin_z(h)
    o_dot_h = dr.dot(wo, h)
    valid = o_dot_h > 0.0
    jacobian = 1.0 / (4.0 * dr.select(valid, o_dot_h, 1.0))    # dh/dwo
    return dr.select(valid, powercos.pdf(c, versin, gamma + 1.0) * jacobian, 0.0)


# ----------------------------------------------------------------------------
#  The plugin
# ----------------------------------------------------------------------------

class Blinn(Phong):
    __doc__ = __doc__                  # the module's documentation, for help()
    # Phong's plugin glue (parameters, lobes, sampling) with Blinn's formulas.
    name = "blinn"
    PARAMS = Phong.PARAMS[:2] + (replace(
        Phong.PARAMS[2], doc="γ, the specular power (the lecture: \"one or two hundreds\" in "
        "practice). A Blinn lobe is wider than a Phong lobe of the same γ (about 4x the "
        "exponent gives a similar highlight). γ = 0 makes the hdr model exactly Lambertian. "
        "The lobe is evaluated and sampled to ~1e-6 at any γ (:mod:`mi_brdfs.bsdfs.powercos`); "
        "the bound ``phong.MAX_EXPONENT`` = 1e8 keeps it well above the spacing of float32 "
        "directions (~1e-7)."),)
    SPECULAR = Formulas(eval_specular, sample_specular, pdf_specular, specular_weight)

    @classmethod
    def cases(cls) -> Cases:
        # Phong's, with the fit's self-fit at Blinn's wider exponents
        return replace(super().cases(), fits=[
            {"diffuse_reflectance": [0.5, 0.3, 0.2], "specular_reflectance": [0.3, 0.3, 0.25],
             "exponent": 80.0},
            {"diffuse_reflectance": [0.1, 0.3, 0.5], "specular_reflectance": [0.5, 0.4, 0.2],
             "exponent": 600.0}])
