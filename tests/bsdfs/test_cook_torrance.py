"""cook_torrance: against the lecture (NumPy, tests/bsdfs/lecture.py), Mitsuba's
roughconductor and roughplastic, the Blinn distribution at tiny roughness,
grazing mirror pairs, and the energy of the single-scattering model. What
every model shares: the battery."""
import math

import numpy as np
import pytest

import drjit as dr
import mitsuba as mi

from mi_brdfs._jit import from_numpy
from mi_brdfs.bsdfs.params import ParameterError
import lecture
from support import (active_variant, albedo, assert_refused, assert_weight_is_value_over_pdf,
                     error_line, eval_and_pdf, finite_difference, mirror_pairs, random_hemisphere,
                     rgb, sampled, surface, vec)

DISTRIBUTIONS = ["blinn", "beckmann", "ggx"]
GEOMETRIES = ["cook_torrance", "smith"]


def pairs(rng, n, min_cos=0.02, alpha=None):
    """(d, w) direction pairs above the surface; with alpha, half of them have
    their half vector within a few alpha of the normal (inside the lobe)."""
    d, w = random_hemisphere(rng, n, min_cos), random_hemisphere(rng, n, min_cos)
    if alpha is not None:
        m = n // 2
        h = np.column_stack([alpha * rng.normal(size=(m, 2)), np.ones(m)])
        h /= np.linalg.norm(h, axis=1, keepdims=True)
        d[:m] = 2 * lecture.dot(w[:m], h)[:, None] * h - w[:m]
        keep = d[:, 2] > min_cos
        d, w = d[keep], w[keep]
    return d, w


# ----------------------------------------------------------------------------
#  The lecture's formulas, transcribed independently in tests/lecture.py
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("distribution", DISTRIBUTIONS)
@pytest.mark.parametrize("geometry", GEOMETRIES)
@pytest.mark.parametrize("mode", ["scanline", "hdr"])
def test_matches_lecture(rng, distribution, geometry, mode):
    d, w = pairs(rng, 4096, alpha=0.35)
    m_d, m_s = np.array([1.4, 0.5, 0.2]), np.array([0.9, 2.0, 0.3])
    k, f0, rho = 0.3, 0.2, 0.35
    bsdf = mi.load_dict({"type": "cook_torrance", "mode": mode, "diffuse_reflectance": rgb(m_d),
                         "specular_reflectance": rgb(m_s), "k": k, "f0": f0, "alpha": rho,
                         "distribution": distribution, "geometry": geometry})
    v, _ = eval_and_pdf(bsdf, wi=w, wo=d)
    reference = lecture.cook_torrance_scanline if mode == "scanline" else lecture.cook_torrance_hdr_eval
    expected = reference(d, w, m_d, m_s, k, f0, rho, distribution, geometry)
    # Blinn's Smith G1 is a table (microfacet.G1_BLINN_VALUES): its interpolation
    # error against the brute-force quadrature of lecture.g_blinn is <= 1.2e-3 relative.
    rtol = 3e-3 if (distribution, geometry) == ("blinn", "smith") else 2e-4
    np.testing.assert_allclose(v, expected, rtol=rtol, atol=1e-6)
    if mode == "scanline":     # the per-lobe clamps are exercised, both ways
        spec = lecture.cook_torrance_terms(d, w, rho, f0, distribution, geometry)[:, None] * m_s
        assert (spec > 1).any() and ((spec > 0.01) & (spec < 1)).any()


def test_below_surface_is_black(rng):
    d, w = pairs(rng, 512)
    bsdf = mi.load_dict({"type": "cook_torrance", "mode": "scanline"})
    for wi, wo in [(w, d * [1, 1, -1]), (w * [1, 1, -1], d)]:
        v, p = eval_and_pdf(bsdf, wi, wo)
        assert not v.any() and not p.any()


# ----------------------------------------------------------------------------
#  Mitsuba's built-ins
# ----------------------------------------------------------------------------

# Mitsuba's Beckmann G1 is a rational fit of the exact erf form (within 0.35 %
# per G1, so within ~0.7 % for G1·G1, and 0.35 % for the pdf of visible
# normals, which holds one G1); GGX's is exact.
RTOL = {"ggx": 1e-4, "beckmann": 7e-3}


def assert_same_as_roughconductor(ours, ref, w, d, distribution: str) -> None:
    """eval (relative where the lobe is not negligible, absolute elsewhere)
    and pdf of ours equal roughconductor's at the pairs (w, d)."""
    v, p = eval_and_pdf(ours, w, d)
    v_ref, p_ref = eval_and_pdf(ref, w, d)
    big = v_ref[:, 0] > 1e-6 * v_ref[:, 0].max()
    assert big.sum() > 1000
    np.testing.assert_allclose(v[big], v_ref[big], rtol=RTOL[distribution])
    np.testing.assert_allclose(v[~big], v_ref[~big], atol=1e-6 * v_ref[:, 0].max())
    np.testing.assert_allclose(p, p_ref, rtol=RTOL[distribution], atol=1e-6)


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
@pytest.mark.parametrize("alpha", [0.05, 0.2, 0.5, 1.0])
def test_equals_roughconductor(rng, distribution, alpha):
    d, w = pairs(rng, 8192, alpha=alpha)
    ours = mi.load_dict({"type": "cook_torrance", "k": 0.0, "f0": 1.0, "geometry": "smith",
                         "distribution": distribution, "alpha": alpha})
    ref = mi.load_dict({"type": "roughconductor", "distribution": distribution, "alpha": alpha})
    assert_same_as_roughconductor(ours, ref, w, d, distribution)


