"""The random walk of Heitz et al. 2016 (mi_brdfs/tools/groundtruth.py), the
ground truth of energy compensation, against closed forms written here from
the literature (not from the module): its first bounce is the height-
correlated Smith single scattering, its visible normals have the density
D_wi, a white microsurface keeps every path, its BRDF is reciprocal."""
import math

import numpy as np
import pytest
from scipy.special import erf

from mi_brdfs.tools import groundtruth as gt


# ----------------------------------------------------------------------------
#  Independent transcriptions (Walter et al. 2007; Heitz 2014)
# ----------------------------------------------------------------------------

def tan2(w):
    return (w[:, 0] ** 2 + w[:, 1] ** 2) / w[:, 2] ** 2


def ndf(distribution, h, alpha):
    """Walter et al. 2007, eqs. 33 and 28: D(h) for h above the horizon."""
    t2, c4 = tan2(h), h[:, 2] ** 4
    if distribution == "ggx":
        return alpha ** 2 / (np.pi * c4 * (alpha ** 2 + t2) ** 2)
    return np.exp(-t2 / alpha ** 2) / (np.pi * alpha ** 2 * c4)


def smith_lambda(distribution, w, alpha):
    """Heitz 2014, eqs. 72 and 86: Λ(w) for w above the horizon."""
    if distribution == "ggx":
        return 0.5 * (-1.0 + np.sqrt(1.0 + alpha ** 2 * tan2(w)))
    with np.errstate(divide="ignore"):
        a = 1.0 / (alpha * np.sqrt(tan2(w)))          # inf along the normal: Λ = 0
    return 0.5 * (erf(a) - 1.0) + np.exp(-a * a) / (2.0 * a * math.sqrt(math.pi))


def height_correlated(distribution, wi, wo, alpha, f0):
    """f·cos θ_o = F(wi·h) D(h) / (4 cos θ_i (1 + Λ(wi) + Λ(wo))) (Heitz 2014, eq. 99)."""
    h = wi + wo
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    fresnel = f0 + (1 - f0) * (1 - np.sum(wi * h, axis=1)) ** 5
    g2 = 1.0 / (1.0 + smith_lambda(distribution, wi, alpha) + smith_lambda(distribution, wo, alpha))
    return fresnel * ndf(distribution, h, alpha) * g2 / (4.0 * wi[:, 2])


def direction(theta_deg, phi_deg=0.0):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


def hemisphere_quadrature(n):
    """Midpoint rule in (cos θ, φ) over the upper hemisphere: directions and weights."""
    c = (np.arange(n) + 0.5) / n
    p = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * np.pi
    C, P = np.meshgrid(c, p, indexing="ij")
    s = np.sqrt(1 - C * C)
    w = np.stack([s * np.cos(P), s * np.sin(P), C], axis=-1).reshape(-1, 3)
    return w, np.full(len(w), 2 * np.pi / (2 * n * n))


# ----------------------------------------------------------------------------
#  The first bounce
# ----------------------------------------------------------------------------

PAIRS = [(0, 30, 180), (20, 20, 180), (45, 60, 180), (60, 40, 90), (75, 75, 180), (80, 30, 0)]


@pytest.mark.parametrize("distribution", gt.DISTRIBUTIONS)
@pytest.mark.parametrize("alpha", [0.2, 0.8])
def test_first_bounce_is_the_height_correlated_brdf(distribution, alpha):
    """Next-event estimation at the first bounce averages to the closed form."""
    wi = np.array([direction(t) for t, _, _ in PAIRS])
    wo = np.array([direction(t, p) for _, t, p in PAIRS])
    walked = gt.brdf(distribution, wi, wo, alpha, f0=0.4, paths=20_000, orders=(1, 1))
    expected = height_correlated(distribution, wi, wo, alpha, 0.4)
    np.testing.assert_allclose(walked, expected, rtol=0.02)


@pytest.mark.parametrize("distribution", gt.DISTRIBUTIONS)
def test_first_bounce_albedo_is_the_height_correlated_albedo(distribution):
    """The paths that leave after one bounce carry the albedo of the closed form."""
    wo, weights = hemisphere_quadrature(400)
    mus = np.array([1.0, 0.5, 0.1])
    walked = gt.albedo(distribution, mus, 0.6, f0s=[1.0, 0.2], paths=100_000, orders=(1, 1))
    for k, mu in enumerate(mus):
        wi = np.repeat(direction(math.degrees(math.acos(mu)))[None], len(wo), axis=0)
        for j, f0 in enumerate((1.0, 0.2)):
            expected = height_correlated(distribution, wi, wo, 0.6, f0) @ weights
            assert walked[k, j] == pytest.approx(expected, abs=4e-3), (mu, f0)


