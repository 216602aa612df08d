"""ashikhmin_shirley: the paper's BRDF (Ashikhmin & Shirley 2000, eqs. for
rho_s, rho_d, F, p_h) transcribed independently in NumPy (float64) from the
paper, not from mi_brdfs/bsdfs/ashikhmin_shirley.py, the plugin compared with
it in both modes; the sampler's closed-form weight; the diffuse term's
closed-form albedo; the anisotropy's orientation. What every model shares
(χ², furnace, extremes, gradients, errors): the battery.

k1 the viewer (``si.wi``), k2 the light (``wo``), local frame u = x, v = y, n = z.
"""
import math

import numpy as np
import pytest

from support import (albedo, assert_refused, direction, eval_and_pdf, hemisphere_points,
                     mirror_pairs, rgb, sampled, surface)

import mitsuba as mi


# ----------------------------------------------------------------------------
#  The paper's model, transcribed (float64)
# ----------------------------------------------------------------------------

def paper_specular(k1, k2, n_u, n_v):
    """rho_s / F and k·h: sqrt((n_u+1)(n_v+1))/(8 pi) (n·h)^((n_u (h·u)^2 + n_v (h·v)^2)
    / (1 - (n·h)^2)) / ((h·k) max(n·k1, n·k2))."""
    h = k1 + k2
    h = h / np.linalg.norm(h, axis=1, keepdims=True)
    hu, hv, hn = h[:, 0], h[:, 1], h[:, 2]
    power = (n_u * hu ** 2 + n_v * hv ** 2) / (hu ** 2 + hv ** 2)   # h = n never drawn
    kh = np.sum(k1 * h, axis=1)
    rho = (math.sqrt((n_u + 1) * (n_v + 1)) / (8 * np.pi) * hn ** power
           / (kh * np.maximum(k1[:, 2], k2[:, 2])))
    return rho, kh


def schlick(r_s, kh):
    return r_s[None, :] + (1 - r_s[None, :]) * (1 - kh[:, None]) ** 5


def paper_diffuse(k1, k2, r_d, r_s):
    """28 R_d/(23 pi) (1 - R_s)(1 - (1 - n·k1/2)^5)(1 - (1 - n·k2/2)^5)."""
    g = (1 - (1 - k1[:, 2] / 2) ** 5) * (1 - (1 - k2[:, 2] / 2) ** 5)
    return 28 * r_d[None, :] / (23 * np.pi) * (1 - r_s[None, :]) * g[:, None]


def paper_eval(k1, k2, r_d, r_s, n_u, n_v, mode):
    """hdr: (rho_d + rho_s)(n·k2); scanline: clamp01(pi rho_d n·k2) + clamp01(rho_s n·k2)."""
    rho_s, kh = paper_specular(k1, k2, n_u, n_v)
    spec = rho_s[:, None] * schlick(r_s, kh) * k2[:, 2:3]
    diff = paper_diffuse(k1, k2, r_d, r_s) * k2[:, 2:3]
    if mode == "hdr":
        return diff + spec
    return np.clip(np.pi * diff, 0, 1) + np.clip(spec, 0, 1)


def paper_pdf(k1, k2, n_u, n_v):
    """p_h(h)/(4 k·h), p_h = sqrt((n_u+1)(n_v+1))/(2 pi) (n·h)^(n_u cos^2 phi + n_v sin^2 phi)."""
    h = k1 + k2
    h = h / np.linalg.norm(h, axis=1, keepdims=True)
    phi = np.arctan2(h[:, 1], h[:, 0])
    p_h = (math.sqrt((n_u + 1) * (n_v + 1)) / (2 * np.pi)
           * h[:, 2] ** (n_u * np.cos(phi) ** 2 + n_v * np.sin(phi) ** 2))
    return p_h / (4 * np.sum(k2 * h, axis=1))