def test_beckmann_g1(rng):
    """The Smith G1 of Beckmann (a rational fit, microfacet.Microfacet.G1_over_cos)
    against the exact erf form in float64 (lecture.g_beckmann, math.erf), from
    the normal to cos θ = 1e-30 and for rho from ALPHA_MIN to 5: within 6e-6
    (its docstring: 5.5e-6 in float32), and G1/cos finite where G1 -> 0."""
    from mi_brdfs.bsdfs import microfacet as mf
    mu = np.concatenate([np.linspace(1e-6, 1.0 - 1e-7, 20001), 10.0 ** rng.uniform(-30, 0, 4000)])
    s = np.sqrt(1.0 - mu**2)
    v = from_numpy(mi.Vector3f, (s, np.zeros(mu.size), mu))
    mu32, s32 = np.array(v.z, dtype=np.float64), np.array(v.x, dtype=np.float64)
    for rho in (mf.ALPHA_MIN, 0.01, 0.1, 0.3, 1.0, 5.0):
        beckmann = mf.Microfacet("beckmann", mi.Float(rho))
        g1 = np.array(beckmann.G1(v), dtype=np.float64)
        g1_over_cos = np.array(beckmann.G1_over_cos(v), dtype=np.float64)
        ok = mu32 < 1.0                         # (at the normal exactly: a = inf, G1 = 1)
        exact = lecture.g_beckmann(mu32[ok] / np.hypot(mu32[ok], s32[ok]), rho)
        np.testing.assert_allclose(g1[ok], exact, rtol=6e-6, err_msg=f"rho = {rho}")
        assert np.isfinite(g1_over_cos).all() and (g1_over_cos > 0).all()
    assert np.array(mf.Microfacet("beckmann", mi.Float(0.3)).G1(mi.Vector3f(0, 0, 1)))[0] == \
        pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
def test_sample_weight_is_fresnel_times_g1(rng, distribution):
    """Visible normals with Smith's G: a sample weighs m_S·F(w_r·h)·G1(d) in
    closed form (no division), its pdf D(h)·G1(w_r)/(4 w_r·n): both against
    the lecture's formulas (NumPy) at the sampled direction, grazing viewers
    included (weight = eval/pdf there too: the battery)."""
    n = 8192
    w = random_hemisphere(rng, n)
    t = np.radians(rng.uniform(80.0, 89.999, n // 4))
    w[: n // 4] = np.column_stack([np.sin(t), np.zeros_like(t), np.cos(t)])
    m_s, f0, rho = np.array([0.9, 0.6, 0.3]), 0.3, 0.3
    bsdf = mi.load_dict({"type": "cook_torrance", "k": 0.0, "f0": f0, "geometry": "smith",
                         "distribution": distribution, "alpha": rho,
                         "specular_reflectance": rgb(m_s)})
    from support import floats, points, surface
    bs, weight = bsdf.sample(mi.BSDFContext(), surface(w), floats(rng.random(n)),
                             points(rng.random(n), rng.random(n)))
    d = np.array(bs.wo, dtype=np.float64).T
    weight, pdf = np.array(weight, dtype=np.float64).T, np.array(bs.pdf, dtype=np.float64)
    ok = pdf > 0
    assert ok.mean() > 0.8
    w, d, weight, pdf = w[ok], d[ok], weight[ok], pdf[ok]
    h = lecture.half(d, w)
    g = lecture.g_ggx if distribution == "ggx" else lecture.g_beckmann
    D = lecture.D_ggx if distribution == "ggx" else lecture.D_beckmann
    expected = m_s * (lecture.F_schlick(f0, lecture.dot(w, h)) * g(d[:, 2], rho))[:, None]
    np.testing.assert_allclose(weight, expected, rtol=2e-4, atol=1e-7)
    np.testing.assert_allclose(pdf, D(h[:, 2], rho) * g(w[:, 2], rho) / (4 * w[:, 2]),
                               rtol=2e-4)


@pytest.mark.parametrize("alpha", [0.1, 0.4])
def test_roughplastic_differs_only_by_schlick(rng, alpha):
    """Ratio of evals == Schlick(F0)/Fresnel_exact(w_r·h), direction by direction."""
    eta = 1.5
    f0 = ((eta - 1) / (eta + 1)) ** 2
    d, w = pairs(rng, 8192, alpha=alpha)
    ours = mi.load_dict({"type": "cook_torrance", "k": 0.0, "f0": f0, "geometry": "smith",
                         "distribution": "ggx", "alpha": alpha})
    ref = mi.load_dict({"type": "roughplastic", "distribution": "ggx", "alpha": alpha,
                        "diffuse_reflectance": 0.0, "int_ior": eta, "ext_ior": 1.0})
    v, _ = eval_and_pdf(ours, w, d)
    v_ref, _ = eval_and_pdf(ref, w, d)
    wh = lecture.dot(w, lecture.half(d, w))
    expected = lecture.F_schlick(f0, wh) / lecture.fresnel_dielectric(wh, eta)
    ok = v_ref[:, 0] > 1e-6 * v_ref[:, 0].max()
    assert ok.sum() > 1000
    np.testing.assert_allclose(v[ok, 0] / v_ref[ok, 0], expected[ok], rtol=1e-4)
    assert expected.min() < 0.9 and expected.max() > 1.05     # Schlick's error is visible


# ----------------------------------------------------------------------------
#  Lobes present, and renders against roughconductor
# ----------------------------------------------------------------------------

def test_only_present_lobes_are_declared():
    F = mi.BSDFFlags
    both = mi.load_dict({"type": "cook_torrance"})
    assert both.flags() == F.DiffuseReflection | F.GlossyReflection | F.FrontSide
    assert both.component_count() == 2
    spec = mi.load_dict({"type": "cook_torrance", "k": 0.0})
    assert spec.flags() == F.GlossyReflection | F.FrontSide and spec.component_count() == 1
    diff = mi.load_dict({"type": "cook_torrance", "k": 1.0})
    assert diff.flags() == F.DiffuseReflection | F.FrontSide and diff.component_count() == 1
    dark = mi.load_dict({"type": "cook_torrance", "specular_reflectance": 0.0})
    assert dark.flags() == F.DiffuseReflection | F.FrontSide


def sphere_scene(bsdf, res=48):
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "direct"},
        "sensor": {"type": "perspective", "fov": 35,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 4}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "key": {"type": "point", "position": [2, 2, 3], "intensity": {"type": "rgb", "value": 20}},
        "fill": {"type": "point", "position": [-3, 0.5, 2], "intensity": {"type": "rgb", "value": 5}},
    })


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
def test_render_equals_roughconductor(distribution):
    """Point lights only: both renders use the same camera samples, so they must
    agree pixel by pixel up to the eval tolerance (no Monte Carlo noise between them)."""
    ours = sphere_scene({"type": "cook_torrance", "k": 0.0, "f0": 1.0, "geometry": "smith",
                         "distribution": distribution, "alpha": 0.25})
    ref = sphere_scene({"type": "roughconductor", "distribution": distribution, "alpha": 0.25})
    img = np.array(mi.render(ours, seed=7))
    img_ref = np.array(mi.render(ref, seed=7))
    assert img_ref.max() > 0.5 and (img_ref > 0).mean() > 0.2
    np.testing.assert_allclose(img, img_ref, rtol=RTOL[distribution], atol=1e-5 * img_ref.max())


