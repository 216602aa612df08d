"""Mitsuba 3.9.1's ``src/bsdfs/tests/test_twosided.py`` (tag v3.9.1, commit
478e193a), ported: ``twosided`` around ``lambert`` and ``cook_torrance``.

What changed, and why (each change is also commented at its test):

- ``diffuse`` is ``lambert``; ``roughconductor`` is ``cook_torrance`` as
  roughconductor (:func:`upstream.cook_torrance`: k = 0, F0 = 1, Smith);
  test05's ``material="Al"`` (complex IOR, which cook_torrance's Schlick F0
  does not take) is left out: the test is about ``alpha``, which stays.
  Assertions, tolerances, directions and sample grids are upstream's.
- test01: no change but the plugins.
- test04 and test05 also check the values themselves: each side's
  reflectance, each side's roughness (added: upstream compares twosided
  with its nested BSDFs only, which a plugin answering 0 would pass).
"""
import drjit as dr
import mitsuba as mi
from drjit.scalar import ArrayXu as UInt32

from upstream import cook_torrance, frontal_si, lambert


def test01_create(variant_scalar_rgb):
    bsdf = mi.load_string("""<bsdf version="3.0.0" type="twosided">
        <bsdf type="lambert"/>
    </bsdf>""")
    assert bsdf is not None
    assert bsdf.component_count() == 2
    assert bsdf.flags(0) == mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
    assert bsdf.flags(1) == mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.BackSide
    assert bsdf.flags() == bsdf.flags(0) | bsdf.flags(1)

    # roughconductor -> cook_torrance as a perfect conductor (no diffuse lobe)
    bsdf = mi.load_string("""<bsdf version="3.0.0" type="twosided">
        <bsdf type="cook_torrance">
            <float name="k" value="0"/>
            <float name="f0" value="1"/>
            <string name="geometry" value="smith"/>
        </bsdf>
        <bsdf type="lambert"/>
    </bsdf>""")
    assert bsdf is not None
    assert bsdf.component_count() == 2
    assert bsdf.flags(0) == mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
    assert bsdf.flags(1) == mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.BackSide
    assert bsdf.flags() == bsdf.flags(0) | bsdf.flags(1)


def test02_pdf(variant_scalar_rgb):
    bsdf = mi.load_string("""<bsdf version="3.0.0" type="twosided">
        <bsdf type="lambert"/>
    </bsdf>""")

    si = frontal_si()
    ctx = mi.BSDFContext()
    p_pdf = bsdf.pdf(ctx, si, [0, 0, 1])
    assert dr.allclose(p_pdf, dr.inv_pi)

    p_pdf = bsdf.pdf(ctx, si, [0, 0, -1])
    assert dr.allclose(p_pdf, 0.0)


def test03_sample_eval_pdf(variant_scalar_rgb):
    bsdf = mi.load_string("""<bsdf version="3.0.0" type="twosided">
        <bsdf type="lambert">
            <rgb name="reflectance" value="0.1, 0.1, 0.1"/>
        </bsdf>
        <bsdf type="lambert">
            <rgb name="reflectance" value="0.9, 0.9, 0.9"/>
        </bsdf>
    </bsdf>""")

    si = frontal_si()
    n = 5
    ctx = mi.BSDFContext()
    for u in dr.arange(UInt32, n):
        for v in dr.arange(UInt32, n):
            si.wi = mi.warp.square_to_uniform_sphere([u / float(n - 1), v / float(n - 1)])
            up = dr.dot(si.wi, [0, 0, 1]) > 0

            for x in dr.arange(UInt32, n):
                for y in dr.arange(UInt32, n):
                    sample = [x / float(n - 1), y / float(n - 1)]
                    (bs, s_value) = bsdf.sample(ctx, si, 0.5, sample)

                    if dr.any(s_value > 0):
                        # Multiply by square_to_cosine_hemisphere_theta
                        s_value *= bs.wo[2] * dr.inv_pi
                        if not up:
                            s_value *= -1

                        e_value = bsdf.eval(ctx, si, bs.wo)
                        p_pdf = bsdf.pdf(ctx, si, bs.wo)

                        assert dr.allclose(s_value, e_value, atol=1e-2)
                        assert dr.allclose(bs.pdf, p_pdf)
                        assert not dr.any(dr.isnan(e_value) | dr.isnan(s_value))

                        v_eval_pdf = bsdf.eval_pdf(ctx, si, bs.wo)
                        assert dr.allclose(e_value, v_eval_pdf[0])
                        assert dr.allclose(p_pdf, v_eval_pdf[1])


