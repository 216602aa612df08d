"""cook_torrance: against the lecture (NumPy), roughconductor and roughplastic."""
import numpy as np
import pytest

import lecture
from conftest import evaluate, random_hemisphere
import mitsuba as mi

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


def rgb(c):
    return {"type": "rgb", "value": list(map(float, c))}


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
    v, _ = evaluate(bsdf, wi=w, wo=d)
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
        v, p = evaluate(bsdf, wi, wo)
        assert not v.any() and not p.any()


# ----------------------------------------------------------------------------
#  Mitsuba's built-ins
# ----------------------------------------------------------------------------

# Mitsuba's Beckmann G1 is a rational fit of the exact erf form (within 0.35 %
# per G1, so within ~0.7 % for G1·G1); GGX's is exact.
RTOL = {"ggx": 1e-4, "beckmann": 7e-3}


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
@pytest.mark.parametrize("alpha", [0.05, 0.2, 0.5, 1.0])
def test_equals_roughconductor(rng, distribution, alpha):
    d, w = pairs(rng, 8192, alpha=alpha)
    ours = mi.load_dict({"type": "cook_torrance", "k": 0.0, "f0": 1.0, "geometry": "smith",
                         "distribution": distribution, "alpha": alpha})
    ref = mi.load_dict({"type": "roughconductor", "distribution": distribution, "alpha": alpha})
    v, p = evaluate(ours, w, d)
    v_ref, p_ref = evaluate(ref, w, d)
    big = v_ref[:, 0] > 1e-6 * v_ref[:, 0].max()
    assert big.sum() > 1000
    np.testing.assert_allclose(v[big], v_ref[big], rtol=RTOL[distribution])
    np.testing.assert_allclose(v[~big], v_ref[~big], atol=1e-6 * v_ref[:, 0].max())
    np.testing.assert_allclose(p, p_ref, rtol=1e-4, atol=1e-6)


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
    v, _ = evaluate(ours, w, d)
    v_ref, _ = evaluate(ref, w, d)
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
    m = mi.Vector3f(np.sin(t), 0 * t, np.cos(t))
    d = np.array(mf.D["blinn"](m, mi.Float(max(alpha, mf.ALPHA_MIN))), dtype=np.float64)
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
    m = mf.sample_blinn(mi.Point2f(rng.random(n), rng.random(n)), mi.Float(alpha))
    sin2 = np.array(m.x, dtype=np.float64) ** 2 + np.array(m.y, dtype=np.float64) ** 2
    e = 2 / alpha**2 - 1
    assert sin2.mean() == pytest.approx(2 / (e + 3), rel=0.01)
    assert len(np.unique(sin2)) > n // 2            # a continuum, not a few rings
