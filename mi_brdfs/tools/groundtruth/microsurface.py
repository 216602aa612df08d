"""The Smith microsurface of GGX and Beckmann normals, isotropic or anisotropic.

Everything the random walk (:mod:`.walk`) needs to know about the surface, as
NumPy float64 functions of local directions (x along the tangent s, y along t,
z the normal; arrays of shape (..., 3)) and of the roughness ``alpha``: one α
(isotropic) or an :class:`Alpha` pair (α_x along s, α_y along t). Both go
through the same code: one α is the pair (α, α).

The one quantity the rest derives from is the **projected area**

    A(w) = ∫ max(0, w·m) D(m) dm,

the area of the facets that face w per unit of macro-surface, in closed form
for every w on the sphere (Heitz 2014, "Understanding the Masking-Shadowing
Function in Microfacet-Based BRDFs", JCGT 3(2): Smith's Λ for Beckmann and
GGX, anisotropic by the projected roughness α(φ) = sqrt(cos²φ α_x² +
sin²φ α_y²)). With r = α(φ) sin θ = |(α_x w_x, α_y w_y)| and z = cos θ:

    GGX:       A(w) = (z + sqrt(z² + r²)) / 2
    Beckmann:  A(w) = z erfc(-z/r) / 2 + r exp(-z²/r²) / (2 sqrt π)

Since ∫ (w·m) D(m) dm = z, A(w) - A(-w) = z, and Smith's Λ is
Λ(w) = A(-w) / z: the facets that face away from w, seen from w, over
cos θ. It is >= 0 above the horizon and Λ(w) = -1 - Λ(-w) below it.
The masking G1(w) = 1 / (1 + Λ(w)) = z / A(w), and the density of the
normals visible from w is D_w(m) = max(0, w·m) D(m) / A(w).

Visible normals are sampled in the configuration stretched to α = 1
(Heitz & d'Eon 2014, "Importance Sampling Microfacet-Based BSDFs using the
Distribution of Visible Normals", EGSR; both distributions are invariant
under the stretch): GGX by spherical caps (Dupuy & Benyoub 2023, "Sampling
Visible GGX Normals with Spherical Caps", HPG), Beckmann by inverting the
cdf of the visible x-slope with safeguarded Newton steps. Both accept any w,
above or below the horizon (the walk meets facets from below too).
"""
from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from scipy.special import erfc, erfinv

DISTRIBUTIONS = ("ggx", "beckmann")
SQRT_PI = math.sqrt(math.pi)


class Alpha(NamedTuple):
    """Anisotropic roughness: ``x`` along the tangent s, ``y`` along t (numbers
    or arrays, broadcast with the directions)."""
    x: Any
    y: Any


def pair(alpha) -> tuple[np.ndarray, np.ndarray]:
    """(α_x, α_y) as float64 arrays, from one α or an :class:`Alpha`."""
    ax, ay = alpha if isinstance(alpha, Alpha) else (alpha, alpha)
    return np.asarray(ax, dtype=np.float64), np.asarray(ay, dtype=np.float64)


def check(distribution: str) -> None:
    if distribution not in DISTRIBUTIONS:
        raise ValueError(f"random walk: distribution {distribution!r}; valid: "
                         f"{', '.join(DISTRIBUTIONS)}")


