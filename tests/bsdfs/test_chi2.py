"""Sampling tests: Mitsuba's chi-square test and sample()/eval()/pdf() consistency.

The chi-square tests follow Mitsuba's own BSDF tests (src/bsdfs/tests/
test_rough_conductor.py and friends): the histogram of the directions drawn by
``sample()`` is compared with the integral of ``pdf()`` over the same cells of a
(cos theta, phi) grid. A sampler and a pdf that disagree (a wrong Jacobian, a
wrong lobe-selection probability, a pdf of a different roughness) are rejected:
``test_chi2_detects_a_wrong_pdf`` checks that the test has the power to do so.

All chi-square runs of this module share one Sidak-corrected significance
level (``test_count=CHI2_TEST_COUNT``), so this module's family fails with
probability 1% when every sampler is right (each model module that adds its
own chi-square grid corrects for its own count).
"""
import math

import numpy as np
import pytest

import mi_brdfs  # noqa: F401  (LLVM set-up, variant, plugin registration)
import drjit as dr
import mitsuba as mi

RES = 201          # histogram rows (402 x 201 cells), as Mitsuba's narrow-lobe tests
IRES = 16          # pdf integration sub-samples per cell and axis
SAMPLES = 1_000_000


def _lambert_cases():
    return [({"type": "lambert", "mode": mode}, theta)
            for mode in ("hdr", "scanline") for theta in (0, 85)]


def _cook_torrance_cases():
    cases = []
    for dist in ("blinn", "beckmann", "ggx"):
        for alpha in (0.1, 0.5):
            for k in (0.0, 0.5):
                for theta in (0, 45, 85):
                    cases.append(({"type": "cook_torrance", "distribution": dist,
                                   "alpha": alpha, "k": k}, theta))
    # The Smith geometry term and the scanline clamp change the weights, not
    # the sampler: they must not zero out samples that pdf() counts.
    cases.append(({"type": "cook_torrance", "distribution": "ggx", "alpha": 0.5,
                   "k": 0.0, "geometry": "smith"}, 60))
    cases.append(({"type": "cook_torrance", "distribution": "beckmann", "alpha": 0.1,
                   "k": 0.5, "geometry": "smith"}, 85))
    cases.append(({"type": "cook_torrance", "distribution": "blinn", "alpha": 0.3,
                   "k": 0.5, "geometry": "smith", "mode": "scanline",
                   "diffuse_reflectance": {"type": "rgb", "value": [0.9, 0.2, 0.1]},
                   "f0": 0.5}, 30))
    # The other samplers: full-distribution microfacet sampling and cosine sampling.
    for dist in ("beckmann", "ggx"):
        cases.append(({"type": "cook_torrance", "distribution": dist, "alpha": 0.3,
                       "k": 0.3, "sample_visible": False}, 60))
    cases.append(({"type": "cook_torrance", "distribution": "ggx", "alpha": 0.3,
                   "k": 0.3, "sampling": "cosine"}, 45))
    return cases


CHI2_CASES = _lambert_cases() + _cook_torrance_cases()
# The negative control below runs one more chi-square test.
CHI2_TEST_COUNT = len(CHI2_CASES) + 1


def _case_id(case):
    params, theta = case
    rest = "-".join(f"{k}={v}" for k, v in params.items()
                    if k != "type" and not isinstance(v, dict))
    return f"{params['type']}-{rest}-theta={theta}"


def _wi(theta_deg):
    t = math.radians(theta_deg)
    return mi.ScalarVector3f(math.sin(t), 0.0, math.cos(t))


def _chi2(sample_params, pdf_params, theta):
    sample_func, _ = mi.chi2.BSDFAdapter(sample_params["type"], sample_params,
                                         wi=_wi(theta))
    _, pdf_func = mi.chi2.BSDFAdapter(pdf_params["type"], pdf_params, wi=_wi(theta))
    return mi.chi2.ChiSquareTest(
        domain=mi.chi2.SphericalDomain(),
        pdf_func=pdf_func,
        sample_func=sample_func,
        sample_dim=3,
        sample_count=SAMPLES,
        res=RES,
        ires=IRES,
    )


@pytest.mark.parametrize("case", CHI2_CASES, ids=[_case_id(c) for c in CHI2_CASES])
def test_chi2(case):
    params, theta = case
    chi2 = _chi2(params, params, theta)
    ok = chi2.run(significance_level=0.01, test_count=CHI2_TEST_COUNT, quiet=True)
    assert ok, f"chi-square test rejected {params} at theta_i={theta} deg:\n{chi2.messages}"


def test_chi2_detects_a_wrong_pdf():
    """Negative control: sampling alpha = 0.1 against the pdf of alpha = 0.105
    (a 5% roughness error) must be rejected, or the tests above prove nothing."""
    base = {"type": "cook_torrance", "distribution": "ggx", "k": 0.0}
    chi2 = _chi2({**base, "alpha": 0.1}, {**base, "alpha": 0.105}, 45)
    ok = chi2.run(significance_level=0.01, test_count=CHI2_TEST_COUNT, quiet=True)
    assert not ok, f"a wrong pdf was accepted:\n{chi2.messages}"


