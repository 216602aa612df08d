"""Mitsuba 3.9.1's ``src/bsdfs/tests/test_diffuse.py`` (tag v3.9.1, commit
478e193a), ported onto ``lambert``.

What changed, and why (each change is also commented at its test):

- ``diffuse`` is ``lambert`` everywhere (hdr mode, its default: Mitsuba's
  diffuse BRDF); the assertions and tolerances are upstream's.
- test01: ``class_name()`` of a Python plugin is the C++ base class name
  ("BSDF"), not the plugin's; the port checks the Python class instead of
  ``"SmoothDiffuse"``.
- test02: also compares with Mitsuba's ``diffuse`` at the same directions
  (upstream checks eval/pdf against the closed form and eval_pdf against
  eval and pdf; the closed form stays, the built-in is an added check).
"""
import drjit as dr
import mitsuba as mi

from upstream import frontal_si, lambert


def test01_create(variant_scalar_rgb):
    b = mi.load_dict(lambert())
    assert b is not None
    assert b.component_count() == 1
    assert b.flags(0) == mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
    assert b.flags() == b.flags(0)
    # Changed: upstream asserts class_name() == "SmoothDiffuse" (the C++ class).
    assert type(b).__name__ == "Lambert"


def test02_eval_pdf(variant_scalar_rgb):
    bsdf = mi.load_dict(lambert())
    builtin = mi.load_dict({"type": "diffuse"})       # added: Mitsuba's own values
    si = frontal_si()
    ctx = mi.BSDFContext()

    for i in range(20):
        theta = i / 19.0 * (dr.pi / 2)
        wo = [dr.sin(theta), 0, dr.cos(theta)]

        v_pdf = bsdf.pdf(ctx, si, wo=wo)
        v_eval = bsdf.eval(ctx, si, wo=wo)[0]
        assert dr.allclose(v_pdf, wo[2] / dr.pi)
        assert dr.allclose(v_eval, 0.5 * wo[2] / dr.pi)

        v_eval_pdf = bsdf.eval_pdf(ctx, si, wo=wo)
        assert dr.allclose(v_eval, v_eval_pdf[0])
        assert dr.allclose(v_pdf, v_eval_pdf[1])

        # Added: the same values as Mitsuba's diffuse.
        assert dr.allclose(v_eval, builtin.eval(ctx, si, wo=wo)[0])
        assert dr.allclose(v_pdf, builtin.pdf(ctx, si, wo=wo))


def test03_chi2(variants_vec_backends_once_rgb):
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    sample_func, pdf_func = BSDFAdapter("lambert", "")

    chi2 = ChiSquareTest(
        domain=SphericalDomain(),
        sample_func=sample_func,
        pdf_func=pdf_func,
        sample_dim=3
    )

    assert chi2.run()