R_D, R_S = np.array([0.9, 0.5, 0.1]), np.array([0.04, 0.3, 0.95])
EXPONENTS = [(1.0, 1.0), (100.0, 100.0), (1000.0, 20.0), (20.0, 1000.0), (1e4, 50.0)]


def load(n_u, n_v, mode="hdr", r_d=R_D, r_s=R_S, **kw):
    return mi.load_dict({"type": "ashikhmin_shirley", "mode": mode, "exponent_u": n_u,
                         "exponent_v": n_v, "diffuse_reflectance": rgb(r_d),
                         "specular_reflectance": rgb(r_s), **kw})


def pairs(rng, n_u, n_v, n=4096):
    """(k1, k2): half with k2 near k1's mirror direction (within the lobe)."""
    width = 2.0 / math.sqrt(min(n_u, n_v) + 1.0)
    return mirror_pairs(rng, n, width, min_cos=0.02)


# ----------------------------------------------------------------------------
#  1. eval and pdf == the paper, in both modes
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("mode", ["hdr", "scanline"])
@pytest.mark.parametrize("n_u, n_v", EXPONENTS)
def test_eval_matches_the_paper(rng, mode, n_u, n_v):
    k1, k2 = pairs(rng, n_u, n_v)
    value, _ = eval_and_pdf(load(n_u, n_v, mode), wi=k1, wo=k2)
    expected = paper_eval(k1, k2, R_D, R_S, n_u, n_v, mode)
    np.testing.assert_allclose(value, expected, rtol=3e-4, atol=1e-6)
    assert (value > 1e-3).mean() > 0.3           # not a comparison of zeros
    if mode == "scanline" and n_u >= 100:
        assert (value > 1.0).any()               # the two clamps add up above 1


@pytest.mark.parametrize("n_u, n_v", EXPONENTS)
def test_pdf_matches_the_paper(rng, n_u, n_v):
    """With R_d = 0 the pdf is the specular lobe's alone: the paper's p_h/(4 k·h)."""
    k1, k2 = pairs(rng, n_u, n_v)
    _, pdf = eval_and_pdf(load(n_u, n_v, r_d=[0, 0, 0]), wi=k1, wo=k2)
    np.testing.assert_allclose(pdf, paper_pdf(k1, k2, n_u, n_v), rtol=3e-4, atol=1e-6)
    assert (pdf > 1e-2).mean() > 0.05            # not a comparison of zeros


def test_scanline_diffuse_has_no_one_over_pi():
    """Without a specular layer, at normal incidence on both sides, scanline
    gives 28/23 · R_d · (1 - 1/32)^2 (the paper's rho_d times pi), hdr that over pi."""
    k = np.array([[0.0, 0.0, 1.0]])
    r_d = np.array([0.3, 0.5, 0.7])
    expected = 28 / 23 * r_d * (31 / 32) ** 2
    for mode, scale in (("scanline", 1.0), ("hdr", 1 / np.pi)):
        value, _ = eval_and_pdf(load(10.0, 10.0, mode, r_d=r_d, r_s=[0, 0, 0]), wi=k, wo=k)
        np.testing.assert_allclose(value[0], expected * scale, rtol=1e-5)


# ----------------------------------------------------------------------------
#  2. Closed forms: the sampler's weight, the diffuse albedo
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("n_u, n_v", [(10.0, 10.0), (1000.0, 20.0), (5.0, 3000.0)])
def test_sample_weight_is_fresnel_times_the_cosine_ratio(rng, n_u, n_v):
    """The paper's normalisation makes rho_s (k2·n)/p(k2) = F(k·h) min(1, (k2·n)/(k1·n))."""
    k1 = mirror_pairs(rng, 2048, 0.5, min_cos=0.05)[0]
    s = sampled(load(n_u, n_v, r_d=[0, 0, 0]), k1, rng)
    ok = s["pdf"] > 0
    assert ok.mean() > 0.5
    wo, wi = s["wo"][ok], k1[ok]
    h = (wi + wo) / np.linalg.norm(wi + wo, axis=1, keepdims=True)
    kh = np.sum(wo * h, axis=1)
    expected = schlick(R_S, kh) * np.minimum(1.0, wo[:, 2] / wi[:, 2])[:, None]
    np.testing.assert_allclose(s["weight"][ok], expected, rtol=1e-3, atol=1e-6)


