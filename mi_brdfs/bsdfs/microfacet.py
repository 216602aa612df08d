"""Microfacet building blocks from the lecture, as pure Dr.Jit functions.

Inputs are local directions (shading frame: n = +z), or cosines with the
normal, and the roughness rho (called ``alpha`` in the plugins)::

  D, distribution   Blinn   (n·h)^(2/rho² - 2) / (pi rho²)
                    Beckmann exp(((n·h)² - 1) / ((n·h)² rho²)) / (pi rho² (n·h)^4)
                    GGX     rho² / (pi (clamp(n·h)² (rho² - 1) + 1)²)
  F, Fresnel        Schlick F0 + (1 - F0) (1 - clamp(w_r·h))^5
  G, geometry       Cook-Torrance (V-cavity)
                        min(1, 2(h·n)(w_r·n)/(w_r·h), 2(h·n)(d·n)/(w_r·h))
                    Smith   G1(w_r) G1(d), with for GGX the lecture's
                        g_GGX = 2 / (1 + sqrt(1 + rho² (1 - c²)/c²)),
                    for Beckmann the Smith G1 (Walter et al. 2007,
                    "Microfacet models for refraction through rough surfaces")
                        a = c / (rho sqrt(1 - c²)),  G1 = 2 / (1 + erf(a) + exp(-a²)/(a sqrt(pi))),
                    as a rational function of a fitted to it within 5.1e-6
                    (:func:`g1_beckmann_over_cos`),
                    and for Blinn the Smith G1 of the Blinn distribution itself,
                        G1(v) = cos θ_v / ∫ max(0, v·m) D(m) dm,
                    the function that makes the visible normals of D integrate
                    to 1 (Heitz 2014, "Understanding the masking-shadowing
                    function"), tabulated by quadrature (:data:`G1_BLINN`).
                    Walter's mapping of Blinn onto Beckmann's G1 is its small-rho
                    limit; at rho = 1 it overestimates G1 (0.87 against 0.67 at
                    60°) and the albedo exceeded 1 (1.30 at 89°).

**Anisotropic roughness** (Beckmann and GGX): ``alpha`` is then a pair
(α_u, α_v), the roughness along the tangent s (local x) and the bitangent t
(local y), as Mitsuba's ``roughconductor`` takes them. D is the distribution
stretched by (α_u, α_v) (Walter et al. 2007, eqs. 28 and 33 with the slope
divided per axis), Smith's G1 that of the roughness projected on the
direction's azimuth, α(φ) = sqrt(α_u² cos²φ + α_v² sin²φ) (Heitz 2014,
section 5.3), and the visible normals are sampled in the configuration
stretched to α = 1 (Heitz 2018). One roughness (a Float) is the isotropic
case, traced exactly as before: the functions branch on the Python type of
``alpha`` when a call is traced, so an isotropic plugin never pays for
anisotropy.

Scale-safe: every function is exact, finite and NaN-free, values and
gradients, for directions down to cos θ = 1e-30 and exactly 0 and for
``alpha >= ALPHA_MIN``. The half vector is normalised after scaling by 2^62
(``|wi + wo|²`` underflows below cos θ ~ 1e-19), and the Smith
forms are written as ratios that need no tan² or 1/cos (G1 -> 0 at grazing).
"""
from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from . import powercos
from .grid import Axis, Grid

ALPHA_MIN = 1e-4      # smallest roughness used (alpha = 0 is clamped here, as Mitsuba does)
# Largest roughness used: a larger alpha (up to the largest float32) is clamped
# here. The single-scattering lobe is then at its limit, no reflection: its
# albedo is below 3.3e-7 at every incidence up to 89.9° for every D x G
# (tests/bsdfs/test_cook_torrance.py::test_roughness_far_end), while alpha² stays
# far from float32's overflow.
ALPHA_MAX = 1e6
# The same for each axis of an anisotropic roughness: with the other axis near
# 1, the derivatives of a sample's weight overflow float32 from about 1e6 on
# (measured: finite up to 1e5, infinite at 1e6 against alpha_v = 0.3). At 1e4
# on both axes the lobe reflects less than 4e-5 of the light up to 89°
# (tests/bsdfs/test_cook_torrance.py::test_roughness_far_end).
ALPHA_MAX_ANISOTROPIC = 1e4
TINY = 1e-18          # keeps squared quantities away from 0 (TINY² is still a normal float32)
COS_FLOOR = 1e-12     # the V-cavity 1/(4 cos θ_i) stops growing below this cosine
BECKMANN_CUTOFF = 100.0   # tan²/rho² beyond which the Beckmann D is 0 (exp(-100) < float32 min)
DEN_MIN = 1e-19       # a denominator's floor whose square (the division's derivative) is normal