def normalize(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def dot(a, b):
    return np.sum(a * b, axis=-1)


# ----------------------------------------------------------------------------
#  Projected area, Λ, D, visible normals
# ----------------------------------------------------------------------------

def projected_area(distribution: str, w, alpha):
    """A(w) = ∫ max(0, w·m) D(m) dm for any unit w (0 straight down)."""
    ax, ay = pair(alpha)
    z = w[..., 2]
    r = np.hypot(ax * w[..., 0], ay * w[..., 1])          # α(φ) sin θ
    with np.errstate(divide="ignore", invalid="ignore"):
        if distribution == "ggx":
            h = np.hypot(z, r)
            # below the horizon z + h cancels: the same value as r² / (h - z)
            area = np.where(z >= 0, 0.5 * (z + h), 0.5 * r * r / (h - z))
        else:
            a = z / r                                      # ±inf along the normal
            area = 0.5 * z * erfc(-a) + r * np.exp(-a * a) / (2.0 * SQRT_PI)
    return np.maximum(np.nan_to_num(area, nan=0.0), 0.0)


def lam(distribution: str, w, alpha):
    """Smith's Λ(w) = A(-w) / cos θ (Λ(-w) = -1 - Λ(w)); ±inf at the horizon."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return projected_area(distribution, -w, alpha) / w[..., 2]


def d(distribution: str, m, alpha):
    """The normal distribution D(m), normalised so that ∫ D(m) cos θ_m dm = 1;
    0 below the horizon."""
    ax, ay = pair(alpha)
    z = m[..., 2]
    q = (m[..., 0] / ax) ** 2 + (m[..., 1] / ay) ** 2      # z² times the stretched slope²
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if distribution == "ggx":
            value = 1.0 / (np.pi * ax * ay * (z * z + q) ** 2)
        else:
            value = np.exp(-q / (z * z)) / (np.pi * ax * ay * z ** 4)
    return np.where(z > 0, np.nan_to_num(value, posinf=0.0), 0.0)


def d_visible(distribution: str, w, m, alpha):
    """D_w(m) = max(0, w·m) D(m) / A(w): normals seen from w (0 if none are)."""
    area = projected_area(distribution, w, alpha)
    seen = area > 0
    return np.where(seen, np.maximum(dot(w, m), 0.0) * d(distribution, m, alpha)
                    / np.where(seen, area, 1.0), 0.0)


def fresnel(f0, cos):
    """Schlick's F0 + (1 - F0)(1 - cos)^5."""
    return f0 + (1.0 - f0) * (1.0 - np.clip(cos, 0.0, 1.0)) ** 5


def conductor(eta, kappa, cos):
    """The exact unpolarised reflectance of a conductor of complex index
    n = η + iκ (relative to the outside) at cos θ, from the Fresnel amplitudes
    in complex arithmetic (Born & Wolf, *Principles of Optics*, §1.5 and §14.2):
    r_s = (cos - n cos_t)/(cos + n cos_t), r_p = (n cos - cos_t)/(n cos + cos_t),
    cos_t = sqrt(1 - sin²/n²)."""
    c = np.clip(np.asarray(cos, dtype=np.float64), 0.0, 1.0)
    n = complex(eta, kappa)
    with np.errstate(divide="ignore", invalid="ignore"):
        ct = np.sqrt(1.0 - (1.0 - c * c) / (n * n) + 0j)
        r_s = (c - n * ct) / (c + n * ct)
        r_p = (n * c - ct) / (n * c + ct)
    return np.nan_to_num(0.5 * (np.abs(r_s) ** 2 + np.abs(r_p) ** 2), nan=1.0)


def dielectric(eta, cos):
    """The exact reflectance of a dielectric interface of relative index η
    (light from outside): :func:`conductor` with κ = 0 (total internal
    reflection, η < 1, gives |r| = 1 there)."""
    return conductor(eta, 0.0, cos)


def f82(f0, tint, cos):
    """Hoffman's F82-tint (*Generalization of Adobe's Fresnel Model*, 2023):
    Schlick's curve less b·cos·(1 - cos)^6, b set so that F(1/7) = tint ×
    Schlick(1/7)."""
    c = np.clip(np.asarray(cos, dtype=np.float64), 0.0, 1.0)
    cb = 1.0 / 7.0
    b = fresnel(f0, cb) * (1.0 - tint) / (cb * (1.0 - cb) ** 6)
    return np.maximum(fresnel(f0, c) - b * c * (1.0 - c) ** 6, 0.0)


def single_scattering(distribution: str, wi, wo, alpha, f0=1.0):
    """f·cos θ_o of the height-correlated Smith microfacet BRDF (Heitz 2014,
    eq. 99: G2 = 1 / (1 + Λ(wi) + Λ(wo))), F D G2 / (4 cos θ_i)."""
    up = (wi[..., 2] > 0) & (wo[..., 2] > 0)
    h = normalize(wi + wo)
    with np.errstate(divide="ignore", invalid="ignore"):
        g2 = 1.0 / (1.0 + lam(distribution, wi, alpha) + lam(distribution, wo, alpha))
        value = fresnel(f0, dot(wi, h)) * d(distribution, h, alpha) * g2 / (4.0 * wi[..., 2])
    return np.where(up, np.nan_to_num(value), 0.0)


# ----------------------------------------------------------------------------
#  Sampling visible normals
# ----------------------------------------------------------------------------

def _stretch(w, ax, ay):
    """The direction in the configuration of α = 1 (unit length)."""
    return normalize(np.stack([ax * w[..., 0], ay * w[..., 1], w[..., 2]], axis=-1))


def _unstretch_normal(n, ax, ay):
    """A normal of the α = 1 configuration back to the surface's: its slopes
    -n_x/n_z, -n_y/n_z scale by α_x, α_y."""
    return normalize(np.stack([ax * n[..., 0], ay * n[..., 1], np.maximum(n[..., 2], 0.0)],
                              axis=-1))


def _caps_ggx(v, u1, u2):
    """GGX at α = 1 is a hemisphere of normals: v + c, c uniform on the part of
    the unit sphere with c_z >= -v_z, has the visible-normal density."""
    cz = 1.0 - u1 * (1.0 + v[..., 2])
    s = np.sqrt(np.maximum(1.0 - cz * cz, 0.0))
    phi = 2.0 * np.pi * u2
    return v + np.stack([s * np.cos(phi), s * np.sin(phi), cz], axis=-1)


NEWTON_STEPS = 100        # each a Newton step or, where that leaves the bracket, a bisection
SLOPE_TOL = 1e-12         # converged when the step (or the bracket) is below this
SLOPE_TAIL = 6.0          # the bracket reaches this far into the Gaussian tail (e^-36)


def visible_slope_beckmann(cos_t, sin_t, u):
    """The x-slope (along the viewer's azimuth) of a Beckmann normal at α = 1
    visible from a viewer at θ (sin θ >= 0, any cos θ): the slopes s <= cot θ
    have the density ∝ (cos θ - s sin θ) e^(-s²), whose integral up to s is

        P(s) = cos θ erfc(-s) / 2 + sin θ e^(-s²) / (2 sqrt π),

    P(cot θ) the projected area. Solves P(s) = u P(cot θ) by Newton steps
    kept inside a shrinking bracket (bisection where a step would leave it)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        cot = np.where(sin_t > 0, cos_t / sin_t, np.inf)

    def integral(s, c, st):
        return 0.5 * c * erfc(-s) + st * np.exp(-s * s) / (2.0 * SQRT_PI)

    hi = np.minimum(cot, SLOPE_TAIL)
    lo = np.minimum(cot, 0.0) - SLOPE_TAIL
    target = u * integral(hi, cos_t, sin_t)
    s = np.clip(erfinv(2.0 * u - 1.0), lo, hi)          # exact along the normal
    todo = np.arange(len(s))
    for _ in range(NEWTON_STEPS):
        c, st, x, a, b = cos_t[todo], sin_t[todo], s[todo], lo[todo], hi[todo]
        excess = integral(x, c, st) - target[todo]
        b = np.where(excess > 0, x, b)                     # the root is below x
        a = np.where(excess > 0, a, x)
        slope = (c - x * st) * np.exp(-x * x) / SQRT_PI
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = x - excess / slope
        inside = np.isfinite(newton) & (newton >= a) & (newton <= b)
        nxt = np.where(inside, newton, 0.5 * (a + b))
        s[todo], lo[todo], hi[todo] = nxt, a, b
        todo = todo[(np.abs(nxt - x) > SLOPE_TOL) & (b - a > SLOPE_TOL)]
        if len(todo) == 0:
            break
    return s


def _slopes_beckmann(v, u1, u2):
    """A visible normal of Beckmann at α = 1, as an (unnormalised) vector."""
    sin_t = np.hypot(v[..., 0], v[..., 1])
    along = sin_t > 0
    cphi = np.where(along, v[..., 0] / np.where(along, sin_t, 1.0), 1.0)
    sphi = np.where(along, v[..., 1] / np.where(along, sin_t, 1.0), 0.0)
    sx = visible_slope_beckmann(v[..., 2], sin_t, u1)
    sy = erfinv(np.maximum(2.0 * u2 - 1.0, -1.0 + 1e-15))   # across: the plain Gaussian
    px, py = cphi * sx - sphi * sy, sphi * sx + cphi * sy   # to the viewer's azimuth
    return np.stack([-px, -py, np.ones_like(px)], axis=-1)


def sample_visible(distribution: str, w, alpha, u1, u2):
    """A microfacet normal m with the density D_w(m), for (N, 3) directions w
    (above or below the horizon, not straight down) and uniform numbers u1, u2."""
    ax, ay = pair(alpha)
    v = _stretch(w, ax, ay)
    n = _caps_ggx(v, u1, u2) if distribution == "ggx" else _slopes_beckmann(v, u1, u2)
    return _unstretch_normal(n, ax, ay)