@pytest.mark.parametrize("theta", [0, 30, 60, 80])
def test_diffuse_albedo_is_the_papers_closed_form(theta):
    """The diffuse lobe alone reflects R_d (1 - R_s)(1 - (1 - cos theta/2)^5): the
    28/(23 pi) normalisation makes the outgoing factor integrate to 23 pi/28."""
    bsdf = load(10.0, 10.0, r_d=[1.0, 0.5, 0.25], r_s=[0.0, 0.2, 0.6])
    wo = hemisphere_points(1024)
    si = surface(direction(theta)[None, :])
    diffuse_only = mi.BSDFContext(mi.TransportMode.Radiance, mi.BSDFFlags.DiffuseReflection)
    value = np.array(bsdf.eval(diffuse_only, si, wo), dtype=np.float64)
    e = value.mean(axis=1) * 2 * np.pi
    c = math.cos(math.radians(theta))
    expected = np.array([1.0, 0.4, 0.1]) * (1 - (1 - c / 2) ** 5)
    np.testing.assert_allclose(e, expected, rtol=2e-3)


@pytest.mark.parametrize("theta", [0, 45, 75, 85])
def test_white_specular_layer_reflects_at_most_all(theta):
    """R_s = 1 (F = 1): the albedo is the mean of min(1, cos ratio) over the
    samples kept, at most 1, and close to 1 at normal incidence for a narrow lobe."""
    e = albedo(load(300.0, 300.0, r_d=[0, 0, 0], r_s=[1, 1, 1]), theta, n=2048)
    assert e.max() <= 1.0 + 3e-3
    if theta == 0:
        assert e.min() > 0.97


# ----------------------------------------------------------------------------
#  3. What is particular to it: anisotropy, reciprocity of the diffuse coupling, ranges
# ----------------------------------------------------------------------------

def test_exponent_u_narrows_the_lobe_along_u():
    """n_u = 1000, n_v = 10: tilting the light away from the mirror direction
    along u (x) dims the highlight far more than along v (y)."""
    bsdf = load(1000.0, 10.0, r_d=[0, 0, 0])
    k1 = np.array([[0.0, 0.0, 1.0]] * 2)
    k2 = np.array([direction(12.0, 0.0), direction(12.0, 90.0)])
    value, _ = eval_and_pdf(bsdf, wi=k1, wo=k2)
    along_u, along_v = value[0, 0], value[1, 0]
    assert along_v > 50 * along_u
    expected = paper_eval(k1, k2, np.zeros(3), R_S, 1000.0, 10.0, "hdr")
    np.testing.assert_allclose(value, expected, rtol=3e-4)


def test_coupled_diffuse_term_is_symmetric(rng):
    """rho_d is symmetric in k1 and k2 (unlike a Lambert term times a Fresnel
    of one direction): swapping them changes eval only by the cosine it carries."""
    k1, k2 = pairs(rng, 100.0, 100.0, 1024)
    bsdf = load(100.0, 100.0)
    a, _ = eval_and_pdf(bsdf, wi=k1, wo=k2)
    b, _ = eval_and_pdf(bsdf, wi=k2, wo=k1)
    np.testing.assert_allclose(a / k2[:, 2:3], b / k1[:, 2:3], rtol=2e-4, atol=1e-6)


def test_a_specular_reflectance_above_one_is_refused():
    """1 - R_s weights the diffuse term: R_s above 1 would make it negative."""
    assert_refused({"type": "ashikhmin_shirley", "specular_reflectance": 1.5},
                   "specular_reflectance", "1.5", "[0, 1]")
