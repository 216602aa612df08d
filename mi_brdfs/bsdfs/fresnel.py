r"""Fresnel reflectance: how much of the light a microfacet reflects at the
cosine c = ω·m between a direction and the facet's normal.

``schlick``: the lecture's F = F0 + (1 - F0)(1 - clamp(c))^5 (Schlick 1994),
F0 the reflectance at normal incidence (a number or a colour).

``conductor``: the exact unpolarised reflectance of a conductor whose index
of refraction relative to the outside is complex, η + iκ (per colour channel,
or per wavelength in spectral variants), as Mitsuba's ``roughconductor``
takes it. With a² + b² = √((η² - κ² - s²)² + 4η²κ²), a = √((a² + b² + η² - κ²
- s²)/2) and s² = 1 - c² (Born & Wolf, *Principles of Optics*, §14.2):

.. math::

    R_s = \frac{a^2 + b^2 - 2ac + c^2}{a^2 + b^2 + 2ac + c^2},\quad
    R_p = R_s\,\frac{(a^2 + b^2)c^2 - 2acs^2 + s^4}{(a^2 + b^2)c^2 + 2acs^2 + s^4},\quad
    F = \tfrac12 (R_s + R_p).

``dielectric``: the exact unpolarised reflectance of a dielectric interface
of relative index η = η_int/η_ext (the light arriving from outside; total
internal reflection where η < 1 and s² > η²): with c_t = √(1 - s²/η²),
r_s = (c - η c_t)/(c + η c_t), r_p = (η c - c_t)/(η c + c_t), F = (r_s² + r_p²)/2.

``f82``: Hoffman's F82-tint model (N. Hoffman, *Generalization of Adobe's
Fresnel Model*, 2023; the metal of OpenPBR and of Adobe's Standard Material):
Schlick's curve less a term that dips at c̄ = 1/7 (θ ≈ 82°), where the
reflectance becomes ``f82_tint`` times Schlick's:

.. math::

    F = F_S(c) - \frac{F_S(\bar c)\,(1 - t)}{\bar c\,(1 - \bar c)^6}\;c\,(1 - c)^6,
    \qquad F_S(c) = F_0 + (1 - F_0)(1 - c)^5.
"""
from __future__ import annotations

import drjit as dr

F82_COS = 1.0 / 7.0                 # c̄: cos 81.8°, where F82-tint sets the dip
TINY = 1e-30                        # keeps the dielectric's quotients finite at their limits


def schlick(f0, c):
    """F0 + (1 - F0)(1 - clamp(c))^5; the Python number 1 for the number 1 (F = 1
    at every angle: nothing traced)."""
    if type(f0) is float and f0 == 1.0:
        return 1.0
    m = 1.0 - dr.fmin(dr.fmax(c, 0.0), 1.0)
    m2 = m * m
    return f0 + (1.0 - f0) * (m2 * m2 * m)


def conductor(eta, kappa, c):
    """The exact reflectance of a conductor of complex index η + iκ at cos c
    (clamped to [0, 1]; η, κ colours or Floats). 1 for the perfect conductor
    η = 0, κ = 1 (``roughconductor``'s default), 0 for η = 1, κ = 0 (no interface)."""
    c = dr.fmin(dr.fmax(c, 0.0), 1.0)
    c2 = c * c
    s2 = 1.0 - c2
    eta2, kappa2 = eta * eta, kappa * kappa
    t = (eta2 - kappa2 - 1.0) + c2      # η² - κ² - s², exact where c² << 1 and η ~ 1
    # a² + b² >= |t| (also where t² underflows); safe_sqrt: a zero derivative at 0
    ab = dr.fmax(dr.safe_sqrt(t * t + 4.0 * eta2 * kappa2), dr.abs(t))
    a = dr.safe_sqrt(0.5 * (ab + t))
    two_ac = 2.0 * a * c
    # (each quotient 1 where its denominator is 0: at grazing for η = 1, κ = 0, and
    # at the normal for η = κ = 0; the other operand of the select never divides by 0,
    # so that no derivative is inf times 0)
    den = ab + c2 + two_ac
    r_s = dr.select(den > 0.0, (ab + c2 - two_ac) / dr.select(den > 0.0, den, 1.0), 1.0)
    u, v = ab * c2 + s2 * s2, two_ac * s2
    r_p = r_s * dr.select(u + v > 0.0, (u - v) / dr.select(u + v > 0.0, u + v, 1.0), 1.0)
    # (>= 0: where the index is that of the outside, η = 1 and κ = 0, the
    # differences above cancel to a few ulps either side of 0)
    return dr.fmax(0.5 * (r_s + r_p), 0.0)