DISTRIBUTIONS = ("blinn", "beckmann", "ggx")
GEOMETRIES = ("cook_torrance", "smith")


H_SCALE = 2.0 ** 62         # wi + wo is scaled by this before |.|² (exact: a power of 2)
H_NORM2_MIN = 1e-30         # |h|² floor: 0 only for wi = -wo (|wi + wo| < 2e-34)


def half_vector(wi, wo):
    """normalize(wi + wo), exact for a length of wi + wo from 2e-34 to 2: the
    sum is scaled by 2^62 first, so that its squared length neither underflows
    (two directions above the horizon, cos θ > 1e-20, have a sum longer than 2e-20) nor
    overflows. The zero vector (wo = -wi) stays 0, with no NaN in values or
    derivatives."""
    x, y, z = (wi.x + wo.x) * H_SCALE, (wi.y + wo.y) * H_SCALE, (wi.z + wo.z) * H_SCALE
    n = dr.rsqrt(dr.fmax(dr.fma(x, x, dr.fma(y, y, z * z)), H_NORM2_MIN))
    return mi.Vector3f(x * n, y * n, z * n)


def anisotropic(alpha) -> bool:
    """True for a roughness pair (α_u, α_v), False for one roughness."""
    return type(alpha) is tuple


def pair(alpha):
    """(α_u, α_v) of a pair, (α, α) of one roughness (the same Float twice: an
    isotropic call traces the same operations as before)."""
    return alpha if type(alpha) is tuple else (alpha, alpha)


def projected_sin2(v, alpha):
    """α(φ)² sin²θ of a local direction: (α_u v.x)² + (α_v v.y)², the squared
    length of its stretched tangential part (α² (x² + y²) for one roughness)."""
    if type(alpha) is tuple:
        return dr.square(alpha[0] * v.x) + dr.square(alpha[1] * v.y)
    return dr.square(alpha) * (dr.square(v.x) + dr.square(v.y))


def sin_theta(v):
    """sin θ of a unit local direction, from x and y (exact near the normal)."""
    return dr.safe_sqrt(dr.square(v.x) + dr.square(v.y))     # safe: finite derivative at 0


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
    if type(alpha) is tuple:
        return _d_beckmann_anisotropic(m, *alpha)
    cos2, sin2 = _cos2_sin2(m)
    a2 = dr.square(alpha)
    # Where exp(-tan²/rho²) < exp(-BECKMANN_CUTOFF) (0 in float32), D is 0; the
    # formula is then evaluated on a benign stand-in so that no 0/0 reaches the
    # gradients through the unselected branch.
    valid = (m.z > 0) & (sin2 < BECKMANN_CUTOFF * cos2 * a2)
    q = 1.0 / (dr.select(valid, cos2, 1.0) * a2)               # 1 / (cos² rho²)
    d = dr.exp(-dr.select(valid, sin2, 0.0) * q) * (q * q * a2 * dr.inv_pi)
    return dr.select(valid, d, 0.0)


def _d_beckmann_anisotropic(m, ax, ay):
    """exp(-(x²/α_u² + y²/α_v²)/z²) / (π α_u α_v z⁴), 0 where the exponent
    passes BECKMANN_CUTOFF (with a benign stand-in there, as the isotropic one)."""
    cos2 = dr.square(m.z)
    slope2 = dr.square(m.x / ax) + dr.square(m.y / ay)          # tan²θ_m · (stretch)
    valid = (m.z > 0) & (slope2 < BECKMANN_CUTOFF * cos2)
    c2 = dr.select(valid, cos2, 1.0)
    d = dr.exp(-dr.select(valid, slope2, 0.0) / c2) / (dr.pi * ax * ay * dr.square(c2))
    return dr.select(valid, d, 0.0)