def sides_of(bsdf, front, back, attribute=None):
    """Upstream's loop of tests 04 and 05: for viewers over the whole sphere,
    twosided's value is the front's above the surface and the back's (seen
    with wi mirrored) below it."""
    si = frontal_si()
    n, epsilon = 5, 0.0001
    for u in dr.linspace(mi.Float, epsilon, 1 - epsilon, n):
        for v in dr.linspace(mi.Float, epsilon, 1 - epsilon, n):
            si.wi = mi.warp.square_to_uniform_sphere([u / float(n - 1), v / float(n - 1)])
            up = mi.Frame3f.cos_theta(si.wi) > 0.0

            if attribute is None:
                value = bsdf.eval_diffuse_reflectance(si)
                value_front = front.eval_diffuse_reflectance(si)
                si.wi.z *= -1
                value_back = back.eval_diffuse_reflectance(si)
            else:
                value = bsdf.eval_attribute(attribute, si)
                value_front = front.eval_attribute(attribute, si)
                si.wi.z *= -1
                value_back = back.eval_attribute(attribute, si)

            assert dr.allclose(dr.select(up, value - value_front, 0), 0.0)
            assert dr.allclose(dr.select(up, 0, value - value_back), 0.0)


def test04_eval_diffuse_reflectance(variants_vec_rgb):
    bsdf_front = mi.load_dict(lambert(reflectance={"type": "rgb", "value": [0.1, 0.1, 0.1]}))
    bsdf_back = mi.load_dict(lambert(reflectance={"type": "rgb", "value": [0.9, 0.9, 0.9]}))
    bsdf = mi.load_dict({"type": "twosided", "a": bsdf_front, "b": bsdf_back})
    sides_of(bsdf, bsdf_front, bsdf_back)

    # Added: each side answers its own reflectance (as Mitsuba's diffuse does).
    si = frontal_si()
    assert dr.allclose(bsdf.eval_diffuse_reflectance(si), 0.1)
    si.wi = [0, 0, -1]
    assert dr.allclose(bsdf.eval_diffuse_reflectance(si), 0.9)


def test05_eval_attribute(variants_vec_rgb):
    # Changed: roughconductor (Al, ggx) -> cook_torrance (ggx, F0 = 1); no material.
    bsdf_front = mi.load_dict(cook_torrance(alpha=0.2, distribution="ggx"))
    bsdf_back = mi.load_dict(cook_torrance(alpha=0.1, distribution="ggx"))
    bsdf = mi.load_dict({"type": "twosided", "a": bsdf_front, "b": bsdf_back})

    value = bsdf.has_attribute("alpha")
    value_front = bsdf_front.has_attribute("alpha")
    value_back = bsdf_back.has_attribute("alpha")
    assert (value == value_front) and (value == value_back)

    sides_of(bsdf, bsdf_front, bsdf_back, attribute="alpha")

    # Added: the attribute is each side's roughness.
    si = frontal_si()
    assert dr.all(value)
    assert dr.allclose(bsdf.eval_attribute("alpha", si), 0.2)
    si.wi = [0, 0, -1]
    assert dr.allclose(bsdf.eval_attribute("alpha", si), 0.1)
