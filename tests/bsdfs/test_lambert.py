"""lambert: hdr mode against Mitsuba's `diffuse`, scanline mode against the
lecture, a coloured albedo. What every model shares: the battery."""
import numpy as np
import pytest

import drjit as dr
import mitsuba as mi

from support import (albedo, eval_and_pdf, floats, load_form, points, property_forms,
                     random_hemisphere, rgb, surface)


@pytest.mark.parametrize("form", ["float", "rgb", "spectrum", "pairs", "file"])
def test_hdr_equals_mitsuba_diffuse(rng, tmp_path, form):
    """The same reflectance element (<float>, <rgb>, a <spectrum> constant, of
    wavelength:value pairs, from a file) in lambert and in diffuse: the same
    eval, pdf and samples (a spectrum becomes sRGB here as in diffuse; the
    spectral variants: tests/test_variants.py)."""
    n = 4096
    wi, wo = random_hemisphere(rng, n), random_hemisphere(rng, n)
    wo[: n // 4, 2] *= -1          # lights below the surface too
    wi[n // 4: n // 2, 2] *= -1    # and viewers below it
    element = property_forms(tmp_path)[form]
    ours, ref = (load_form(plugin, "reflectance", element) for plugin in ("lambert", "diffuse"))
    v, p = eval_and_pdf(ours, wi, wo)
    v_ref, p_ref = eval_and_pdf(ref, wi, wo)
    np.testing.assert_allclose(v, v_ref, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(p, p_ref, rtol=1e-5, atol=1e-7)
    assert np.count_nonzero(v[:, 0]) > n // 3     # not a trivial all-zero agreement
    assert form in ("float", "spectrum") or np.ptp(v_ref[v_ref[:, 0] > 0][0]) > 0   # coloured
    u = (floats(rng.random(n)), points(rng.random(n), rng.random(n)))
    (bs, weight), (bs_ref, weight_ref) = (b.sample(mi.BSDFContext(), surface(wi), *u)
                                          for b in (ours, ref))
    up = wi[:, 2] > 0                # (below, diffuse reports a pdf with its weight 0; we pdf 0)
    for a, b in ((bs.wo, bs_ref.wo), (bs.pdf, bs_ref.pdf)):
        np.testing.assert_allclose(np.array(a)[..., up], np.array(b)[..., up], rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(np.array(weight), np.array(weight_ref), rtol=1e-5, atol=1e-7)


def test_scanline_is_lecture_formula(rng):
    """f_r = m_D · max(lx·n, 0), clamped per channel to [0, 1] (m_D above 1 allowed)."""
    n = 2048
    m_d = np.array([1.7, 0.6, 0.0])
    wi, wo = random_hemisphere(rng, n), random_hemisphere(rng, n)
    wo[: n // 4, 2] *= -1
    bsdf = mi.load_dict({"type": "lambert", "mode": "scanline",
                         "reflectance": {"type": "rgb", "value": m_d.tolist()}})
    v, _ = eval_and_pdf(bsdf, wi, wo)
    expected = np.clip(m_d[None, :] * np.maximum(wo[:, 2:3], 0.0), 0.0, 1.0)
    np.testing.assert_allclose(v, expected, rtol=1e-6, atol=1e-7)
    assert (v[:, 0] == 1.0).any() and (v[:, 0] < 1.0).any()   # the clamp is exercised


def test_zero_reflectance_has_no_lobe():
    bsdf = mi.load_dict({"type": "lambert", "reflectance": 0.0})
    assert bsdf.flags() == 0 and bsdf.component_count() == 0
    bsdf = mi.load_dict({"type": "lambert"})
    assert bsdf.flags() == mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
    assert bsdf.component_count() == 1 and bsdf.flags(0) == bsdf.flags()


def test_albedo_is_the_reflectance():
    """hdr: a coloured Lambert surface reflects its colour at every angle."""
    colour = [0.8, 0.4, 0.1]
    bsdf = mi.load_dict({"type": "lambert", "reflectance": rgb(colour)})
    for th in (0, 45, 85):
        np.testing.assert_allclose(albedo(bsdf, th), colour, rtol=0.01)


def test_a_spectrum_above_1_keeps_its_colour():
    """Colours above 1 are allowed (scanline mode clamps the lobe): a <spectrum>
    above 1 becomes its unclipped sRGB colour (Mitsuba's own conversion, not
    bounded), as the spectral variants keep its values; diffuse would clip it."""
    bsdf = mi.load_string('<bsdf version="3.0.0" type="lambert">'
                          '<spectrum name="reflectance" value="400:1.5, 700:2"/></bsdf>')
    colour = np.array(bsdf.eval_attribute_3("reflectance", dr.zeros(mi.SurfaceInteraction3f)))
    expected = mi.spectrum_list_to_srgb([400.0, 700.0], [1.5, 2.0], bounded=False, d65=True)
    np.testing.assert_allclose(colour.ravel(), np.array(expected), rtol=1e-5)
    assert colour.min() > 1.0