def d_ggx(m, alpha):
    if type(alpha) is tuple:
        return _d_ggx_anisotropic(m, *alpha)
    cos2, sin2 = _cos2_sin2(m)
    a2 = dr.square(alpha)
    up = m.z > 0
    # clamp(n·h)² (rho² - 1) + 1, written as sin² + cos² rho² for float32 accuracy;
    # 0 only for the zero vector (the half vector of wo = -wi): a stand-in then
    d = a2 / (dr.pi * dr.square(dr.select(up, sin2 + cos2 * a2, 1.0)))
    return dr.select(up, d, 0.0)


def _d_ggx_anisotropic(m, ax, ay):
    """1 / (π α_u α_v (x²/α_u² + y²/α_v² + z²)²) above the horizon."""
    up = m.z > 0
    t = dr.square(m.x / ax) + dr.square(m.y / ay) + dr.square(m.z)
    d = 1.0 / (dr.pi * ax * ay * dr.square(dr.select(up, t, 1.0)))
    return dr.select(up, d, 0.0)


D = {"blinn": d_blinn, "beckmann": d_beckmann, "ggx": d_ggx}


# ----------------------------------------------------------------------------
#  F and G
# ----------------------------------------------------------------------------

def fresnel_schlick(f0, cos_theta):
    if type(f0) is float and f0 == 1.0:            # the number 1: F = 1 at every angle
        return 1.0
    m = 1.0 - dr.fmin(dr.fmax(cos_theta, 0.0), 1.0)
    m2 = m * m
    return f0 + (1.0 - f0) * (m2 * m2 * m)


def g_cook_torrance(cos_h, cos_i, cos_o, i_dot_h):
    """The lecture's microfacet (V-cavity) term; cos_i is w_r·n, cos_o is d·n."""
    denom = dr.fmax(i_dot_h, TINY)
    g = dr.minimum(1.0, dr.minimum(2.0 * cos_h * cos_i / denom,
                                   2.0 * cos_h * cos_o / denom))
    return dr.fmax(g, 0.0)


def g1_ggx_over_cos(v, alpha):
    """G1(v) / cos θ_v for GGX: the lecture's 2/(1 + sqrt(1 + rho² tan²θ)) times
    cos/cos = 2 / (c + sqrt(c² + rho² sin²θ)): no tan², finite at c = 0."""
    c = dr.fmax(v.z, 0.0)
    if type(alpha) is tuple:                       # the projected roughness α(φ)
        denom = c + dr.sqrt(dr.fma(c, c, projected_sin2(v, alpha)))
    else:
        denom = c + dr.sqrt(dr.fma(c, c, dr.square(alpha) * dr.fma(v.x, v.x, v.y * v.y)))
    # >= alpha >= ALPHA_MIN above the surface; below TINY only straight down or
    # for the zero vector, where G1 = G1/c · c is 0 anyway
    return 2.0 / dr.fmax(denom, TINY)


# Beckmann's Smith G1 = 2 / (1 + erf(a) + exp(-a²)/(a sqrt(pi))) as a P(a) / Q(a),
# a rational function fitted to it over a in [0, inf) (relative minimax, float64):
# P of degree 5 with P(0) = 2 sqrt(pi) (the slope at a = 0), Q of degree 6 with
# Q(0) = 1 and the leading coefficient of P (G1 -> 1). Every coefficient is
# positive: no cancellation, Q > 0.
BECKMANN_P = (2.0 * math.sqrt(math.pi), 1.9594363629708278, 1.8768557662038479,
              1.1668724016110976, 0.13398800624993143, 0.5547577466057122)