# ----------------------------------------------------------------------------
#  The Blinn distribution stays normalised and samplable at tiny roughness
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("alpha", [0.0, 1e-3, 0.01, 0.3, 1.0])
def test_blinn_distribution_is_normalised(alpha):
    """Integral of D(m) cos(theta_m) over the hemisphere is 1 (physics), by a
    quadrature in theta log-spaced towards the normal; alpha = 0 is the clamped minimum."""
    from mi_brdfs.bsdfs import microfacet as mf
    t = np.logspace(-9, np.log10(np.pi / 2), 200_000)
    m = from_numpy(mi.Vector3f, (np.sin(t), 0 * t, np.cos(t)))
    blinn = mf.Microfacet("blinn", mi.Float(max(alpha, mf.ALPHA_MIN)))
    d = np.array(blinn.D(m), dtype=np.float64)
    assert np.isfinite(d).all()
    integral = np.trapezoid(d * np.cos(t) * np.sin(t) * 2 * np.pi, t)
    assert integral == pytest.approx(1.0, abs=1e-4)


@pytest.mark.parametrize("alpha", [1e-4, 1e-3, 0.05])
def test_blinn_sampler_keeps_narrow_lobes(alpha):
    """Sampled normals have density (e+1)/(2 pi) cos^e, e = 2/alpha² - 1, so
    E[sin²(theta_m)] = 2/(e+3) = alpha²: float32 cancellation would collapse it."""
    from mi_brdfs.bsdfs import microfacet as mf
    rng = np.random.default_rng(9)
    n = 1_000_000
    blinn = mf.Microfacet("blinn", mi.Float(alpha))
    m = blinn.sample(mi.Vector3f(0, 0, 1), from_numpy(mi.Point2f, rng.random((2, n))))
    sin2 = np.array(m.x, dtype=np.float64) ** 2 + np.array(m.y, dtype=np.float64) ** 2
    e = 2 / alpha**2 - 1
    assert sin2.mean() == pytest.approx(2 / (e + 3), rel=0.01)
    assert len(np.unique(sin2)) > n // 2            # a continuum, not a few rings


# ----------------------------------------------------------------------------
#  Energy of the single-scattering model (the bounds of every D x G: the battery)
# ----------------------------------------------------------------------------

TOL = 3e-3        # the suite's uniform-hemisphere quadrature (support.albedo), 2048² points


def albedos(bsdf, thetas):
    """{θ_i: E(θ_i)}, the channel maximum (the lobes here are white)."""
    return {th: float(albedo(bsdf, th, n=2048).max()) for th in thetas}


def _fmt(values):
    return ", ".join(f"{th} deg: {e:.5f}" for th, e in values.items())


def test_smooth_white_conductor_keeps_its_energy():
    """A nearly smooth (alpha = 0.1), F = 1 surface whose lobe stays above the
    horizon reflects (almost) everything, for every D and G: the bound above is
    reached, so a model that is simply too dark everywhere fails here."""
    for dist in ("blinn", "beckmann", "ggx"):
        for geo in ("cook_torrance", "smith"):
            bsdf = mi.load_dict({"type": "cook_torrance", "distribution": dist,
                                 "geometry": geo, "alpha": 0.1, "k": 0.0, "f0": 1.0})
            values = albedos(bsdf, (0, 30))
            # GGX's long tail: ~1-2% of its microfacet normals reflect below the horizon.
            lower = 0.975 if dist == "ggx" else 0.995
            assert all(lower <= e <= 1.0 + TOL for e in values.values()), \
                f"{dist}/{geo}: {_fmt(values)}"


