"""The random walk of Heitz et al. 2016 (mi_brdfs/tools/groundtruth/), the
ground truth of energy compensation, against closed forms written here from
the literature (not from the package), for isotropic and anisotropic
roughness: the projected area and Λ, the density of the sampled visible
normals, a first bounce that is the height-correlated Smith single
scattering, a white microsurface that keeps every path, a reciprocal BRDF,
the symmetry of a 90° turn, and the committed reference albedos."""
import json
import math
import os

import numpy as np
import pytest
from scipy.special import erf

from mi_brdfs.tools import groundtruth as gt
from mi_brdfs.tools.groundtruth import Alpha
from support import direction

REFERENCE = json.load(open(os.path.join(os.path.dirname(__file__), "walk_reference.json")))


# ----------------------------------------------------------------------------
#  Independent transcriptions (Walter et al. 2007; Heitz 2014), anisotropic
#  by the azimuth: roughness = α or (α_x, α_y)
# ----------------------------------------------------------------------------

def xy(alpha):
    return alpha if isinstance(alpha, tuple) else (alpha, alpha)


def polar(w):
    """(tan² θ, φ) of directions (n, 3)."""
    return (w[:, 0] ** 2 + w[:, 1] ** 2) / w[:, 2] ** 2, np.arctan2(w[:, 1], w[:, 0])


def ndf(distribution, h, alpha):
    """Walter et al. 2007, eqs. 33 and 28, anisotropic as in Heitz 2014: the
    slope term tan² θ / α² becomes tan² θ (cos² φ / α_x² + sin² φ / α_y²) and
    the normalisation 1 / α² becomes 1 / (α_x α_y)."""
    ax, ay = xy(alpha)
    t2, phi = polar(h)
    k = t2 * (np.cos(phi) ** 2 / ax ** 2 + np.sin(phi) ** 2 / ay ** 2)
    c4 = h[:, 2] ** 4
    if distribution == "ggx":
        return 1.0 / (np.pi * ax * ay * c4 * (1.0 + k) ** 2)
    return np.exp(-k) / (np.pi * ax * ay * c4)


def smith_lambda(distribution, w, alpha):
    """Heitz 2014, eqs. 72 and 86, for w above the horizon; anisotropic with
    the roughness projected on w's azimuth, α(φ)² = cos² φ α_x² + sin² φ α_y²
    (Heitz 2014, anisotropic distributions)."""
    ax, ay = xy(alpha)
    t2, phi = polar(w)
    a_phi = np.sqrt(np.cos(phi) ** 2 * ax ** 2 + np.sin(phi) ** 2 * ay ** 2)
    if distribution == "ggx":
        return 0.5 * (-1.0 + np.sqrt(1.0 + a_phi ** 2 * t2))
    with np.errstate(divide="ignore"):
        a = 1.0 / (a_phi * np.sqrt(t2))               # inf along the normal: Λ = 0
    return 0.5 * (erf(a) - 1.0) + np.exp(-a * a) / (2.0 * a * math.sqrt(math.pi))


def height_correlated(distribution, wi, wo, alpha, f0):
    """f·cos θ_o = F(wi·h) D(h) / (4 cos θ_i (1 + Λ(wi) + Λ(wo))) (Heitz 2014, eq. 99)."""
    h = wi + wo
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    fresnel = f0 + (1 - f0) * (1 - np.sum(wi * h, axis=1)) ** 5
    g2 = 1.0 / (1.0 + smith_lambda(distribution, wi, alpha) + smith_lambda(distribution, wo, alpha))
    return fresnel * ndf(distribution, h, alpha) * g2 / (4.0 * wi[:, 2])


def walk_alpha(alpha):
    return Alpha(*alpha) if isinstance(alpha, tuple) else alpha


def hemisphere_cells(n):
    """Midpoint rule in (cos θ, φ) over the upper hemisphere, n x 2n cells:
    directions and the solid angle of each."""
    c = (np.arange(n) + 0.5) / n
    p = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * np.pi
    C, P = np.meshgrid(c, p, indexing="ij")
    s = np.sqrt(1 - C * C)
    w = np.stack([s * np.cos(P), s * np.sin(P), C], axis=-1).reshape(-1, 3)
    return w, np.full(len(w), 2 * np.pi / (2 * n * n))


ROUGHNESS = [0.2, 0.8, (0.1, 0.5), (0.7, 0.15)]
ids = lambda a: f"{a[0]}x{a[1]}" if isinstance(a, tuple) else str(a)