BECKMANN_Q = (1.0, 2.3248140898992533, 2.5176469350385013, 1.7605286964621758,
              1.1774410503340418, 0.133677665243859, 0.5547577466057122)


def _homogeneous(coefficients, c, r):
    """sum_k coefficients[k] c^k r^(n - k) (n the degree), by Horner in c."""
    acc, r_k = coefficients[-1], r
    for k in range(len(coefficients) - 2, -1, -1):
        acc = dr.fma(acc, c, coefficients[k] * r_k)
        if k:
            r_k = r_k * r
    return acc


def g1_beckmann_over_cos(v, alpha):
    """G1(v) / cos θ_v for Beckmann. With a = c/(rho s) (c = cos θ, s = sin θ),
    G1 = a P(a)/Q(a) (:data:`BECKMANN_P`, :data:`BECKMANN_Q`), so
    G1/c = s^5 P(c'/s) / (rho s^6 Q(c'/s)), c' = c/rho: a ratio of homogeneous
    polynomials in (c', s), with no exp and no clamp; it tends to 1/c at the
    normal (G1 = 1) and to 2 sqrt(pi)/(rho s) at the horizon. (In c' and s, not
    in c and rho s: the denominator then stays above ~0.07/rho^5, so that
    float32 derivatives of the division, which square it, do not overflow; the
    floor DEN_MIN only catches the zero vector, and rho > ~3000.) Against the
    exact erf form (float64), the fit's relative error is at most 5.1e-6 for
    every a; in float32, 5.5e-6 (tests/bsdfs/test_cook_torrance.py::
    test_beckmann_g1). Mitsuba's own fit (its ``roughconductor``) is within
    3.5e-3. Anisotropic: the same with the roughness projected on v's azimuth,
    α(φ) = sqrt(α_u² cos²φ + α_v² sin²φ) (α_u along the normal, where G1 = 1)."""
    if type(alpha) is tuple:
        s = sin_theta(v)
        alpha = dr.select(s > 0, dr.sqrt(projected_sin2(v, alpha)) / dr.select(s > 0, s, 1.0),
                          alpha[0])
    c = dr.fmax(v.z, 0.0) * (1.0 / alpha)               # cos θ / rho
    s = sin_theta(v)
    return _homogeneous(BECKMANN_P, c, s) / dr.fmax(alpha * _homogeneous(BECKMANN_Q, c, s),
                                                    DEN_MIN)


# --- the Smith G1 of the Blinn distribution, tabulated -----------------------