# ----------------------------------------------------------------------------
#  The walk as a whole
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("distribution", gt.DISTRIBUTIONS)
def test_a_white_microsurface_keeps_every_path(distribution):
    """F0 = 1: every path leaves with weight 1, at any roughness; F0 = 0.5 loses light."""
    e = gt.albedo(distribution, [1.0, 0.3, 0.05], [0.1, 1.0, 3.0], f0s=[1.0, 0.5], paths=4000)
    np.testing.assert_array_equal(e[:, 0], 1.0)
    assert (e[:, 1] < 0.6).all() and (e[:, 1] > 0.0).all()


@pytest.mark.parametrize("distribution", gt.DISTRIBUTIONS)
@pytest.mark.parametrize("theta", [30, 100, 150])
def test_visible_normals_have_the_density_d_wi(distribution, theta):
    """Normals sampled for a viewer above or below the horizon (the walk meets
    facets from below) against D_wi(m) = <wi, m> D(m) / A(wi), A(wi) =
    cos θ (1 + Λ(wi)) above and |cos θ| Λ(-wi) below: counts per cell of
    (cos θ_m, φ_m) within 5 standard deviations."""
    alpha, n = 0.5, 200_000
    wi = direction(theta)
    rng = np.random.default_rng(7)
    m = gt.sample_visible(distribution, np.repeat(wi[None], n, axis=0), np.full(n, alpha),
                          rng.random(n), rng.random(n))
    bins = 8
    counts, _, _ = np.histogram2d(m[:, 2], np.arctan2(m[:, 1], m[:, 0]) % (2 * np.pi),
                                  bins=bins, range=[[0, 1], [0, 2 * np.pi]])
    # the density, by a fine midpoint rule in each cell
    k = 32
    c = (np.arange(bins * k) + 0.5) / (bins * k)
    p = (np.arange(bins * k) + 0.5) / (bins * k) * 2 * np.pi
    C, P = np.meshgrid(c, p, indexing="ij")
    s = np.sqrt(1 - C * C)
    mm = np.stack([s * np.cos(P), s * np.sin(P), C], axis=-1).reshape(-1, 3)
    up = wi[2] > 0
    w_up = wi if up else -wi
    area = wi[2] * (1 + smith_lambda(distribution, w_up[None], alpha)[0]) if up \
        else -wi[2] * smith_lambda(distribution, w_up[None], alpha)[0]
    density = np.maximum(mm @ wi, 0) * ndf(distribution, mm, alpha) / area
    expected = density.reshape(bins, k, bins, k).sum(axis=(1, 3)) \
        * (1 / (bins * k)) * (2 * np.pi / (bins * k)) * n
    assert expected.sum() == pytest.approx(n, rel=2e-3)           # D_wi integrates to 1
    assert np.all(np.abs(counts - expected) <= 5 * np.sqrt(expected) + 3)


@pytest.mark.parametrize("distribution", gt.DISTRIBUTIONS)
def test_the_walk_is_reciprocal(distribution):
    """The multiple-scattering BRDF of the walk is symmetric (Heitz et al.
    2016, section 5): f(wi, wo) cos θ_o / cos θ_o = f(wo, wi) cos θ_i / cos θ_i."""
    wi = np.array([direction(20), direction(70), direction(50, 45)])
    wo = np.array([direction(60, 180), direction(40, 90), direction(80, 200)])
    forward = gt.brdf(distribution, wi, wo, 0.8, f0=0.6, paths=60_000, orders=(2, 1000))
    backward = gt.brdf(distribution, wo, wi, 0.8, f0=0.6, paths=60_000, orders=(2, 1000))
    np.testing.assert_allclose(forward / wo[:, 2], backward / wi[:, 2], rtol=0.05)
    assert (forward > 0.003).all()


def test_unknown_distribution_is_refused():
    with pytest.raises(ValueError, match="random walk: distribution 'blinn'"):
        gt.albedo("blinn", [1.0], 0.5)