# ----------------------------------------------------------------------------
#  The microsurface
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("distribution", gt.DISTRIBUTIONS)
@pytest.mark.parametrize("alpha", [0.5, (0.15, 0.9)], ids=ids)
def test_projected_area_and_lambda(distribution, alpha):
    """A(w) = ∫ max(0, w·m) D(m) dm by quadrature, for w above and below the
    horizon at several azimuths; Λ(w) against Heitz 2014 above the horizon and
    -1 - Λ(-w) below it."""
    m, dm = hemisphere_cells(300)
    dm_d = ndf(distribution, m, alpha) * dm
    w = np.array([direction(t, p) for t in (0, 30, 70, 89, 95, 130, 170) for p in (0, 40, 90)])
    integral = np.maximum(w @ m.T, 0.0) @ dm_d
    np.testing.assert_allclose(gt.projected_area(distribution, w, walk_alpha(alpha)), integral,
                               rtol=2e-3, atol=1e-5)
    up = w[:, 2] > 0
    lam = gt.lam(distribution, w, walk_alpha(alpha))
    np.testing.assert_allclose(lam[up], smith_lambda(distribution, w[up], alpha), rtol=1e-9,
                               atol=1e-15)
    np.testing.assert_allclose(lam[~up], -1.0 - smith_lambda(distribution, -w[~up], alpha),
                               rtol=1e-9)


@pytest.mark.parametrize("distribution", gt.DISTRIBUTIONS)
@pytest.mark.parametrize("theta, phi, alpha", [
    (30, 0, 0.5), (100, 0, 0.5), (150, 0, 0.5), (40, 30, (0.2, 0.8)), (60, 90, (0.2, 0.8)),
    (120, 60, (0.9, 0.3))], ids=lambda v: ids(v) if isinstance(v, tuple) else str(v))
def test_visible_normals_have_the_density_d_wi(distribution, theta, phi, alpha):
    """Normals sampled for a viewer above or below the horizon (the walk meets
    facets from below) against D_wi(m) = <wi, m> D(m) / A(wi), A(wi) =
    cos θ (1 + Λ(wi)) above and |cos θ| Λ(-wi) below: counts per cell of
    (cos θ_m, φ_m) within 5 standard deviations."""
    n, bins, k = 200_000, 8, 32
    wi = direction(theta, phi)
    rng = np.random.default_rng(7)
    m = gt.sample_visible(distribution, np.repeat(wi[None], n, axis=0), walk_alpha(alpha),
                          rng.random(n), rng.random(n))
    counts, _, _ = np.histogram2d(m[:, 2], np.arctan2(m[:, 1], m[:, 0]) % (2 * np.pi),
                                  bins=bins, range=[[0, 1], [0, 2 * np.pi]])
    cells, dm = hemisphere_cells(bins * k)               # k x 2k cells per histogram bin
    above = wi[2] > 0
    area = wi[2] * (1 + smith_lambda(distribution, wi[None], alpha)[0]) if above \
        else -wi[2] * smith_lambda(distribution, -wi[None], alpha)[0]
    density = np.maximum(cells @ wi, 0) * ndf(distribution, cells, alpha) / area
    expected = (density * dm).reshape(bins, k, bins, 2 * k).sum(axis=(1, 3)) * n
    assert expected.sum() == pytest.approx(n, rel=2e-3)           # D_wi integrates to 1
    assert np.all(np.abs(counts - expected) <= 5 * np.sqrt(expected) + 3)


# ----------------------------------------------------------------------------
#  The first bounce
# ----------------------------------------------------------------------------

PAIRS = [(0, 0, 30, 180), (20, 0, 20, 180), (45, 30, 60, 210), (60, 90, 40, 90),
         (75, 45, 75, 225), (80, 0, 30, 0), (50, 120, 50, 300)]     # θ_i, φ_i, θ_o, φ_o


@pytest.mark.parametrize("distribution", gt.DISTRIBUTIONS)
@pytest.mark.parametrize("alpha", ROUGHNESS, ids=ids)
def test_first_bounce_is_the_height_correlated_brdf(distribution, alpha):
    """Next-event estimation at the first bounce averages to the closed form."""
    wi = np.array([direction(t, p) for t, p, _, _ in PAIRS])
    wo = np.array([direction(t, p) for _, _, t, p in PAIRS])
    walked = gt.brdf(distribution, wi, wo, walk_alpha(alpha), f0=0.4, paths=20_000,
                     orders=(1, 1))
    expected = height_correlated(distribution, wi, wo, alpha, 0.4)
    np.testing.assert_allclose(walked, expected, rtol=0.02)