def _blinn_projected_area(mu: np.ndarray, rho: float, nodes) -> np.ndarray:
    """∫ max(0, v·m) D_blinn(m) dm for directions v at cos θ = mu (float64, NumPy).

    θ_m through tan θ_m = rho x, x = s/(1 - s), Gauss-Legendre in s (the D
    lobe is ~rho wide); the azimuth integral of max(0, a cos φ + b) is
    2 (sqrt(a² - b²) + b acos(-b/a)) for a > b, else 2 pi b.
    """
    xs, ws = nodes
    s, w = 0.5 * (xs + 1.0), 0.5 * ws
    x, dx = s / (1.0 - s), w / (1.0 - s) ** 2
    theta_m = np.arctan(rho * x)
    d_theta = rho * dx / (1.0 + (rho * x) ** 2)
    e = 2.0 / rho ** 2 - 2.0
    d = np.exp(-0.5 * e * np.log1p((rho * x) ** 2)) / (np.pi * rho ** 2)   # cos^e θ_m
    sin_v = np.sqrt(np.maximum(1.0 - mu ** 2, 0.0))[:, None]
    a = sin_v * np.sin(theta_m)[None, :]
    b = mu[:, None] * np.cos(theta_m)[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        ring = np.where(a > b, 2.0 * (np.sqrt(np.maximum(a * a - b * b, 0.0))
                                      + b * np.arccos(np.clip(-b / np.where(a > 0, a, 1.0), -1, 1))),
                        2.0 * np.pi * b)
    return ring @ (d * np.sin(theta_m) * d_theta)


def _g1_beckmann_np(a: np.ndarray) -> np.ndarray:
    from math import erf
    a = np.asarray(a, dtype=np.float64)
    erf_a = np.array([erf(v) for v in a.ravel()]).reshape(a.shape)
    return 2.0 * a * math.sqrt(math.pi) / (a * math.sqrt(math.pi) * (1.0 + erf_a) + np.exp(-a * a))


# G1 of the Blinn distribution over (t, rho), t = a / (1 + a), a = cos θ/(rho sin θ):
# t = 0 is the horizon, t = 1 the normal. rho = 0 holds the limit, Beckmann's G1.
G1_BLINN_AXES = (Axis("t", 0.0, 1.0, 65), Axis("rho", 0.0, 1.0, 41))


def _g1_blinn_table() -> np.ndarray:
    t = G1_BLINN_AXES[0].nodes()
    a = t[:-1] / (1.0 - t[:-1])
    values = np.ones((len(t), G1_BLINN_AXES[1].n))
    values[:-1, 0] = _g1_beckmann_np(a)
    nodes = np.polynomial.legendre.leggauss(512)         # ~10 ms, once
    for j, rho in enumerate(G1_BLINN_AXES[1].nodes()[1:], start=1):
        mu = a * rho / np.sqrt(1.0 + (a * rho) ** 2)
        values[:-1, j] = np.minimum(mu / _blinn_projected_area(mu, rho, nodes), 1.0)
    values[0, :] = 0.0
    return values


G1_BLINN_VALUES = _g1_blinn_table()
_g1_blinn_grids: dict[str, Grid] = {}


def g1_blinn_grid() -> Grid:
    """The table of the Blinn G1 for the active variant (a plugin that uses it
    holds its ``data`` as a member, so that frozen functions see it)."""
    variant = mi.variant()
    if variant not in _g1_blinn_grids:
        _g1_blinn_grids[variant] = Grid(G1_BLINN_AXES, G1_BLINN_VALUES)
    return _g1_blinn_grids[variant]


def g1_blinn_over_cos(v, alpha):
    """G1(v) / cos θ_v for the Blinn distribution, from :data:`G1_BLINN_VALUES`.
    Near the horizon G1 ~ c · g'(0), so G1/c is taken from the first cell's
    slope there (no division by a tiny c)."""
    grid = g1_blinn_grid()
    c = dr.fmax(v.z, 0.0)
    rs = dr.fmax(alpha * sin_theta(v), TINY)
    t = c / (c + rs)                                   # a/(1 + a), a = c/(rho s)
    g1 = grid(t, dr.fmin(alpha, 1.0))
    # In the first cell g1 is linear in t: g1/c = (g1/t)(t/c) = (g1/t)/(c + rs)
    h = 1.0 / (G1_BLINN_AXES[0].n - 1)
    first = t < h
    g1_over_t = dr.select(first, grid(mi.Float(h), dr.fmin(alpha, 1.0)) / h,
                          g1 / dr.select(first, 1.0, t))
    return g1_over_t / (c + rs)


G1_OVER_COS = {"blinn": g1_blinn_over_cos, "beckmann": g1_beckmann_over_cos,
               "ggx": g1_ggx_over_cos}


def g1(distribution: str, v, alpha):
    """Smith G1(v) of the distribution (0 below the horizon)."""
    return G1_OVER_COS[distribution](v, alpha) * dr.fmax(v.z, 0.0)


# ----------------------------------------------------------------------------
#  Sampling microfacet normals
# ----------------------------------------------------------------------------
#
# Visible normals (Heitz 2018, "Sampling the GGX distribution of visible
# normals"): m with density D_wi(m) = G1(wi)/cos θ_i · max(0, wi·m) D(m). GGX
# by Dupuy & Benyoub's spherical caps (2023, "Sampling visible GGX normals with
# spherical caps"); Beckmann by Mitsuba's MicrofacetDistribution (Jakob's
# inversion of the visible-slope cdf). The density is ours for both: with the
# exact, scale-safe G1/cos above, so sampler and pdf agree at any angle
# (cook_torrance.lobe()). The full distribution: m with density D(m) cos θ_m;
# Blinn always.

def _normalize(x, y, z):
    """(x, y, z) / |(x, y, z)| for a vector whose largest component is not tiny
    (|v| >= ~1e-19)."""
    n = dr.rsqrt(dr.fmax(dr.fma(x, x, dr.fma(y, y, z * z)), TINY * TINY))
    return x * n, y * n, z * n


def sample_ggx_visible(wi, sample2, alpha):
    """A GGX visible normal for the viewer wi (spherical caps)."""
    ax, ay = pair(alpha)
    # the viewer in the hemisphere configuration (roughness 1)
    vx, vy, vz = _normalize(ax * wi.x, ay * wi.y, dr.fmax(wi.z, 0.0))
    z = dr.fma(1.0 - sample2.y, 1.0 + vz, -vz)            # uniform on the spherical cap
    sin_t = dr.safe_sqrt(1.0 - z * z)
    s, c = dr.sincos(dr.two_pi * sample2.x)
    # back to the ellipsoid configuration
    return mi.Vector3f(*_normalize(ax * dr.fma(c, sin_t, vx), ay * dr.fma(s, sin_t, vy),
                                   dr.fmax(z + vz, 0.0)))


def sample_full(distribution: str, sample2, alpha):
    """m with density D(m) cos θ_m: tan²θ_m = rho² u/(1 - u) (GGX),
    -rho² log(1 - u) (Beckmann); Blinn through powercos. Anisotropic: the
    azimuth of the stretched slope, tan φ = (α_v/α_u) tan(2π u_y), and the
    roughness projected on it (Walter et al. 2007's sampling with the
    slope distribution stretched per axis)."""
    if distribution == "blinn":
        return sample_blinn(sample2, alpha)
    u = dr.fmin(sample2.x, 1.0 - 2.0**-24)
    if type(alpha) is tuple:
        ax, ay = alpha
        s0, c0 = dr.sincos(dr.two_pi * sample2.y)          # the unstretched slope's azimuth
        sx, sy = ax * c0, ay * s0                           # stretched: azimuth of m
        r = dr.sqrt(dr.fma(sx, sx, sy * sy))
        c, s = sx / r, sy / r
        # α(φ)² = 1 / (cos²φ/α_u² + sin²φ/α_v²) along m's azimuth φ
        a2 = 1.0 / (dr.square(c / ax) + dr.square(s / ay))
    else:
        a2 = dr.square(alpha)
        s, c = dr.sincos(dr.two_pi * sample2.y)
    if distribution == "ggx":
        tan2 = a2 * u / (1.0 - u)
    else:
        tan2 = -a2 * dr.log(1.0 - u)
    cos_t = dr.rsqrt(1.0 + tan2)
    sin_t = dr.safe_sqrt(tan2) * cos_t
    return mi.Vector3f(c * sin_t, s * sin_t, cos_t)


def sample_visible(distribution: str, wi, sample2, alpha):
    """A visible normal of GGX or Beckmann for the viewer wi."""
    if distribution == "ggx":
        return sample_ggx_visible(wi, sample2, alpha)
    ax, ay = pair(alpha)
    m, _ = mi.MicrofacetDistribution(mi.MicrofacetType.Beckmann, ax, ay, True).sample(wi, sample2)
    # Mitsuba's Beckmann sampler fails at a corner of its domain (NaN for
    # u = (0, 0) at normal incidence): the zero vector instead, whose
    # "reflection" -wi is below the horizon (a discarded sample), and no NaN
    # in the other lanes' derivatives.
    return dr.select(dr.isfinite(m.x + m.y + m.z), m, 0.0)


# ----------------------------------------------------------------------------
#  Sampling the Blinn distribution (its D(m) cos θ_m is a power-cosine lobe)
# ----------------------------------------------------------------------------

def sample_blinn(sample2, alpha):
    """A microfacet normal with density D_blinn(m) cos(theta_m), which is the
    power-cosine lobe of exponent 2/rho² - 1 about the normal."""
    return powercos.sample(sample2, 2.0 / dr.square(alpha) - 1.0)
