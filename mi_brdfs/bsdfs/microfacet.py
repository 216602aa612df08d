"""Microfacet building blocks from the lecture, as pure Dr.Jit functions.

Inputs are local directions (shading frame: n = +z), or cosines with the
normal, and the roughness rho (called ``alpha`` in the plugins). Every function is NaN- and
Inf-free for cosines in [-1, 1] and ``alpha >= ALPHA_MIN`` (values and
gradients): degenerate denominators are kept away from zero by ``TINY``.

  D, distribution   Blinn   (n·h)^(2/rho² - 2) / (pi rho²)
                    Beckmann exp(((n·h)² - 1) / ((n·h)² rho²)) / (pi rho² (n·h)^4)
                    GGX     rho² / (pi (clamp(n·h)² (rho² - 1) + 1)²)
  F, Fresnel        Schlick F0 + (1 - F0) (1 - clamp(w_r·h))^5
  G, geometry       Cook-Torrance (V-cavity)
                        min(1, 2(h·n)(w_r·n)/(w_r·h), 2(h·n)(d·n)/(w_r·h))
                    Smith   G1(w_r) G1(d), with the lecture's
                        g_GGX = 2 / (1 + sqrt(1 + rho² (1 - c²)/c²))
                    and the exact Smith G1 of Beckmann (used for Blinn too)
                        a = c / (rho sqrt(1 - c²)),  G1 = 2 / (1 + erf(a) + exp(-a²)/(a sqrt(pi)))
"""
from __future__ import annotations

import drjit as dr

from . import powercos

ALPHA_MIN = 1e-4      # smallest roughness used (alpha = 0 is clamped here, as Mitsuba does)
TINY = 1e-18          # keeps squared cosines away from 0 (TINY² is still a normal float32)
BECKMANN_CUTOFF = 100.0   # tan²/rho² beyond which the Beckmann D is 0 (exp(-100) < float32 min)

DISTRIBUTIONS = ("blinn", "beckmann", "ggx")
GEOMETRIES = ("cook_torrance", "smith")


def half_vector(wi, wo):
    """normalize(wi + wo); the zero vector when wi = -wo."""
    h = wi + wo
    return h * dr.rsqrt(dr.fmax(dr.squared_norm(h), TINY))


# ----------------------------------------------------------------------------
#  D: normal distributions (normalised: integral of D(h) cos(theta_h) = 1)
# ----------------------------------------------------------------------------

def _cos2_sin2(v):
    """cos² and sin² of a local direction's polar angle, sin² from x and y
    (not 1 - cos², which cancels catastrophically in float32 near the normal)."""
    return dr.square(v.z), dr.square(v.x) + dr.square(v.y)


def d_blinn(m, alpha):
    # cos^e with e = 2/rho² - 2, through powercos: at small rho the exponent is
    # huge (2e8 at ALPHA_MIN) and cos(theta_m) must not be rounded to 1 first.
    cos_t, versin = powercos.cos_versin_z(m)
    e = 2.0 / dr.square(alpha) - 2.0                     # the Blinn exponent
    return powercos.pow_cos(cos_t, versin, e) / (dr.pi * dr.square(alpha))


def d_beckmann(m, alpha):
    cos2, sin2 = _cos2_sin2(m)
    a2 = dr.square(alpha)
    # Where exp(-tan²/rho²) < exp(-BECKMANN_CUTOFF) (0 in float32), D is 0; the
    # formula is then evaluated on a benign stand-in so that no 0/0 reaches the
    # gradients through the unselected branch.
    valid = (m.z > 0) & (sin2 < BECKMANN_CUTOFF * cos2 * a2)
    cos2 = dr.select(valid, cos2, 1.0)
    sin2 = dr.select(valid, sin2, 0.0)
    d = dr.exp(-sin2 / (cos2 * a2)) / (dr.pi * a2 * dr.square(cos2))
    return dr.select(valid, d, 0.0)


def d_ggx(m, alpha):
    cos2, sin2 = _cos2_sin2(m)
    a2 = dr.square(alpha)
    # clamp(n·h)² (rho² - 1) + 1, written as sin² + cos² rho² for float32 accuracy
    d = a2 / (dr.pi * dr.square(sin2 + cos2 * a2))
    return dr.select(m.z > 0, d, 0.0)


D = {"blinn": d_blinn, "beckmann": d_beckmann, "ggx": d_ggx}


# ----------------------------------------------------------------------------
#  F and G
# ----------------------------------------------------------------------------

def fresnel_schlick(f0, cos_theta):
    return f0 + (1.0 - f0) * dr.power(1.0 - dr.clip(cos_theta, 0.0, 1.0), 5.0)


def g_cook_torrance(cos_h, cos_i, cos_o, i_dot_h):
    """The lecture's microfacet (V-cavity) term; cos_i is w_r·n, cos_o is d·n."""
    denom = dr.fmax(i_dot_h, TINY)
    g = dr.minimum(1.0, dr.minimum(2.0 * cos_h * cos_i / denom,
                                   2.0 * cos_h * cos_o / denom))
    return dr.fmax(g, 0.0)


def g1_ggx(v, alpha):
    cos2, sin2 = _cos2_sin2(v)
    tan2 = sin2 / dr.fmax(cos2, TINY)
    g = 2.0 / (1.0 + dr.sqrt(1.0 + dr.square(alpha) * tan2))
    return dr.select(v.z > 0, g, 0.0)


def g1_beckmann(v, alpha):
    cos2, sin2 = _cos2_sin2(v)
    a = dr.fmax(dr.sqrt(cos2 / dr.fmax(sin2, TINY)) / alpha, 1e-6)   # 1 / (rho tan)
    g = 2.0 / (1.0 + dr.erf(a) + dr.exp(-dr.square(a)) / (a * dr.sqrt(dr.pi)))
    return dr.select(v.z > 0, g, 0.0)


G1 = {"blinn": g1_beckmann, "beckmann": g1_beckmann, "ggx": g1_ggx}


def g_smith(distribution, wi, wo, alpha):
    g1 = G1[distribution]
    return g1(wi, alpha) * g1(wo, alpha)


# ----------------------------------------------------------------------------
#  Sampling the Blinn distribution (Mitsuba samples Beckmann and GGX itself)
# ----------------------------------------------------------------------------

def sample_blinn(sample2, alpha):
    """A microfacet normal with density D_blinn(m) cos(theta_m), which is the
    power-cosine lobe of exponent 2/rho² - 1 about the normal."""
    return powercos.sample(sample2, 2.0 / dr.square(alpha) - 1.0)


def pdf_blinn(m, alpha):
    """Density of sample_blinn() over microfacet normals."""
    cos_t, versin = powercos.cos_versin_z(m)
    return powercos.pdf(cos_t, versin, 2.0 / dr.square(alpha) - 1.0)