def _ggx_smith_reference(theta_deg, alpha, n_mu=128, n_phi=256):
    """Independent float64 NumPy quadrature of the textbook GGX/Smith BRDF
    (Walter et al. 2007), F = 1: Gauss-Legendre in cos(theta_o), midpoint
    (spectrally accurate for a periodic integrand) in phi_o; at alpha = 1 the
    integrand is smooth and 128 x 256 nodes agree with 512 x 1024 to 1e-15."""
    x, w = np.polynomial.legendre.leggauss(n_mu)
    mu, w_mu = 0.5 * (x + 1.0), 0.5 * w
    phi = (np.arange(n_phi) + 0.5) * 2.0 * np.pi / n_phi
    mu_o, ph = np.meshgrid(mu, phi, indexing="ij")
    s_o = np.sqrt(1.0 - mu_o ** 2)
    wo = np.stack([s_o * np.cos(ph), s_o * np.sin(ph), mu_o], axis=-1)
    t = math.radians(theta_deg)
    wi = np.array([math.sin(t), 0.0, math.cos(t)])
    h = wi + wo
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    a2 = alpha * alpha
    d = a2 / (np.pi * (h[..., 2] ** 2 * (a2 - 1.0) + 1.0) ** 2)

    def g1(c):
        tan2 = (1.0 - c * c) / (c * c)
        return 2.0 / (1.0 + np.sqrt(1.0 + a2 * tan2))

    f_cos = d * g1(wi[2]) * g1(mu_o) / (4.0 * wi[2])      # f_r * cos(theta_o)
    return float(np.sum(f_cos * w_mu[:, None]) * 2.0 * np.pi / n_phi)


def test_ggx_smith_energy_loss(capsys):
    """GGX + Smith at alpha = 1, F = 1, no diffuse lobe: the single-scattering
    model loses the energy of the multiply scattered light. Printed for the log."""
    bsdf = mi.load_dict({"type": "cook_torrance", "distribution": "ggx",
                         "geometry": "smith", "alpha": 1.0, "k": 0.0, "f0": 1.0})
    thetas = (0, 30, 60, 75, 85, 89)
    values = albedos(bsdf, thetas)
    refs = {th: _ggx_smith_reference(th, 1.0) for th in thetas}
    with capsys.disabled():
        print("\nGGX/Smith, alpha = 1, f0 = 1, k = 0: single-scattering albedo "
              "(NumPy reference) and energy loss 1 - E")
        for th in thetas:
            print(f"  theta_i = {th:2d} deg: E = {values[th]:.5f} ({refs[th]:.5f}),"
                  f" loss = {1.0 - values[th]:.1%}")
    # Closed form at normal incidence: D = 1/pi, G1(w_o) = 2 mu/(1 + mu), so
    # E = integral_0^1 mu / (1 + mu) dmu = 1 - ln 2.
    assert values[0] == pytest.approx(1.0 - math.log(2.0), abs=1e-3)
    assert 0.3 < values[0] < 0.95
    for th in thetas:
        assert values[th] < 0.95, f"no energy loss at {th} deg: {_fmt(values)}"
        assert values[th] == pytest.approx(refs[th], abs=TOL), \
            f"theta_i = {th}: plugin {values[th]:.5f} vs NumPy {refs[th]:.5f}"


@pytest.mark.parametrize("dist", ["ggx", "blinn"])
def test_v_cavity_normal_incidence_closed_form(dist):
    """alpha = 1 makes GGX and Blinn uniform, D = 1/pi. At normal incidence the
    V-cavity term is min(1, 2 cos(theta_o)), F = 1:
    E = 1/2 integral_0^1 min(1, 2 mu) dmu = 3/8."""
    bsdf = mi.load_dict({"type": "cook_torrance", "distribution": dist,
                         "geometry": "cook_torrance", "alpha": 1.0, "k": 0.0, "f0": 1.0})
    assert albedos(bsdf, (0,))[0] == pytest.approx(0.375, abs=1e-3)


# ----------------------------------------------------------------------------
#  Grazing mirror pairs: exact down to cos θ = 1e-19, 0 below
# ----------------------------------------------------------------------------

GRAZING = [1e-10, 1e-12, 1e-19]


@pytest.mark.parametrize("distribution", ["ggx", "beckmann", "blinn"])
@pytest.mark.parametrize("alpha", [0.1, 0.3, 1.0])
def test_smith_at_grazing_mirror_pairs(distribution, alpha):
    """A viewer and a light at cos θ = c on either side of the normal: the
    half vector is n, and Smith's G1 -> 0 takes the value with it (D F G1 G1 /
    (4 c) ~ c / alpha^4). The plugin equals the float64 transcription (GGX,
    Beckmann) and stays below 1e-3; at cos θ = 1e-30 and 0 a viewer is on the
    surface (base.HORIZON = 1e-20) and gets nothing."""
    wi = np.array([[math.sqrt(1 - c * c), 0.0, c] for c in GRAZING + [1e-30, 0.0]])
    wo = wi * [-1, 1, 1]
    bsdf = mi.load_dict({"type": "cook_torrance", "distribution": distribution,
                         "geometry": "smith", "alpha": alpha, "k": 0.0, "f0": 1.0})
    value, pdf = eval_and_pdf(bsdf, wi, wo)
    assert np.isfinite(value).all() and np.isfinite(pdf).all()
    n = len(GRAZING)
    assert (value[:n] <= 1e-3).all() and (value[n:] == 0).all()
    if distribution != "blinn":
        ref = lecture.cook_torrance_hdr_eval(wo[:n], wi[:n], np.zeros(3), np.ones(3), 0.0, 1.0,
                                             alpha, distribution, "smith")
        np.testing.assert_allclose(value[:n], ref, rtol=RTOL[distribution])