@pytest.mark.parametrize("distribution", gt.DISTRIBUTIONS)
@pytest.mark.parametrize("alpha, phi", [(0.6, 0.0), ((0.3, 0.9), 0.0), ((0.3, 0.9), 60.0)],
                         ids=["0.6", "0.3x0.9-along", "0.3x0.9-at-60"])
def test_first_bounce_albedo_is_the_height_correlated_albedo(distribution, alpha, phi):
    """The paths that leave after one bounce carry the albedo of the closed form."""
    wo, dwo = hemisphere_cells(400)
    mus = np.array([1.0, 0.5, 0.1])
    walked = gt.albedo(distribution, mus, walk_alpha(alpha), f0s=[1.0, 0.2], paths=100_000,
                       orders=(1, 1), phi=math.radians(phi))
    for k, mu in enumerate(mus):
        wi = np.repeat(direction(math.degrees(math.acos(mu)), phi)[None], len(wo), axis=0)
        for j, f0 in enumerate((1.0, 0.2)):
            expected = height_correlated(distribution, wi, wo, alpha, f0) @ dwo
            assert walked[k, j] == pytest.approx(expected, abs=4e-3), (mu, f0)


# ----------------------------------------------------------------------------
#  The walk as a whole
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("distribution", gt.DISTRIBUTIONS)
@pytest.mark.parametrize("alpha", [(0.1, 1.0, 3.0), Alpha((0.05, 1.0, 3.0), (0.5, 0.1, 0.3))],
                         ids=["isotropic", "anisotropic"])
def test_a_white_microsurface_keeps_every_path(distribution, alpha):
    """F0 = 1: every path leaves with weight 1, at any roughness and viewer
    azimuth; F0 = 0.5 loses light."""
    e = gt.albedo(distribution, [1.0, 0.3, 0.05], alpha, f0s=[1.0, 0.5], paths=4000,
                  phi=[0.0, 0.7, 1.6])
    np.testing.assert_array_equal(e[:, 0], 1.0)
    assert (e[:, 1] < 0.6).all() and (e[:, 1] > 0.0).all()


RECIPROCAL = [(20, 0, 60, 180), (30, 0, 50, 150), (60, 0, 60, 200), (60, 90, 30, 270),
              (40, 90, 60, 250), (45, 45, 70, 225), (75, 45, 35, 160), (30, 45, 60, 180)]
# (θ_i, φ_i, θ_o, φ_o): viewers along the tangent, across it and at 45°; not where
# Beckmann's Gaussian tails leave so little that a few paths make the estimate


@pytest.mark.parametrize("distribution", gt.DISTRIBUTIONS)
@pytest.mark.parametrize("alpha", [0.8, (0.3, 0.9)], ids=ids)
def test_the_walk_is_reciprocal(distribution, alpha):
    """The multiple-scattering BRDF of the walk is symmetric (Heitz et al.
    2016, section 5): f(wi, wo) cos θ_o / cos θ_o = f(wo, wi) cos θ_i / cos θ_i,
    for viewers along the tangent, across it and at 45°."""
    wi = np.array([direction(t, p) for t, p, _, _ in RECIPROCAL])
    wo = np.array([direction(t, p) for _, _, t, p in RECIPROCAL])
    kw = dict(f0=0.6, paths=60_000, orders=(2, 1000), error=True)
    forward, e_forward = gt.brdf(distribution, wi, wo, walk_alpha(alpha), **kw)
    backward, e_backward = gt.brdf(distribution, wo, wi, walk_alpha(alpha), seed=2, **kw)
    f, b = forward / wo[:, 2], backward / wi[:, 2]
    assert np.all(np.abs(f - b) <= 4 * np.hypot(e_forward / wo[:, 2], e_backward / wi[:, 2])), \
        (f.tolist(), b.tolist())
    assert (f > 0.01).all() and (e_forward < 0.06 * forward).all()


