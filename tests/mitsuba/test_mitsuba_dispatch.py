"""Mitsuba 3.9.1's ``src/render/tests/test_dispatch.py`` (tag v3.9.1, commit
478e193a), ported: ``dr.dispatch`` over ``BSDFPtr`` arrays holding the plugins.

What changed, and why (each change is also commented at its test):

- ``diffuse`` is ``lambert``; test02's ``plastic`` (the instance deleted to
  leave a hole in the registry) is ``cook_torrance``, so that the hole is a
  Python plugin's; ``conductor`` stays (no counterpart; a delta BSDF, whose
  eval is 0). Assertions are upstream's.
- Upstream's ``func`` printed the traced class; the print is gone (noise).
- Both tests also compare with the closed form (added: upstream compares
  dispatch with the vectorised call, two routes through the same plugin):
  lambert's 0.5/pi at wi = wo = n, the conductor's 0.
"""
import drjit as dr
import mitsuba as mi
import pytest

from upstream import cook_torrance, lambert


def func(self, si, wo):
    return self.eval(mi.BSDFContext(), si, wo)


def dispatch_and_check(bsdf_ptr, mask):
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.n = [0, 0, 1]
    si.sh_frame = mi.Frame3f(si.n)
    si.wi = [0, 0, 1]
    wo = mi.Vector3f(0, 0, 1)
    ctx = mi.BSDFContext()

    res = dr.dispatch(bsdf_ptr, func, si, wo)
    dr.eval(res)

    assert dr.allclose(res, bsdf_ptr.eval(ctx, si, wo))
    # Added: lambert (0.5 / pi) where the mask is set, the conductor (0) elsewhere.
    assert dr.allclose(res, dr.select(mask, 0.5 * dr.inv_pi, 0.0))


@pytest.mark.parametrize("recorded", [True, False])
def test01_dispatch(variants_vec_rgb, recorded):
    dr.set_flag(dr.JitFlag.VCallRecord, recorded)

    bsdf1 = mi.load_dict(lambert())
    bsdf2 = mi.load_dict({"type": "conductor"})

    mask = mi.Bool([True, True, False, False])
    bsdf_ptr = dr.select(mask, mi.BSDFPtr(bsdf1), mi.BSDFPtr(bsdf2))
    dispatch_and_check(bsdf_ptr, mask)


@pytest.mark.parametrize("recorded", [True, False])
def test02_dispatch_sparse_registry(variants_vec_rgb, recorded):
    dr.set_flag(dr.JitFlag.VCallRecord, recorded)

    bsdf1 = mi.load_dict(lambert())
    bsdf2 = mi.load_dict(cook_torrance())        # changed: upstream's plastic
    bsdf3 = mi.load_dict({"type": "conductor"})

    del bsdf2

    mask = mi.Bool([True, True, False, False])
    bsdf_ptr = dr.select(mask, mi.BSDFPtr(bsdf1), mi.BSDFPtr(bsdf3))
    dispatch_and_check(bsdf_ptr, mask)
    dispatch_and_check(bsdf_ptr, mask)