# ----------------------------------------------------------------------------
#  Options and values particular to cook_torrance
# ----------------------------------------------------------------------------

def test_blinn_roughness_is_at_most_one():
    """The Blinn exponent 2/rho² - 2 must stay >= 0: rho <= 1 (other D: no bound)."""
    assert_refused({"type": "cook_torrance", "distribution": "blinn", "alpha": 1.5}, "alpha",
                   "1.5", "is invalid; valid: [0, 1]")
    mi.load_dict({"type": "cook_torrance", "distribution": "ggx", "alpha": 4.0})


@pytest.mark.parametrize("alpha", [0.0, 1e-9, 4.0])
def test_extreme_roughness_is_accepted(alpha):
    """rho = 0 and tiny values are clamped to ALPHA_MIN = 1e-4, as Mitsuba does."""
    mi.load_dict({"type": "cook_torrance", "distribution": "ggx", "alpha": alpha})


# ----------------------------------------------------------------------------
#  The far end of the roughness range
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
@pytest.mark.parametrize("geometry", GEOMETRIES)
def test_roughness_far_end(distribution, geometry):
    """alpha is accepted up to the largest float32 and evaluated at ALPHA_MAX
    (1e6) beyond it: the single-scattering lobe is at its limit there (no
    reflection: an albedo below 1e-6 up to 89.9°), the same at 1e7 and at the
    largest float32, and infinity is refused."""
    from mi_brdfs.bsdfs.params import FLOAT_MAX
    from mi_brdfs.bsdfs.microfacet import ALPHA_MAX
    config = {"type": "cook_torrance", "distribution": distribution, "geometry": geometry,
              "k": 0.0, "f0": 1.0}
    thetas = (0.0, 60.0, 85.0, 89.0, 89.9)
    at_max = np.array([albedo(mi.load_dict({**config, "alpha": ALPHA_MAX}), t) for t in thetas])
    assert (at_max >= 0).all() and at_max.max() < 1e-6, at_max
    for beyond in (1e7, FLOAT_MAX):
        far = np.array([albedo(mi.load_dict({**config, "alpha": beyond}), t) for t in thetas])
        np.testing.assert_array_equal(far, at_max)
    # the walk's albedo at the table's infinite node, for the compensated lobe
    white = mi.load_dict({**config, "alpha": FLOAT_MAX, "energy_compensation": True})
    np.testing.assert_allclose([albedo(white, t).mean() for t in (0.0, 60.0, 85.0)], 1.0,
                               rtol=0.01)
    assert_refused({**config, "alpha": math.inf}, "alpha", "inf", f"[0, {FLOAT_MAX:.7g}]")
    # anisotropic: each axis evaluated at ALPHA_MAX_ANISOTROPIC (1e4) beyond it
    from mi_brdfs.bsdfs.microfacet import ALPHA_MAX_ANISOTROPIC as HI
    at_hi = np.array([albedo(mi.load_dict({**config, "alpha_u": HI, "alpha_v": HI}), t, phi)
                      for t in thetas[:-1] for phi in (0.0, 90.0)])
    assert (at_hi >= 0).all() and at_hi.max() < 4e-5, at_hi
    far = np.array([albedo(mi.load_dict({**config, "alpha_u": FLOAT_MAX, "alpha_v": FLOAT_MAX}),
                           t, phi) for t in thetas[:-1] for phi in (0.0, 90.0)])
    np.testing.assert_array_equal(far, at_hi)


# ----------------------------------------------------------------------------
#  Anisotropic roughness (alpha_u along s, alpha_v along t), as roughconductor
# ----------------------------------------------------------------------------

ANISOTROPIC = [(0.05, 0.3), (0.3, 0.05), (0.7, 0.1), (0.02, 0.02)]


def anisotropic_pairs(rng, n, au, av, min_cos=0.02):
    """(d, w): half the lights reflect the viewer about a half vector drawn
    within a few roughnesses of the normal along each axis (inside the lobe)."""
    d, w = random_hemisphere(rng, n, min_cos), random_hemisphere(rng, n, min_cos)
    m = n // 2
    h = np.column_stack([au * rng.normal(size=m), av * rng.normal(size=m), np.ones(m)])
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    d[:m] = 2 * lecture.dot(w[:m], h)[:, None] * h - w[:m]
    keep = d[:, 2] > min_cos
    return d[keep], w[keep]