@pytest.mark.parametrize("distribution", gt.DISTRIBUTIONS)
def test_a_quarter_turn_swaps_the_roughnesses(distribution):
    """Seen from azimuth φ + 90°, (α_x, α_y) reflects what (α_y, α_x) does
    from φ, albedo and BRDF; an isotropic surface reflects alike from every
    azimuth; and the azimuth does matter when α_x ≠ α_y (the test can fail)."""
    mus, phis = np.array([0.9, 0.5, 0.15]), np.radians([0.0, 10.0, 80.0])
    kw = dict(f0s=[0.5], paths=40_000, error=True)
    w1, e1 = gt.albedo(distribution, mus, Alpha(0.1, 1.0), phi=phis, **kw)
    w2, e2 = gt.albedo(distribution, mus, Alpha(1.0, 0.1), phi=phis + np.pi / 2, seed=2, **kw)
    assert np.all(np.abs(w1 - w2) <= 5 * np.hypot(e1, e2))
    w3, e3 = gt.albedo(distribution, mus, Alpha(1.0, 0.1), phi=phis, seed=3, **kw)
    assert np.max(np.abs(w1 - w3) / np.hypot(e1, e3)) > 20, (w1.tolist(), w3.tolist())
    w4, e4 = gt.albedo(distribution, mus, 0.4, phi=[0.3, 1.2, 2.0], seed=4, **kw)
    w5, e5 = gt.albedo(distribution, mus, Alpha(0.4, 0.4), seed=5, **kw)
    assert np.all(np.abs(w4 - w5) <= 5 * np.hypot(e4, e5))
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])   # +90° about z
    wi = np.array([direction(t, p) for t, p, _, _ in RECIPROCAL])
    wo = np.array([direction(t, p) for _, _, t, p in RECIPROCAL])
    kw = dict(f0=0.6, paths=40_000, orders=(2, 1000), error=True)
    f1, e1 = gt.brdf(distribution, wi, wo, Alpha(0.3, 0.9), **kw)
    f2, e2 = gt.brdf(distribution, wi @ turn.T, wo @ turn.T, Alpha(0.9, 0.3), seed=6, **kw)
    assert np.all(np.abs(f1 - f2) <= 4 * np.hypot(e1, e2)), (f1.tolist(), f2.tolist())


def test_the_reference_albedos_are_the_walk():
    """The committed reference (tests/bsdfs/walk_reference.json, 100,000 paths
    per point) walked again at some of its points with another seed: within 5
    standard errors of the difference everywhere (the spread of the paths'
    weights measured by the new walk, for both)."""
    agreement = gt.reference_agreement(REFERENCE, paths=20_000, thetas=(0, 60, 85),
                                       alphas=(0.1, 0.6, 1.5))
    for distribution, a in agreement.items():
        assert a["worst_z"] < 5.0, (distribution, a)
        assert 1e-4 < a["largest"] < 1e-2, (distribution, a)    # noise there is, and little


def test_unknown_distribution_is_refused():
    with pytest.raises(ValueError, match="random walk: distribution 'blinn'; valid: ggx, beckmann"):
        gt.albedo("blinn", [1.0], 0.5)


@pytest.mark.parametrize("args, shown", [
    ([], "nothing to do: give -o FILE, --residuals"),
    (["--paths", "1", "--residuals"], "--paths 1: at least 2 paths per point"),
    (["--agreement"], "--agreement compares with the values of --reference FILE"),
    (["--reference", "/nonexistent/ref.json", "--residuals"], "--reference /nonexistent/ref.json"),
    (["-o", "/nonexistent/folder/ref.json"], "folder /nonexistent/folder does not exist")])
def test_the_command_refuses_bad_input_in_one_line(args, shown, capsys):
    from mi_brdfs.tools.groundtruth.command import main
    with pytest.raises(SystemExit) as exit_:
        main(args)
    assert exit_.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert shown in err[-1] and err[-1].startswith("python -m mi_brdfs.tools.groundtruth: error:")


def test_the_command_prints_the_anisotropic_albedo(capsys):
    """--anisotropic: a line per distribution, (α_x, α_y), θ and φ; white
    surfaces reflect exactly 1, F0 = 0.5 less."""
    from mi_brdfs.tools.groundtruth.command import ANISOTROPIC, main
    assert main(["--anisotropic", "--paths", "500"]) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if ", alpha (" in line]
    assert len(lines) == len(gt.DISTRIBUTIONS) * len(ANISOTROPIC) * 3 * 2
    for line in lines:
        white, coloured = line.split("F0 1: ")[1].split(", F0 0.5: ")
        assert float(white) == 1.0 and 0.3 < float(coloured.split(" +- ")[0]) < 0.95, line
