"""Microfacet distributions as values, and the lecture's geometric term.

A :class:`Microfacet` holds one distribution of microfacet normals, its type
and its roughness (one α, or α_u along the tangent s and α_v along the
bitangent t), and answers what a microfacet BRDF asks of it, as Mitsuba's
``MicrofacetDistribution`` and pbrt's ``TrowbridgeReitzDistribution`` do:

==================  ==========================================================
``D(m)``            the density of normals (∫ D(m) cos θ_m dm = 1)
``G1(v)``           Smith's masking of direction v (``G1_over_cos``: G1/cos θ_v)
``G(wi, wo)``       Smith's masking-shadowing: G1(ω_i) G1(ω_o), or the
                    height-correlated 1 / (1 + Λ(ω_i) + Λ(ω_o))
``sample(wi, u)``   a normal m, visible from ω_i or from the whole distribution
``pdf(wi, m)``      its density
``reflection_pdf``  the density of the direction reflected about that normal
==================  ==========================================================

so that a plugin reads like its formula: ``D * F * G / (4 cos θ_i)``.

The three distributions, with ρ the roughness (α in the plugins)::

  Blinn     (n·h)^(2/ρ² - 2) / (π ρ²)
  Beckmann  exp(((n·h)² - 1) / ((n·h)² ρ²)) / (π ρ² (n·h)^4)
  GGX       ρ² / (π (clamp(n·h)² (ρ² - 1) + 1)²)

and their Smith G1: for GGX the lecture's g_GGX = 2 / (1 + sqrt(1 + ρ²
(1 - c²)/c²)); for Beckmann (Walter et al. 2007, "Microfacet models for
refraction through rough surfaces") a = c / (ρ sqrt(1 - c²)), G1 = 2 / (1 +
erf(a) + exp(-a²)/(a sqrt(π))), as a rational function of a fitted to it within
5.1e-6 (:data:`BECKMANN_P`); for Blinn the Smith G1 of the Blinn distribution
itself, G1(v) = cos θ_v / ∫ max(0, v·m) D(m) dm, the function that makes the
visible normals of D integrate to 1 (Heitz 2014, "Understanding the
masking-shadowing function"), tabulated by quadrature (:data:`G1_BLINN_VALUES`;
Walter's mapping of Blinn onto Beckmann's G1 is its small-ρ limit, which at ρ
= 1 overestimates G1, 0.87 against 0.67 at 60°, and let the albedo exceed 1).
Smith's Λ = 1/G1 - 1 for each, so the height-correlated G is
G1(ω_i) G1(ω_o) / (G1(ω_i) + G1(ω_o) - G1(ω_i) G1(ω_o)) (Heitz 2014, eq. 99).
The lecture's own G, the V-cavity term of Cook and Torrance, is no property
of a distribution: :func:`g_v_cavity`.

**Anisotropic roughness** (Beckmann and GGX): D is the distribution stretched
by (α_u, α_v) (Walter et al. 2007, eqs. 28 and 33 with the slope divided per
axis), G1 that of the roughness projected on the direction's azimuth, α(φ) =
sqrt(α_u² cos²φ + α_v² sin²φ) (Heitz 2014, section 5.3), and the visible
normals are sampled in the configuration stretched to α = 1 (Heitz 2018). An
isotropic value traces exactly the operations of one roughness: anisotropy is
decided when the value is made, never at a call site.

**Sampling.** Visible normals (Heitz 2018, "Sampling the GGX distribution of
visible normals"): m with density D_ωi(m) = G1(ω_i)/cos θ_i · max(0, ω_i·m)
D(m); GGX by Dupuy & Benyoub's spherical caps (2023), Beckmann by Mitsuba's
``MicrofacetDistribution`` (Jakob's inversion of the visible-slope cdf), each
with our own scale-safe density, so sampler and pdf agree at any angle. The
whole distribution: m with density D(m) cos θ_m (always for Blinn, a
power-cosine lobe: :mod:`.powercos`).

**Scale-safe**: every method is exact, finite and NaN-free, values and
gradients, for directions down to cos θ = 1e-30 and exactly 0 and for
roughness >= ``ALPHA_MIN``. The half vector is normalised after scaling by
2^62 (``|wi + wo|²`` underflows below cos θ ~ 1e-19), and the Smith forms are
ratios that need no tan² and no 1/cos (G1 -> 0 at grazing).
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
# (finite up to 1e5, infinite at 1e6 against alpha_v = 0.3). At 1e4 on both
# axes the lobe reflects less than 4e-5 of the light up to 89°
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


def dot(a, b):
    """a·b of two local directions, by fused multiply-adds."""
    return dr.fma(a.x, b.x, dr.fma(a.y, b.y, a.z * b.z))


def sin_theta(v):
    """sin θ of a unit local direction, from x and y (exact near the normal)."""
    return dr.safe_sqrt(dr.square(v.x) + dr.square(v.y))     # safe: finite derivative at 0


def _cos2_sin2(v):
    """cos² and sin² of a local direction's polar angle, sin² from x and y
    (not 1 - cos², which cancels catastrophically in float32 near the normal)."""
    return dr.square(v.z), dr.square(v.x) + dr.square(v.y)


def _normalize(x, y, z):
    """(x, y, z) / |(x, y, z)| for a vector whose largest component is not tiny
    (|v| >= ~1e-19)."""
    n = dr.rsqrt(dr.fmax(dr.fma(x, x, dr.fma(y, y, z * z)), TINY * TINY))
    return x * n, y * n, z * n


def g_v_cavity(h, wi, wo):
    """The lecture's microfacet G (Cook & Torrance's V-cavity):
    min(1, 2 (h·n)(ω_r·n)/(ω_r·h), 2 (h·n)(d·n)/(ω_r·h)), with ω_r = wi, d = wo."""
    denom = dr.fmax(dot(wi, h), TINY)
    g = dr.minimum(1.0, dr.minimum(2.0 * h.z * wi.z / denom, 2.0 * h.z * wo.z / denom))
    return dr.fmax(g, 0.0)


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


def erf_np(x: np.ndarray) -> np.ndarray:
    """erf of a NumPy array (Abramowitz & Stegun 7.1.26, within 1.5e-7), vectorised."""
    t = 1.0 / (1.0 + 0.3275911 * np.abs(x))
    poly = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027
                                                                          + t * 1.061405429))))
    return np.sign(x) * (1.0 - poly * np.exp(-x * x))


def _g1_beckmann_np(a: np.ndarray) -> np.ndarray:
    """Beckmann's Smith G1 at a = cos θ / (α sin θ), NumPy."""
    a = np.asarray(a, dtype=np.float64)
    return 2.0 * a * math.sqrt(math.pi) / (a * math.sqrt(math.pi) * (1.0 + erf_np(a)) + np.exp(-a * a))