def conductor(distribution, **roughness) -> dict:
    return {"type": "cook_torrance", "k": 0.0, "f0": 1.0, "geometry": "smith",
            "distribution": distribution, **roughness}


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
@pytest.mark.parametrize("au, av", ANISOTROPIC)
def test_anisotropic_equals_roughconductor(rng, distribution, au, av):
    d, w = anisotropic_pairs(rng, 8192, au, av)
    ours = mi.load_dict(conductor(distribution, alpha_u=au, alpha_v=av))
    ref = mi.load_dict({"type": "roughconductor", "distribution": distribution,
                        "alpha_u": au, "alpha_v": av})
    assert_same_as_roughconductor(ours, ref, w, d, distribution)


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
@pytest.mark.parametrize("geometry", GEOMETRIES)
def test_anisotropic_axes_turn_with_the_azimuth(rng, distribution, geometry):
    """Physics: (alpha_u, alpha_v) seen from azimuth φ is (alpha_v, alpha_u) seen
    from φ + 90° (both directions turned about the normal); and an equal pair
    is the isotropic alpha."""
    d, w = anisotropic_pairs(rng, 4096, 0.1, 0.4)
    turn = lambda v: np.column_stack([-v[:, 1], v[:, 0], v[:, 2]])
    config = {"type": "cook_torrance", "distribution": distribution, "geometry": geometry,
              "k": 0.3, "f0": 0.4}
    a = eval_and_pdf(mi.load_dict({**config, "alpha_u": 0.1, "alpha_v": 0.4}), w, d)
    b = eval_and_pdf(mi.load_dict({**config, "alpha_u": 0.4, "alpha_v": 0.1}), turn(w), turn(d))
    for x, y in zip(a, b):
        np.testing.assert_allclose(x, y, rtol=2e-5, atol=1e-7 * np.abs(x).max())
    iso = eval_and_pdf(mi.load_dict({**config, "alpha": 0.25}), w, d)
    equal = eval_and_pdf(mi.load_dict({**config, "alpha_u": 0.25, "alpha_v": 0.25}), w, d)
    for x, y in zip(iso, equal):
        np.testing.assert_allclose(x, y, rtol=2e-6, atol=1e-7 * np.abs(x).max())


@pytest.mark.parametrize("given, name, value, valid", [
    ({"alpha": 0.2, "alpha_u": 0.1}, "alpha", "0.2", "either alpha or alpha_u/alpha_v, not both"),
    ({"distribution": "blinn", "alpha_v": 0.1}, "alpha_v", "0.1",
     'distribution "beckmann" or "ggx"'),
])
def test_anisotropic_bad_input_is_one_line(given, name, value, valid):
    assert_refused({"type": "cook_torrance", **given}, name, value, valid)


def plane_with_uv_turned(bsdf: dict, degrees: float, res: int = 40) -> dict:
    """A square mesh whose texture coordinates (so its tangent s, along dp/du)
    are turned by ``degrees`` about its normal, under a point light, seen at an
    angle; a sphere beside it (its tangents follow its parametrisation)."""
    t = np.radians(degrees)
    corners = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=np.float32)
    rot = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    uv = (corners[:, :2] @ rot.T).astype(np.float32)
    mesh = mi.Mesh("plane", 4, 2, has_vertex_texcoords=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = from_numpy(mi.Float, corners.ravel())
    params["vertex_texcoords"] = from_numpy(mi.Float, uv.ravel())
    params["faces"] = from_numpy(mi.UInt32, np.array([0, 1, 2, 0, 2, 3], dtype=np.uint32))
    params.update()
    mesh.set_bsdf(mi.load_dict(bsdf))
    T = mi.ScalarTransform4f
    return {"type": "scene",
            # light samples only: both BSDFs are evaluated at the same directions
            "integrator": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0},
            "sensor": {"type": "perspective", "fov": 40,
                       "to_world": T().look_at(origin=[0, -3, 2.5], target=[0.3, 0, 0],
                                               up=[0, 0, 1]),
                       "film": {"type": "hdrfilm", "width": res, "height": res,
                                "rfilter": {"type": "box"}},
                       "sampler": {"type": "independent", "sample_count": 4}},
            "plane": mesh,
            "sphere": {"type": "sphere", "center": [1.4, 0.6, 0.5], "radius": 0.5,
                       "bsdf": bsdf},
            "key": {"type": "point", "position": [0.5, 1.5, 1.5],
                    "intensity": {"type": "rgb", "value": 10}}}


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
def test_anisotropic_renders_as_roughconductor_in_turned_frames(distribution):
    """A mesh whose tangents are turned by its texture coordinates, and a
    sphere: the same image as roughconductor, pixel by pixel (the same camera
    and light samples); turning the tangents changes the image (the
    anisotropy follows the shading frame)."""
    roughness = {"alpha_u": 0.05, "alpha_v": 0.4}
    images = {}
    for name, bsdf in (("ours", conductor(distribution, **roughness)),
                       ("theirs", {"type": "roughconductor", "distribution": distribution,
                                   **roughness})):
        for degrees in (0.0, 35.0):
            scene = mi.load_dict(plane_with_uv_turned(bsdf, degrees))
            images[name, degrees] = np.array(mi.render(scene, seed=3))
    for degrees in (0.0, 35.0):
        ref = images["theirs", degrees]
        assert ref.max() > 0.1
        np.testing.assert_allclose(images["ours", degrees], ref, rtol=RTOL[distribution],
                                   atol=1e-5 * ref.max())
    turned = np.abs(images["ours", 35.0] - images["ours", 0.0]).max()
    assert turned > 0.1 * images["ours", 0.0].max()


# ----------------------------------------------------------------------------
#  A colour F0 (issue 35): per channel, per point, per wavelength
# ----------------------------------------------------------------------------

F0_RGB = np.array([0.95, 0.64, 0.2])        # a gold-ish F0, far from grey


def schlick_lobe(d, w, m_s, f0, rho, distribution, geometry):
    """(n, 3): the lecture's m_S·D·F·G/(4 cos θ_i) with Schlick's F of a colour F0,
    one channel at a time through tests/bsdfs/lecture.py (hdr eval, k = 0)."""
    return np.stack([m_s[c] * lecture.cook_torrance_terms(d, w, rho, f0[c], distribution, geometry)
                     for c in range(3)], axis=1)


