"""Mitsuba 3.9.1's ``src/bsdfs/tests/test_blendbsdf.py`` (tag v3.9.1, commit
478e193a), ported: ``blendbsdf`` of ``lambert`` and ``cook_torrance``.

What changed, and why (each change is also commented at its test):

- ``diffuse`` is ``lambert``; ``roughconductor`` is ``cook_torrance`` as
  roughconductor (:func:`upstream.cook_torrance`: k = 0, F0 = 1, Smith) with
  the same ``alpha``. Mitsuba's ``conductor``, ``plastic`` and
  ``roughdielectric`` have no counterpart among the plugins and stay: they
  are the other half of each blend. Assertions, weights, samples and
  tolerances are upstream's.
- test02/test03 also check the blend's value against the closed form of
  its Lambert part (added: at wi = wo = n the smooth conductor contributes 0,
  so upstream's expected value is the Lambert part alone, 0.2/pi).
"""
import drjit as dr
import mitsuba as mi
import pytest

from upstream import cook_torrance, frontal_si, lambert

WEIGHT = 0.2
WHITE = {"type": "rgb", "value": 1.0}


def test01_create(variant_scalar_rgb):
    bsdf = mi.load_dict({"type": "blendbsdf", "nested1": lambert(), "nested2": lambert(),
                         "weight": WEIGHT})
    assert bsdf is not None
    assert bsdf.component_count() == 2
    assert bsdf.flags(0) == mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
    assert bsdf.flags(1) == mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
    assert bsdf.flags() == bsdf.flags(0) | bsdf.flags(1)

    bsdf = mi.load_dict({"type": "blendbsdf", "nested1": cook_torrance(), "nested2": lambert(),
                         "weight": WEIGHT})
    assert bsdf is not None
    assert bsdf.component_count() == 2
    assert bsdf.flags(0) == mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
    assert bsdf.flags(1) == mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
    assert bsdf.flags() == bsdf.flags(0) | bsdf.flags(1)


def conductor_and_lambert():
    """Upstream's blend of tests 02, 03 and 05: a smooth conductor and a white
    diffuse surface (here lambert), weight 0.2."""
    bsdf_0 = mi.load_dict({"type": "conductor"})
    bsdf_1 = mi.load_dict(lambert(reflectance=WHITE))
    bsdf = mi.load_dict({"type": "blendbsdf", "nested1": bsdf_0, "nested2": bsdf_1,
                         "weight": WEIGHT})
    return bsdf_0, bsdf_1, bsdf


def test02_eval_all(variant_scalar_rgb):
    bsdf_0, bsdf_1, bsdf = conductor_and_lambert()
    si = frontal_si()
    wo = [0, 0, 1]
    ctx = mi.BSDFContext()

    # Evaluate the blend of both components
    expected = (1 - WEIGHT) * bsdf_0.eval(ctx, si, wo) + WEIGHT * bsdf_1.eval(ctx, si, wo)
    value = bsdf.eval(ctx, si, wo)
    assert dr.allclose(value, expected)
    assert dr.allclose(value, WEIGHT / dr.pi)          # added: the closed form


def test03_eval_components(variant_scalar_rgb):
    bsdf_0, bsdf_1, bsdf = conductor_and_lambert()
    si = frontal_si()
    wo = [0, 0, 1]
    ctx = mi.BSDFContext()
    blend_ctx = mi.BSDFContext()

    # Evaluate the two components separately
    blend_ctx.component = 0
    value0 = bsdf.eval(blend_ctx, si, wo)
    expected0 = (1.0 - WEIGHT) * bsdf_0.eval(ctx, si, wo)
    assert dr.allclose(value0, expected0)

    blend_ctx.component = 1
    value1 = bsdf.eval(blend_ctx, si, wo)
    expected1 = WEIGHT * bsdf_1.eval(ctx, si, wo)
    assert dr.allclose(value1, expected1)
    assert dr.allclose(value1, WEIGHT / dr.pi)         # added: the closed form


def test04_sample_all(variant_scalar_rgb):
    bsdf = mi.load_dict({"type": "blendbsdf", "nested1": {"type": "plastic"},
                         "nested2": lambert(reflectance=WHITE), "weight": WEIGHT})
    si = frontal_si()
    ctx = mi.BSDFContext()

    # Sample using two different values of 'sample1' and make sure correct
    # components are chosen.
    bs_a, weight_a = bsdf.sample(ctx, si, 0.1, [0.2, 0.9])
    eval_a, pdf_a = bsdf.eval_pdf(ctx, si, wo=bs_a.wo)
    expected_a = eval_a / pdf_a
    assert dr.allclose(weight_a, expected_a)

    bs_b, weight_b = bsdf.sample(ctx, si, 0.3, [0.4, 0.6])
    eval_b, pdf_b = bsdf.eval_pdf(ctx, si, wo=bs_b.wo)
    expected_b = eval_b / pdf_b
    assert dr.allclose(weight_b, expected_b)


@pytest.mark.parametrize("component", [0, 1])
def test05_sample_components(variant_scalar_rgb, component):
    # Upstream runs both components in one test; one per parameter here.
    bsdfs = conductor_and_lambert()
    bsdf = bsdfs[2]
    nested, scale = bsdfs[component], (1.0 - WEIGHT, WEIGHT)[component]
    si = frontal_si()
    ctx = mi.BSDFContext()
    blend_ctx = mi.BSDFContext()

    # Sample specific components separately using two different values of
    # 'sample1' and make sure the desired component is chosen always.
    blend_ctx.component = component
    for sample1, sample2 in ((0.1, [0.5, 0.5]), (0.3, [0.2, 0.7])):
        expected_bs, expected = nested.sample(ctx, si, sample1, sample2)
        bs, weight = bsdf.sample(blend_ctx, si, sample1, sample2)
        assert dr.allclose(weight, scale * expected)
        assert dr.allclose(bs.wo, expected_bs.wo)
        assert dr.allclose(bs.pdf, expected_bs.pdf)


def chi2_blend(nested1: dict, nested2: dict) -> bool:
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    sample_func, pdf_func = BSDFAdapter("blendbsdf", {
        "type": "blendbsdf", "nested1": nested1, "nested2": nested2, "weight": WEIGHT})
    chi2 = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func,
                         pdf_func=pdf_func, sample_dim=3)
    return chi2.run()


def test06_chi2_diffuse(variants_vec_backends_once_rgb):
    assert chi2_blend(lambert(), lambert())


def test07_chi2_diffuse_roughdielectric(variants_vec_backends_once_rgb):
    assert chi2_blend(lambert(), {"type": "roughdielectric", "alpha": 0.5})


def test08_chi2_roughconductor_roughdielectric(variants_vec_backends_once_rgb):
    assert chi2_blend(cook_torrance(alpha=0.5), {"type": "roughdielectric", "alpha": 0.5})
