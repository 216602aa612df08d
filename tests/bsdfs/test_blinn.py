"""blinn: the lecture's formula and its hdr lobe with the exact
normal-incidence normalisation, transcribed independently in NumPy (float64),
and blinn's own closed forms. What blinn shares with phong is in
test_power_lobes.py, what every model shares in the battery (test_battery.py).

The transcription is written from the lecture and the hdr formulas, not from
mi_brdfs/bsdfs/blinn.py: d the light (``wo``), w the viewer (``si.wi``), n = +z,
h = normalize(d + w).
"""
import math

import numpy as np
import pytest

import mitsuba as mi

from support import eval_and_pdf, f32, mirror_pairs, mirror_lobe_albedo, random_hemisphere


def blinn(**params):
    return mi.load_dict({"type": "blinn", **params})


# ----------------------------------------------------------------------------
#  The lecture's Blinn, transcribed independently (float64)
# ----------------------------------------------------------------------------

def clamp(x):
    return np.clip(x, 0.0, 1.0)


def cos_h(d, w):
    """n·h with h = normalize(d + w)."""
    h = d + w
    h = h / np.linalg.norm(h, axis=1, keepdims=True)
    return h[:, 2]


def above(d, w):
    """A light or a viewer below (or on) the surface gets no reflection."""
    return ((d[:, 2] > 0) & (w[:, 2] > 0))[:, None]


def lecture_scanline(d, w, m_d, m_s, gamma):
    """clamp01(m_D·clamp(d·n)) + clamp01(m_S·clamp(n·h)^gamma)."""
    f_d = clamp(m_d[None, :] * clamp(d[:, 2:3]))
    f_s = clamp(m_s[None, :] * clamp(cos_h(d, w))[:, None] ** gamma)
    return (f_d + f_s) * above(d, w)


def giesen(gamma):
    """The exact normal-incidence normalisation (Giesen)."""
    return (gamma + 2) * (gamma + 4) / (8 * np.pi * (2 ** (-gamma / 2) + gamma))


def normalised_hdr(d, w, m_d, m_s, gamma):
    """(m_D/pi + m_S N(gamma) cos^gamma(theta_h)) · cos(theta_o)."""
    lobe = giesen(gamma) * clamp(cos_h(d, w)) ** gamma
    f = m_d[None, :] / np.pi + m_s[None, :] * lobe[:, None]
    return f * d[:, 2:3] * above(d, w)


def pairs(rng, n, gamma, min_cos=0.0):
    """(d, w): half random, half with d within a few lobe widths of w's mirror."""
    w, d = mirror_pairs(rng, n, 3.0 / math.sqrt(gamma + 1), min_cos)
    return d, w


lobe_cosine = cos_h          # the cosine the lobe raises to gamma


def test_exponent_zero_is_lambert(rng):
    """gamma = 0: N = 1/pi and n·h > 0 always, so the hdr model is Lambert with
    m_D + m_S (and the scanline lobe the constant m_S)."""
    d, w = f32(random_hemisphere(rng, 4096)), f32(random_hemisphere(rng, 4096))
    value, pdf = eval_and_pdf(blinn(diffuse_reflectance=0.2, specular_reflectance=0.7, exponent=0.0), w, d)
    lambert, _ = eval_and_pdf(mi.load_dict({"type": "lambert", "reflectance": 0.9}), w, d)
    np.testing.assert_allclose(value, lambert, rtol=1e-6)
    value, _ = eval_and_pdf(blinn(mode="scanline", diffuse_reflectance=0.0,
                             specular_reflectance=0.7, exponent=0.0), w, d)
    np.testing.assert_array_equal(value[:, 0], np.float32(0.7))


# ----------------------------------------------------------------------------
#  What test_power_lobes.py needs of blinn
# ----------------------------------------------------------------------------

GAMMAS = [0.0, 0.5, 1.0, 10.0, 100.0, 1e3, 1e4, 1e6]


def lobe_width(gamma):
    """A Blinn lobe is about 2/sqrt(gamma + 1) wide in light directions."""
    return 2.0 / math.sqrt(gamma + 1.0)


def closed_forms(thetas):
    """((m_D, m_S, gamma), angles, E): gamma = 0 is Lambert, E = m_D + m_S at
    every angle. A narrow lobe (gamma = 10^6, 1e-3 rad) reflects
    m_S N(gamma) 2 pi/(gamma+1) · 4 cos²(theta_i) = m_S cos²(theta_i) (1 + O(1/gamma)):
    the half-vector lobe integrates to 2 pi/(gamma+1), times cos(theta_o) and
    the Jacobian 4 (d·h), both cos(theta_i) at h = n. A plugin that loses the
    lobe to float32 cancellation fails here."""
    cos_t = np.cos(np.radians(thetas))
    for m_d, m_s in ((0.0, 1.0), (0.3, 0.7)):
        yield (m_d, m_s, 0.0), slice(None), np.full(len(thetas), m_d + m_s)
    yield (0.0, 0.7, 1e6), slice(None), 0.7 * cos_t**2


def test_furnace_would_catch_the_common_normalisation():
    """Power of the furnace bound: with (gamma+8)/(8 pi) instead of N(gamma) (the
    lobe's albedo scales with the constant) the albedo at gamma = 10, normal
    incidence, is 1.07, above 1."""
    gamma = 10.0
    e = mirror_lobe_albedo(blinn(diffuse_reflectance=0.0, specular_reflectance=1.0,
                                 exponent=gamma), 0.0, lobe_width(gamma))[0]
    assert e == pytest.approx(1.0, abs=1e-4)
    assert e * (gamma + 8) / (8 * np.pi) / giesen(gamma) == pytest.approx(1.0748, abs=1e-3)


def lobe_statistic(wi, wo, gamma):
    """-(gamma+2) log cos(theta_h) in float64: Exp(1)-distributed for half
    vectors of density (gamma+2)/(2 pi) cos^(gamma+1)(theta_h) (their cdf is
    cos^(gamma+2)(theta_h) = u)."""
    v = wi + wo
    sin2 = (v[:, 0] ** 2 + v[:, 1] ** 2) / np.sum(v**2, axis=1)
    return -(gamma + 2) * 0.5 * np.log1p(-sin2)


def lobe_reference(wi, wo, gamma):
    """(pdf, eval) of the lobe (m_S = 1) in float64 at the sampled directions."""
    v = wi + wo
    norm = np.linalg.norm(v, axis=1)
    log_cos = 0.5 * np.log1p(-(v[:, 0] ** 2 + v[:, 1] ** 2) / norm**2)
    o_dot_h = np.sum(wo * v, axis=1) / norm
    pdf = (gamma + 2) / (2 * np.pi) * np.exp((gamma + 1) * log_cos) / (4 * o_dot_h)
    return pdf, giesen(gamma) * np.exp(gamma * log_cos) * wo[:, 2]


def sampled_exponent(gamma):
    """The exponent of the power-cosine density of half vectors the sampler draws from."""
    return gamma + 1.0