@pytest.mark.parametrize("distribution, geometry", [("ggx", "smith"), ("beckmann", "cook_torrance"),
                                                    ("blinn", "smith")])
@pytest.mark.parametrize("extra", [{"mode": "hdr"}, {"mode": "scanline"},
                                   {"mode": "hdr", "energy_compensation": True}],
                         ids=["hdr", "scanline", "compensated"])
@pytest.mark.parametrize("k", [0.0, 0.4])
def test_colour_f0_is_three_grey_plugins(rng, distribution, geometry, extra, k):
    """An rgb f0 evaluates, channel by channel, as three plugins of one number
    each (compensated too: the walk tables read at each channel's F0); with
    one lobe (k = 0, not compensated: nothing picked by F) the pdf is theirs;
    the sample weights equal eval / pdf."""
    d, w = pairs(rng, 4096, alpha=0.3)
    m_s = np.array([0.9, 0.8, 0.7])
    common = {"type": "cook_torrance", "distribution": distribution, "geometry": geometry,
              "alpha": 0.3, "k": k, "diffuse_reflectance": rgb([0.2, 0.5, 0.3]),
              "specular_reflectance": rgb(m_s), **extra}
    colour = mi.load_dict({**common, "f0": rgb(F0_RGB)})
    v, p = eval_and_pdf(colour, w, d)
    for c, f0 in enumerate(F0_RGB):
        v_c, p_c = eval_and_pdf(mi.load_dict({**common, "f0": float(f0)}), w, d)
        np.testing.assert_allclose(v[:, c], v_c[:, c], rtol=2e-6, atol=1e-8, err_msg=f"channel {c}")
        if k == 0.0 and "energy_compensation" not in extra:
            np.testing.assert_allclose(p, p_c, rtol=1e-6, atol=1e-8)
    if k == 0.0 and extra == {"mode": "hdr"}:        # independently: the lecture's formula
        rtol = 3e-3 if (distribution, geometry) == ("blinn", "smith") else 2e-4
        np.testing.assert_allclose(v, schlick_lobe(d, w, m_s, F0_RGB, 0.3, distribution, geometry),
                                   rtol=rtol, atol=1e-6)
    assert_weight_is_value_over_pdf(sampled(colour, w[:1024], rng), f"f0 {F0_RGB}")


def test_colour_f0_picks_the_lobe_by_its_mean(rng):
    """The specular lobe is picked in proportion to (1 - k)·mean(m_S·F): Schlick's
    F is affine in F0, so with a grey m_S the pdf of an rgb f0 is that of the
    one number mean(f0) (and not that of any one channel)."""
    d, w = pairs(rng, 4096, alpha=0.3)
    common = {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith",
              "alpha": 0.3, "k": 0.4, "specular_reflectance": 0.8}
    _, p = eval_and_pdf(mi.load_dict({**common, "f0": rgb(F0_RGB)}), w, d)
    _, p_mean = eval_and_pdf(mi.load_dict({**common, "f0": float(F0_RGB.mean())}), w, d)
    _, p_red = eval_and_pdf(mi.load_dict({**common, "f0": float(F0_RGB[0])}), w, d)
    np.testing.assert_allclose(p, p_mean, rtol=1e-5, atol=1e-8)
    assert np.abs(p - p_red).max() > 1e-2 * p.max()


@pytest.mark.parametrize("compensated", [False, True])
def test_textured_f0_is_read_per_point(rng, compensated):
    """f0 as a checkerboard texture: at a uv of each tile the plugin evaluates as
    the plugin of that tile's number (eval and pdf; compensated, the tables'
    F0 axis read per lane, not contracted as a constant)."""
    lo, hi = 0.1, 0.85
    common = {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith",
              "alpha": 0.4, "k": 0.0, "energy_compensation": compensated}
    textured = mi.load_dict({**common, "f0": {"type": "checkerboard", "color0": lo, "color1": hi}})
    assert textured.state.f0 == "colour"
    n = 2048
    d, w = pairs(rng, n, alpha=0.4)
    n = len(w)
    tiles = (np.arange(n) % 2).astype(bool)           # alternate lanes: one tile, the other
    uv = np.where(tiles[:, None], [0.75, 0.25], [0.25, 0.25])
    seen = np.array(textured.eval_attribute("f0", surface(w, uv)), dtype=np.float64)
    np.testing.assert_allclose(seen[0], np.where(tiles, hi, lo), rtol=1e-6)   # the tiles
    v, p = eval_and_pdf(textured, w, d, uv)
    for tile, f0 in ((False, lo), (True, hi)):
        v_f, p_f = eval_and_pdf(mi.load_dict({**common, "f0": f0}), w, d, uv)
        lanes = tiles == tile
        np.testing.assert_allclose(v[lanes], v_f[lanes], rtol=2e-6, atol=1e-8)
        np.testing.assert_allclose(p[lanes], p_f[lanes], rtol=1e-6, atol=1e-8)
        other = ~lanes                                # (there, the other tile's number)
        assert np.abs(v[other] - v_f[other]).max() > 0.1 * v[other].max()


