"""An independent NumPy transcription of the lecture's formulas (tests only).

Written from the lecture text, not from the package: d is the light direction
(lx), w the viewer (w_r), the normal is n = (0, 0, 1); arrays of directions are
(N, 3). Float64 throughout.
"""
import functools
import math

import numpy as np

erf = np.vectorize(math.erf)


def clamp(x):
    return np.clip(x, 0.0, 1.0)


def dot(a, b):
    return np.sum(a * b, axis=-1)


def half(d, w):
    h = d + w
    return h / np.linalg.norm(h, axis=-1, keepdims=True)


# --- Cook-Torrance terms -------------------------------------------------------
def D_blinn(hn, rho):
    return hn ** (2 / rho**2 - 2) / (np.pi * rho**2)


def D_beckmann(hn, rho):
    return np.exp((hn**2 - 1) / (hn**2 * rho**2)) / (np.pi * rho**2 * hn**4)


def D_ggx(hn, rho):
    return rho**2 / (np.pi * (clamp(hn) ** 2 * (rho**2 - 1) + 1) ** 2)


def F_schlick(f0, wh):
    return f0 + (1 - f0) * (1 - clamp(wh)) ** 5


def G_microfacet(hn, wn, dn, wh):
    return np.minimum(1, np.minimum(2 * hn * wn / wh, 2 * hn * dn / wh))


def g_ggx(na, rho):
    return 2 / (1 + np.sqrt(1 + rho**2 * (1 - na**2) / na**2))


def g_beckmann(na, rho):
    """Smith G1 of the Beckmann distribution (Walter et al. 2007, exact form)."""
    a = na / (rho * np.sqrt(1 - na**2))
    return 2 / (1 + erf(a) + np.exp(-a**2) / (a * np.sqrt(np.pi)))


@functools.lru_cache(maxsize=None)
def _g_blinn_curve(rho, n_mu=401, n_theta=400, n_phi=256):
    """G1 of the Blinn distribution on a grid of cos θ, by brute-force 2-D
    quadrature of its definition G1(v) = cos θ_v / ∫ max(0, v·m) D(m) dm
    (Gauss-Legendre in θ_m, midpoint in φ_m; the package tabulates the same
    definition with an analytic azimuthal integral)."""
    x, w = np.polynomial.legendre.leggauss(n_theta)
    theta = np.pi / 4 * (x + 1)
    w_theta = np.pi / 4 * w
    phi = (np.arange(n_phi) + 0.5) * np.pi / n_phi          # [0, pi]; the rest by symmetry
    T, P = np.meshgrid(theta, phi, indexing="ij")
    m = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1)
    weight = (D_blinn(np.cos(T), rho) * np.sin(T) * w_theta[:, None] * 2 * np.pi / n_phi)
    t = np.linspace(0.0, np.pi / 2, n_mu)
    mu = np.cos(t)
    area = np.array([np.sum(np.maximum(0.0, m @ np.array([np.sin(a), 0.0, np.cos(a)])) * weight)
                     for a in t])
    return mu[::-1], (mu / area)[::-1]


def g_blinn(na, rho):
    """Smith G1 of the Blinn distribution itself, interpolated
    (cubic) from the brute-force quadrature above."""
    from scipy.interpolate import CubicSpline
    mu, g = _g_blinn_curve(float(rho))
    return CubicSpline(mu, g)(na)


D = {"blinn": D_blinn, "beckmann": D_beckmann, "ggx": D_ggx}
G1 = {"blinn": g_blinn, "beckmann": g_beckmann, "ggx": g_ggx}


def cook_torrance_terms(d, w, rho, f0, distribution, geometry):
    """D·F·G / (4 clamp(w·n)), the lecture's f_specular without m_S."""
    n = np.array([0.0, 0.0, 1.0])
    h = half(d, w)
    hn, wn, dn, wh = dot(h, n), dot(w, n), dot(d, n), dot(w, h)
    Dv = D[distribution](hn, rho)
    Fv = F_schlick(f0, wh)
    if geometry == "cook_torrance":
        Gv = G_microfacet(hn, wn, dn, wh)
    else:
        Gv = G1[distribution](wn, rho) * G1[distribution](dn, rho)
    return Dv * Fv * Gv / (4 * clamp(wn))


def cook_torrance_scanline(d, w, m_d, m_s, k, f0, rho, distribution, geometry):
    """k f_diffuse + (1-k) f_specular, each clamped per channel to [0, 1]."""
    dn = d[:, 2:3]
    f_diffuse = m_d[None, :] * clamp(dn)
    f_specular = m_s[None, :] * cook_torrance_terms(d, w, rho, f0, distribution, geometry)[:, None]
    return k * clamp(f_diffuse) + (1 - k) * clamp(f_specular)


def cook_torrance_hdr_eval(d, w, m_d, m_s, k, f0, rho, distribution, geometry):
    """(k m_D/pi + (1-k) m_S DFG/(4 cos_i cos_o)) cos_o: Mitsuba's eval convention."""
    dn = d[:, 2:3]
    spec = cook_torrance_terms(d, w, rho, f0, distribution, geometry)[:, None]   # has 1/(4 cos_i)
    return k * m_d[None, :] / np.pi * dn + (1 - k) * m_s[None, :] * spec


def fresnel_dielectric(cos_i, eta):
    """Exact unpolarised Fresnel reflectance of a dielectric interface (eta = n2/n1)."""
    sin_t2 = (1 - cos_i**2) / eta**2
    cos_t = np.sqrt(1 - sin_t2)
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs**2 + rp**2)