def dielectric(eta, c):
    """The exact reflectance of a dielectric interface of relative index η
    (> 0) for light arriving from outside at cos c (clamped to [0, 1]): 1
    beyond the critical angle (η < 1)."""
    c = dr.fmin(dr.fmax(c, 0.0), 1.0)
    s2_t = (1.0 - c * c) / (eta * eta)                  # sin² of the refracted ray
    c_t = dr.sqrt(dr.fmax(1.0 - s2_t, 0.0))
    r_s = (c - eta * c_t) / dr.fmax(c + eta * c_t, TINY)
    r_p = (eta * c - c_t) / dr.fmax(eta * c + c_t, TINY)
    return dr.select(s2_t < 1.0, 0.5 * (r_s * r_s + r_p * r_p), 1.0)


def f82(f0, tint, c):
    """Hoffman's F82-tint: Schlick's F0 with the reflectance at c̄ = 1/7 set to
    ``tint`` times Schlick's there (``tint`` 1: Schlick's curve); kept >= 0."""
    m = 1.0 - F82_COS
    a = schlick(f0, F82_COS) * (1.0 - tint) / (F82_COS * m ** 6)
    c = dr.fmin(dr.fmax(c, 0.0), 1.0)
    m = 1.0 - c
    m2 = m * m
    return dr.fmax(schlick(f0, c) - a * (c * m2 * m2 * m2), 0.0)


# ----------------------------------------------------------------------------
#  Hemispherical averages: the Fresnel factor of multiple scattering
# ----------------------------------------------------------------------------
#
# F_avg = 2 ∫ F(μ) μ dμ over μ in [0, 1], the cosine-weighted average of F over
# the hemisphere: the reflectance of a bounce between facets whose directions are
# spread over the hemisphere (Kulla & Conty, "Revisiting Physically Based Shading
# at Imageworks", SIGGRAPH 2017 course, their F_avg). Schlick's is
# F0 + (1 - F0)/21 (2 ∫ (1 - μ)^5 μ dμ = 1/21); F82-tint's subtracts
# a · 2 ∫ μ² (1 - μ)^6 dμ = a/126; the exact forms are integrated by
# Gauss-Legendre (AVERAGE_NODES nodes in μ, traced per lane: textured or
# spectral indices and their gradients go through).

AVERAGE_NODES = 24


def _legendre():
    import numpy as np
    x, w = np.polynomial.legendre.leggauss(AVERAGE_NODES)
    return [float(v) for v in 0.5 * (x + 1.0)], [float(v) for v in 0.5 * w]


_MU, _W = _legendre()


def average(F, lo=0.0):
    """2 ∫ F(μ) μ dμ over [lo, 1] of a Fresnel form F(μ) (a callable of the
    cosine), by Gauss-Legendre quadrature; from lo > 0 in t, μ = lo + (1 - lo) t²,
    which smooths a square-root edge at lo (the dielectric's critical angle)."""
    if type(lo) is float and lo == 0.0:
        return sum((F(mu) * (2.0 * w * mu) for mu, w in zip(_MU, _W)), 0.0)
    total, span = 0.0, 1.0 - lo
    for t, w in zip(_MU, _W):
        x = lo + span * (t * t)
        total = total + F(x) * (2.0 * w * x * span * 2.0 * t)
    return total


def conductor_average(eta, kappa):
    """F_avg of :func:`conductor` (quadrature; within 1e-6 of a fine trapezoid rule
    for gold's and aluminium's indices)."""
    return average(lambda c: conductor(eta, kappa, c))


def dielectric_average(eta):
    """F_avg of :func:`dielectric`: for η < 1 the part beyond the critical
    angle, cos θ < μ_c = √(1 - η²), reflects all (μ_c² of the average) and the
    rest is integrated from μ_c, so that the quadrature never straddles the kink."""
    mu_c2 = dr.fmax(1.0 - eta * eta, 0.0)
    return mu_c2 + average(lambda c: dielectric(eta, c), dr.safe_sqrt(mu_c2))


def schlick_average(f0):
    """Schlick's F_avg = F0 + (1 - F0)/21 (exact)."""
    return f0 + (1.0 - f0) * (1.0 / 21.0)


def f82_average(f0, tint):
    """F82-tint's F_avg = F0 + (1 - F0)/21 - a/126 (exact, a as in :func:`f82`;
    without :func:`f82`'s clamp at 0, which a tint in [0, 1] never reaches)."""
    m = 1.0 - F82_COS
    a = schlick(f0, F82_COS) * (1.0 - tint) / (F82_COS * m ** 6)
    return schlick_average(f0) - a * (1.0 / 126.0)


def schlick_equivalent(f_avg):
    """The F0 whose Schlick curve has the hemispherical average ``f_avg``,
    (21 F_avg - 1)/20, clamped to [0, 1]: the coordinate at which the random
    walk's tables (tabulated with Schlick's F at every bounce) are read for
    another Fresnel form (Schlick's own F0 maps to itself)."""
    return dr.fmin(dr.fmax((21.0 * f_avg - 1.0) * (1.0 / 20.0), 0.0), 1.0)