@pytest.mark.parametrize("variant", ["llvm_ad_spectral", "scalar_spectral"])
@pytest.mark.parametrize("compensated", [False, True])
def test_spectrum_f0_is_read_per_wavelength(rng, variant, compensated):
    """In spectral variants an f0 spectrum is read at each wavelength: its value
    at wavelength j is that of the plugin of the spectrum's number there."""
    nodes = {420.0: 0.3, 520.0: 0.6, 610.0: 0.9, 690.0: 0.95}      # evaluated at its nodes
    with active_variant(variant):
        common = {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith",
                  "alpha": 0.5, "k": 0.0, "energy_compensation": compensated}
        bsdf = mi.load_dict({**common, "f0": {"type": "spectrum",
                                              "value": list(nodes.items())}})
        greys = [mi.load_dict({**common, "f0": f0}) for f0 in nodes.values()]
        wi, wo = random_hemisphere(rng, 6, 0.1), random_hemisphere(rng, 6, 0.1)
        ctx = mi.BSDFContext()
        for k in range(len(wi)):
            si = dr.zeros(mi.SurfaceInteraction3f)
            si.wavelengths = mi.Spectrum(*nodes)
            si.wi = mi.Vector3f(*map(float, wi[k]))
            v = mi.Vector3f(*map(float, wo[k]))
            ours = np.array(bsdf.eval(ctx, si, v), dtype=np.float64).ravel()
            assert len(ours) == len(nodes)
            for j, grey in enumerate(greys):
                value = np.array(grey.eval(ctx, si, v), dtype=np.float64).ravel()[j]
                assert ours[j] == pytest.approx(value, rel=1e-5, abs=1e-8)
            assert np.ptp(ours) > 0.05 * ours.max()


@pytest.mark.parametrize("compensated", [False, True])
def test_colour_f0_gradient_matches_finite_differences(rng, compensated):
    """AD of Σ eval with respect to each channel of an rgb f0 (through traverse,
    the key ``f0.value``) = central finite differences of fresh loads."""
    wi, wo = mirror_pairs(rng, 1024, 0.35, min_cos=0.1)
    common = {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith",
              "alpha": 0.4, "k": 0.3, "energy_compensation": compensated}
    bsdf = mi.load_dict({**common, "f0": rgb(F0_RGB)})
    params = mi.traverse(bsdf)
    dr.enable_grad(params["f0.value"])
    params.update()
    dr.backward(dr.sum(dr.sum(bsdf.eval(mi.BSDFContext(), surface(wi), vec(wo)))))
    grad = np.array(dr.grad(params["f0.value"]), dtype=np.float64).ravel()
    h = 1e-3
    for c in range(3):
        def total(x, c=c):
            f0 = F0_RGB.copy()
            f0[c] = x
            return float(eval_and_pdf(mi.load_dict({**common, "f0": rgb(f0)}), wi, wo)[0].sum())
        fd = finite_difference(total, float(F0_RGB[c]), h)
        assert abs(fd) > 1e-3
        np.testing.assert_allclose(grad[c], fd, rtol=2e-2, err_msg=f"channel {c}")


@pytest.mark.parametrize("f0, shown", [([0.5, 1.2, 0.3], "1.2"), ([0.5, 0.3, -0.1], "-0.1")])
def test_colour_f0_out_of_range_is_one_line(f0, shown):
    """A channel outside [0, 1], at load time and at params.update()."""
    config = {"type": "cook_torrance", "f0": rgb([0.5, 0.5, 0.5])}
    assert_refused({**config, "f0": rgb(f0)}, "f0", shown, "[0, 1]")
    params = mi.traverse(mi.load_dict(config))
    params["f0.value"] = mi.Color3f(*f0)
    with pytest.raises(ParameterError) as info:
        params.update()
    last = error_line(info.value)
    value = repr(float(np.float32(float(shown))))
    assert f"cook_torrance: parameter 'f0' = {value} is invalid" in last and "[0, 1]" in last, last


def test_a_number_f0_keeps_f_a_float():
    """One number (a course scene's f0) keeps Schlick's F a Float, its traverse
    key ``f0.value``; the constant 1 is folded (F = 1, nothing traced), and
    unfolds when it is changed."""
    grey = mi.load_dict({"type": "cook_torrance", "f0": 0.3})
    assert grey.state.f0 == "grey" and not grey.coloured()
    assert mi.load_dict({"type": "cook_torrance", "f0": rgb([0.3, 0.3, 0.4])}).coloured()
    one = mi.load_dict({"type": "cook_torrance", "f0": 1.0})
    assert one.state.f0 == "one"
    key = one.trace_key()
    params = mi.traverse(one)
    params["f0.value"] = 0.5
    params.update()
    assert one.state.f0 == "grey" and one.trace_key() != key


def test_effective_colour_of_a_colour_f0():
    """What the fit reports: the highlight's colour (1 - k)·m_S·F(θ) per channel,
    Schlick's F of each channel's F0 (NumPy: lecture.F_schlick); a number f0
    gives the same as before, a grey colour."""
    from mi_brdfs.bsdfs.cook_torrance import CookTorrance
    m_s, k, c = np.array([0.9, 0.8, 0.7]), 0.25, math.cos(math.radians(70.0))
    values = {"k": k, "diffuse_reflectance": 0.5, "specular_reflectance": list(m_s)}
    got = CookTorrance.effective({**values, "f0": list(F0_RGB)}, c)
    expected = (1 - k) * m_s * lecture.F_schlick(F0_RGB, c)
    np.testing.assert_allclose(got.specular, expected, rtol=1e-12)
    grey = CookTorrance.effective({**values, "f0": 0.3}, c)
    np.testing.assert_allclose(grey.specular, (1 - k) * m_s * lecture.F_schlick(0.3, c),
                               rtol=1e-12)
