"""phong: the lecture's formula and its normalised hdr lobe, transcribed
independently in NumPy (float64), and phong's own closed forms. What phong
shares with blinn is in test_power_lobes.py, what every model shares in the
battery (test_battery.py).

The transcription is written from the lecture and the hdr formulas, not from
mi_brdfs/bsdfs/phong.py: d the light (``wo``), w the viewer (``si.wi``), n = +z,
r = 2 (d·n) n - d.
"""
import math

import numpy as np

import mitsuba as mi

from support import eval_and_pdf, f32, mirror_pairs, random_hemisphere, unit


def phong(**params):
    return mi.load_dict({"type": "phong", **params})


# ----------------------------------------------------------------------------
#  The lecture's Phong, transcribed independently (float64)
# ----------------------------------------------------------------------------

def clamp(x):
    return np.clip(x, 0.0, 1.0)


def cos_alpha(d, w):
    """w·r with r = 2 (d·n) n - d (of the unit vectors along d and w)."""
    d, w = unit(d), unit(w)
    dn = d[:, 2]
    r = 2.0 * dn[:, None] * np.array([0.0, 0.0, 1.0]) - d
    return np.sum(w * r, axis=1)


def above(d, w):
    """A light or a viewer below (or on) the surface gets no reflection."""
    return ((d[:, 2] > 0) & (w[:, 2] > 0))[:, None]


def lecture_scanline(d, w, m_d, m_s, gamma):
    """clamp01(m_D·clamp(d·n)) + clamp01(m_S·clamp(w·r)^gamma), gamma > 0."""
    f_d = clamp(m_d[None, :] * clamp(d[:, 2:3]))
    f_s = clamp(m_s[None, :] * clamp(cos_alpha(d, w))[:, None] ** gamma)
    return (f_d + f_s) * above(d, w)


def normalised_hdr(d, w, m_d, m_s, gamma):
    """(m_D/pi + m_S (gamma+2)/(2 pi) cos^gamma(alpha)) · cos(theta_o), gamma > 0."""
    lobe = (gamma + 2) / (2 * np.pi) * clamp(cos_alpha(d, w)) ** gamma
    f = m_d[None, :] / np.pi + m_s[None, :] * lobe[:, None]
    return f * d[:, 2:3] * above(d, w)


def pairs(rng, n, gamma, min_cos=0.0):
    """(d, w): half random, half with d within a few lobe widths of w's mirror."""
    w, d = mirror_pairs(rng, n, 1.5 / math.sqrt(gamma + 1), min_cos)
    return d, w


lobe_cosine = cos_alpha          # the cosine the lobe raises to gamma


def test_exponent_zero_is_the_hemisphere_about_the_mirror_direction(rng):
    """gamma = 0: clamp(w·r)^0 is 1 where w·r > 0 and 0 beyond 90 deg (0^0 := 0)."""
    d, w = f32(random_hemisphere(rng, 4096)), f32(random_hemisphere(rng, 4096))
    value, _ = eval_and_pdf(phong(mode="scanline", diffuse_reflectance=0.0,
                              specular_reflectance=0.7, exponent=0.0), w, d)
    np.testing.assert_array_equal(value[:, 0], np.where(cos_alpha(d, w) > 0, np.float32(0.7), 0.0))
    assert (cos_alpha(d, w) < 0).sum() > 500


# ----------------------------------------------------------------------------
#  What test_power_lobes.py needs of phong
# ----------------------------------------------------------------------------

GAMMAS = [0.0, 1.0, 10.0, 100.0, 1e3, 1e4, 1e6]


def lobe_width(gamma):
    """The lobe's angular width about the mirror direction."""
    return 1.0 / math.sqrt(gamma + 1.0)


def closed_forms(thetas):
    """((m_D, m_S, gamma), angles, E): gamma = 0 is the hemisphere about r', of
    albedo (1 + cos theta_i)/2 (a hemispherical source tilted by theta_i); a
    narrow lobe above the horizon reflects m_S cos(theta_i) (its tilt sin(alpha)
    cos(phi) integrates to 0): a plugin that loses the lobe to float32
    cancellation at gamma = 10^6 fails here."""
    cos_t = np.cos(np.radians(thetas))
    yield (0.0, 1.0, 0.0), slice(None), (1 + cos_t) / 2
    lobe_up = thetas <= 85
    for gamma in (1e4, 1e6):
        yield (0.0, 0.7, gamma), lobe_up, 0.7 * cos_t[lobe_up]


def lobe_statistic(wi, wo, gamma):
    """-(gamma+1) log cos(alpha), alpha the angle of wo to wi's mirror direction,
    in float64: Exp(1)-distributed for the sampler's cdf cos^(gamma+1) alpha = u."""
    return -(gamma + 1) * _log_cos_alpha(wi, wo)


def lobe_reference(wi, wo, gamma):
    """(pdf, eval) of the lobe (m_S = 1) in float64 at the sampled directions."""
    log_cos = _log_cos_alpha(wi, wo)
    pdf = (gamma + 1) / (2 * np.pi) * np.exp(gamma * log_cos)
    return pdf, (gamma + 2) / (2 * np.pi) * np.exp(gamma * log_cos) * unit(wo)[:, 2]


def sampled_exponent(gamma):
    """The exponent of the power-cosine density the sampler draws from."""
    return gamma


def _log_cos_alpha(wi, wo):
    """log cos(alpha) in float64: log1p(-(1 - cos alpha)), 1 - cos alpha = |wo - r|²/2."""
    r = unit(wi * [-1, -1, 1])
    return np.log1p(-0.5 * np.sum((unit(wo) - r) ** 2, axis=1))