def g1_np(kind: str, alpha: float, cos_theta, sin_theta) -> np.ndarray:
    """Smith's G1 of a direction (cos θ taken as |cos θ|) for ``kind`` "ggx" or
    "beckmann", NumPy (for tables made at load time)."""
    tan2 = (sin_theta / np.maximum(np.abs(cos_theta), 1e-300)) ** 2
    if kind == "ggx":
        return 2.0 / (1.0 + np.sqrt(1.0 + alpha * alpha * tan2))
    return _g1_beckmann_np(1.0 / np.maximum(alpha * np.sqrt(tan2), 1e-300))


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



# ----------------------------------------------------------------------------
#  The distribution
# ----------------------------------------------------------------------------

class Microfacet:
    """A microfacet distribution: ``kind`` ("blinn", "beckmann" or "ggx") and
    its roughness, one ``alpha`` or ``alpha`` along the tangent s (local x)
    with ``alpha_v`` along the bitangent t (local y). The roughness is a Float
    per lane, already clamped to the plugin's range. ``visible``: ``sample``
    draws the normals visible from ω_i (Beckmann and GGX; Blinn always samples
    the whole distribution). Made per call, at trace time: its fields are
    Python decisions and Dr.Jit values, and it holds nothing else."""

    __slots__ = ("kind", "alpha", "alpha_v", "visible")

    def __init__(self, kind: str, alpha, alpha_v=None, visible: bool = True):
        if kind not in DISTRIBUTIONS:
            raise ValueError(f"Microfacet: kind {kind!r}; valid: {', '.join(DISTRIBUTIONS)}")
        if kind == "blinn" and alpha_v is not None:
            raise ValueError("Microfacet: Blinn's distribution is isotropic (one alpha)")
        self.kind = kind
        self.alpha = alpha            # α, or α_u when alpha_v is given
        self.alpha_v = alpha_v        # None: isotropic
        self.visible = visible and kind != "blinn"

    @property
    def isotropic(self) -> bool:
        return self.alpha_v is None

    def _projected_sin2(self, v):
        """α(φ)² sin²θ of a local direction: (α_u v.x)² + (α_v v.y)², the squared
        length of its stretched tangential part."""
        return dr.square(self.alpha * v.x) + dr.square(self.alpha_v * v.y)

    # --- D ------------------------------------------------------------------------
    def D(self, m):
        """The density of normals at m (0 below the horizon)."""
        if self.kind == "ggx":
            return self._d_ggx(m)
        if self.kind == "beckmann":
            return self._d_beckmann(m)
        # cos^e with e = 2/ρ² - 2, through powercos: at small ρ the exponent is
        # huge (2e8 at ALPHA_MIN) and cos θ_m must not be rounded to 1 first.
        cos_t, versin = powercos.cos_versin_z(m)
        e = 2.0 / dr.square(self.alpha) - 2.0
        return powercos.pow_cos(cos_t, versin, e) / (dr.pi * dr.square(self.alpha))

    def _d_ggx(self, m):
        up = m.z > 0
        if self.isotropic:
            cos2, sin2 = _cos2_sin2(m)
            a2 = dr.square(self.alpha)
            # clamp(n·h)² (ρ² - 1) + 1, written as sin² + cos² ρ² for float32
            # accuracy; 0 only for the zero vector (the half vector of wo = -wi):
            # a stand-in then
            d = a2 / (dr.pi * dr.square(dr.select(up, sin2 + cos2 * a2, 1.0)))
        else:
            # 1 / (π α_u α_v (x²/α_u² + y²/α_v² + z²)²)
            ax, ay = self.alpha, self.alpha_v
            t = dr.square(m.x / ax) + dr.square(m.y / ay) + dr.square(m.z)
            d = 1.0 / (dr.pi * ax * ay * dr.square(dr.select(up, t, 1.0)))
        return dr.select(up, d, 0.0)

    def _d_beckmann(self, m):
        # Where exp(-tan²/ρ²) < exp(-BECKMANN_CUTOFF) (0 in float32), D is 0; the
        # formula is then evaluated on a benign stand-in so that no 0/0 reaches
        # the gradients through the unselected branch.
        if self.isotropic:
            cos2, sin2 = _cos2_sin2(m)
            a2 = dr.square(self.alpha)
            valid = (m.z > 0) & (sin2 < BECKMANN_CUTOFF * cos2 * a2)
            q = 1.0 / (dr.select(valid, cos2, 1.0) * a2)               # 1 / (cos² ρ²)
            d = dr.exp(-dr.select(valid, sin2, 0.0) * q) * (q * q * a2 * dr.inv_pi)
        else:
            # exp(-(x²/α_u² + y²/α_v²)/z²) / (π α_u α_v z⁴)
            ax, ay = self.alpha, self.alpha_v
            cos2 = dr.square(m.z)
            slope2 = dr.square(m.x / ax) + dr.square(m.y / ay)        # tan²θ_m, stretched
            valid = (m.z > 0) & (slope2 < BECKMANN_CUTOFF * cos2)
            c2 = dr.select(valid, cos2, 1.0)
            d = dr.exp(-dr.select(valid, slope2, 0.0) / c2) / (dr.pi * ax * ay * dr.square(c2))
        return dr.select(valid, d, 0.0)

    # --- G ------------------------------------------------------------------------
    def G1_over_cos(self, v):
        """Smith's G1(v) / cos θ_v, computed without the division (finite at
        the horizon, where G1 -> 0)."""
        if self.kind == "ggx":
            return self._g1_over_cos_ggx(v)
        if self.kind == "beckmann":
            return self._g1_over_cos_beckmann(v)
        return self._g1_over_cos_blinn(v)

    def G1(self, v):
        """Smith's masking G1(v) (0 below the horizon)."""
        return self.G1_over_cos(v) * dr.fmax(v.z, 0.0)

    def G(self, wi, wo, correlated: bool = False):
        """Smith's masking-shadowing: G1(ω_i) G1(ω_o), or with ``correlated``
        the height-correlated 1 / (1 + Λ(ω_i) + Λ(ω_o)), Λ = 1/G1 - 1."""
        g1_i, g1_o = self.G1(wi), self.G1(wo)
        if not correlated:
            return g1_i * g1_o
        return g1_i * g1_o / dr.fmax(g1_i + g1_o - g1_i * g1_o, TINY)

    def _g1_over_cos_ggx(self, v):
        # the lecture's 2/(1 + sqrt(1 + ρ² tan²θ)) times cos/cos:
        # 2 / (c + sqrt(c² + ρ² sin²θ)), no tan², finite at c = 0
        c = dr.fmax(v.z, 0.0)
        if self.isotropic:
            r2 = dr.square(self.alpha) * dr.fma(v.x, v.x, v.y * v.y)
        else:
            r2 = self._projected_sin2(v)                # the projected roughness α(φ)
        denom = c + dr.sqrt(dr.fma(c, c, r2))
        # >= alpha >= ALPHA_MIN above the surface; below TINY only straight down or
        # for the zero vector, where G1 = G1/c · c is 0 anyway
        return 2.0 / dr.fmax(denom, TINY)

    def _g1_over_cos_beckmann(self, v):
        """With a = c/(ρ s) (c = cos θ, s = sin θ), G1 = a P(a)/Q(a), so
        G1/c = s^5 P(c'/s) / (ρ s^6 Q(c'/s)), c' = c/ρ: a ratio of homogeneous
        polynomials in (c', s), with no exp and no clamp; it tends to 1/c at the
        normal (G1 = 1) and to 2 sqrt(π)/(ρ s) at the horizon. (In c' and s, not
        in c and ρ s: the denominator then stays above ~0.07/ρ^5, so that the
        float32 derivatives of the division, which square it, do not overflow;
        DEN_MIN only catches the zero vector, and ρ > ~3000.) Against the exact
        erf form the fit is within 5.1e-6 (float64), 5.5e-6 in float32
        (tests/bsdfs/test_cook_torrance.py::test_beckmann_g1); Mitsuba's own
        fit (its ``roughconductor``) is within 3.5e-3."""
        s = sin_theta(v)
        alpha = self.alpha
        if not self.isotropic:      # α(φ), and α_u along the normal, where G1 = 1
            alpha = dr.select(s > 0, dr.sqrt(self._projected_sin2(v)) / dr.select(s > 0, s, 1.0),
                              self.alpha)
            s = sin_theta(v)
        c = dr.fmax(v.z, 0.0) * (1.0 / alpha)               # cos θ / ρ
        return _homogeneous(BECKMANN_P, c, s) / dr.fmax(alpha * _homogeneous(BECKMANN_Q, c, s),
                                                        DEN_MIN)

    def _g1_over_cos_blinn(self, v):
        """From :data:`G1_BLINN_VALUES`. Near the horizon G1 ~ c g'(0), so G1/c
        is taken from the first cell's slope there (no division by a tiny c)."""
        grid = g1_blinn_grid()
        rho = dr.fmin(self.alpha, 1.0)
        c = dr.fmax(v.z, 0.0)
        rs = dr.fmax(self.alpha * sin_theta(v), TINY)
        t = c / (c + rs)                                   # a/(1 + a), a = c/(ρ s)
        g1 = grid(t, rho)
        # in the first cell g1 is linear in t: g1/c = (g1/t)(t/c) = (g1/t)/(c + rs)
        h = 1.0 / (G1_BLINN_AXES[0].n - 1)
        first = t < h
        g1_over_t = dr.select(first, grid(mi.Float(h), rho) / h, g1 / dr.select(first, 1.0, t))
        return g1_over_t / (c + rs)

    # --- sampling -----------------------------------------------------------------
    def sample(self, wi, sample2):
        """A normal m: visible from ω_i (density ``pdf(wi, m)``), or from the
        whole distribution, D(m) cos θ_m."""
        if self.visible:
            if self.kind == "ggx":
                return self._sample_ggx_visible(wi, sample2)
            return self._sample_beckmann_visible(wi, sample2)
        if self.kind == "blinn":
            # D(m) cos θ_m is the power-cosine lobe of exponent 2/ρ² - 1 about n
            return powercos.sample(sample2, 2.0 / dr.square(self.alpha) - 1.0)
        return self._sample_all(sample2)

    def pdf(self, wi, m):
        """The density of :meth:`sample` at m: G1(ω_i)/cos θ_i · max(0, ω_i·m)
        D(m) (visible normals) or D(m) cos θ_m."""
        if self.visible:
            return self.G1_over_cos(wi) * dr.fmax(dot(wi, m), 0.0) * self.D(m)
        return self.D(m) * dr.fmax(m.z, 0.0)

    def reflection_pdf(self, wi, wo, h, d=None):
        """The density of ω_o = reflect(ω_i, m) for m sampled by :meth:`sample`,
        at the half vector h of (ω_i, ω_o): pdf(h) / (4 ω_o·h). For visible
        normals ω_i·h = ω_o·h cancels: D(h) G1(ω_i) / (4 cos θ_i) (Heitz 2018).
        ``d``: D(h), when the caller has it. (D is 0 at the zero half vector of
        ω_o = -ω_i, where ω_o·h = 0.)"""
        d = self.D(h) if d is None else d
        if self.visible:
            return d * (self.G1_over_cos(wi) * 0.25)
        return d * dr.fmax(h.z, 0.0) / (4.0 * dr.fmax(dot(wo, h), TINY))

    def _sample_ggx_visible(self, wi, sample2):
        """Spherical caps (Dupuy & Benyoub 2023)."""
        ax, ay = (self.alpha, self.alpha) if self.isotropic else (self.alpha, self.alpha_v)
        # the viewer in the hemisphere configuration (roughness 1)
        vx, vy, vz = _normalize(ax * wi.x, ay * wi.y, dr.fmax(wi.z, 0.0))
        z = dr.fma(1.0 - sample2.y, 1.0 + vz, -vz)            # uniform on the spherical cap
        sin_t = dr.safe_sqrt(1.0 - z * z)
        s, c = dr.sincos(dr.two_pi * sample2.x)
        # back to the ellipsoid configuration
        return mi.Vector3f(*_normalize(ax * dr.fma(c, sin_t, vx), ay * dr.fma(s, sin_t, vy),
                                       dr.fmax(z + vz, 0.0)))

    def _sample_beckmann_visible(self, wi, sample2):
        ax, ay = (self.alpha, self.alpha) if self.isotropic else (self.alpha, self.alpha_v)
        m, _ = mi.MicrofacetDistribution(mi.MicrofacetType.Beckmann, ax, ay, True).sample(
            wi, sample2)
        # Mitsuba's Beckmann sampler fails at a corner of its domain (NaN for
        # u = (0, 0) at normal incidence): the zero vector instead, whose
        # "reflection" -wi is below the horizon (a discarded sample), and no NaN
        # in the other lanes' derivatives.
        return dr.select(dr.isfinite(m.x + m.y + m.z), m, 0.0)

    def _sample_all(self, sample2):
        """m with density D(m) cos θ_m, Beckmann or GGX: tan²θ_m = ρ² u/(1 - u)
        (GGX), -ρ² log(1 - u) (Beckmann). Anisotropic: the azimuth of the
        stretched slope, tan φ = (α_v/α_u) tan(2π u_y), and the roughness
        projected on it (Walter et al. 2007's sampling with the slope
        distribution stretched per axis)."""
        u = dr.fmin(sample2.x, 1.0 - 2.0**-24)
        if self.isotropic:
            a2 = dr.square(self.alpha)
            s, c = dr.sincos(dr.two_pi * sample2.y)
        else:
            ax, ay = self.alpha, self.alpha_v
            s0, c0 = dr.sincos(dr.two_pi * sample2.y)          # the unstretched slope's azimuth
            sx, sy = ax * c0, ay * s0                           # stretched: the azimuth of m
            r = dr.sqrt(dr.fma(sx, sx, sy * sy))
            c, s = sx / r, sy / r
            # α(φ)² = 1 / (cos²φ/α_u² + sin²φ/α_v²) along m's azimuth φ
            a2 = 1.0 / (dr.square(c / ax) + dr.square(s / ay))
        tan2 = a2 * u / (1.0 - u) if self.kind == "ggx" else -a2 * dr.log(1.0 - u)
        cos_t = dr.rsqrt(1.0 + tan2)
        sin_t = dr.safe_sqrt(tan2) * cos_t
        return mi.Vector3f(c * sin_t, s * sin_t, cos_t)