# ----------------------------------------------------------------------------
#  sample() against eval() and pdf()
# ----------------------------------------------------------------------------

CONSISTENCY_CONFIGS = [
    {"type": "lambert"},
    {"type": "lambert", "mode": "scanline",
     "reflectance": {"type": "rgb", "value": [1.7, 0.6, 0.2]}},
]
for _dist in ("blinn", "beckmann", "ggx"):
    for _geo in ("cook_torrance", "smith"):
        for _alpha, _k in ((0.1, 0.0), (0.5, 0.5), (1.0, 0.3)):
            CONSISTENCY_CONFIGS.append(
                {"type": "cook_torrance", "distribution": _dist, "geometry": _geo,
                 "alpha": _alpha, "k": _k})
CONSISTENCY_CONFIGS += [
    {"type": "cook_torrance", "mode": "scanline", "distribution": "beckmann",
     "alpha": 0.2, "k": 0.4, "f0": 0.8,
     "diffuse_reflectance": {"type": "rgb", "value": [1.5, 0.3, 0.0]},
     "specular_reflectance": {"type": "rgb", "value": [0.9, 0.9, 2.0]}},
    {"type": "cook_torrance", "distribution": "ggx", "alpha": 0.3, "k": 1.0},   # diffuse only
    {"type": "cook_torrance", "distribution": "ggx", "alpha": 0.0, "k": 0.0},   # alpha clamped
    {"type": "cook_torrance", "distribution": "beckmann", "alpha": 0.4, "k": 0.2,
     "sample_visible": False},
    {"type": "cook_torrance", "distribution": "ggx", "alpha": 0.2, "k": 0.0, "sampling": "cosine"},
]


def _config_id(params):
    return "-".join([params["type"]] + [f"{k}={v}" for k, v in params.items()
                                        if k != "type" and not isinstance(v, dict)])


def _random_wi(rng, n):
    """Mostly upper-hemisphere directions (many near grazing), plus some below."""
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[:, 2] = np.abs(v[:, 2])
    m = n // 8                                      # near-grazing viewers
    t = np.radians(rng.uniform(80.0, 89.9, size=m))
    p = rng.uniform(0, 2 * np.pi, size=m)
    v[:m] = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=1)
    v[m:2 * m, 2] *= -1                             # viewers below the surface
    return v


@pytest.mark.parametrize("params", CONSISTENCY_CONFIGS,
                         ids=[_config_id(p) for p in CONSISTENCY_CONFIGS])
def test_sample_weight_matches_eval_over_pdf(params):
    n = 200_000
    rng = np.random.default_rng(20240531)
    wi = _random_wi(rng, n)
    below = wi[:, 2] <= 0
    bsdf = mi.load_dict(params)
    ctx = mi.BSDFContext()
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(wi[:, 0], wi[:, 1], wi[:, 2])
    si.uv = mi.Point2f(0.5, 0.5)
    s1 = mi.Float(rng.random(n))
    s2 = mi.Point2f(rng.random(n), rng.random(n))

    bs, weight = bsdf.sample(ctx, si, s1, s2)
    value = bsdf.eval(ctx, si, bs.wo)
    pdf = bsdf.pdf(ctx, si, bs.wo)

    weight = np.array(weight).T                 # (n, 3)
    value = np.array(value).T
    bs_pdf = np.array(bs.pdf)
    pdf = np.array(pdf)
    wo = np.array(bs.wo).T

    assert np.all(np.isfinite(weight)) and np.all(np.isfinite(bs_pdf))
    assert np.all(np.isfinite(value)) and np.all(np.isfinite(pdf))
    assert np.all(weight >= 0) and np.all(bs_pdf >= 0)

    ok = bs_pdf > 0
    # A real sampler: most upper-hemisphere viewers get a usable direction.
    assert np.count_nonzero(ok & ~below) > 0.5 * np.count_nonzero(~below), \
        f"only {np.count_nonzero(ok)} of {n} samples have pdf > 0"
    # Viewers below the surface: no sample. Failed samples: zero weight.
    assert not np.any(ok & below)
    assert np.all(weight[~ok] == 0)
    # A successful sample leaves upwards (the plugins are reflection-only).
    assert np.all(wo[ok, 2] > 0)

    # weight * pdf = eval at the sampled direction.
    np.testing.assert_allclose(weight[ok] * bs_pdf[ok, None], value[ok],
                               rtol=1e-4, atol=1e-6)
    # pdf() reproduces the pdf reported by sample().
    np.testing.assert_allclose(pdf[ok], bs_pdf[ok], rtol=1e-4, atol=0)
    # Where sample() failed for an upper viewer, the direction is one with no
    # density (below the horizon or outside the lobe).
    failed_up = ~ok & ~below
    if np.any(failed_up):
        assert np.all((wo[failed_up, 2] <= 0) | (pdf[failed_up] == 0))
