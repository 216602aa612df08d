"""No NaN or Inf from eval, pdf, sample or gradients at the extremes."""
import itertools

import numpy as np
import pytest

import drjit as dr
import mitsuba as mi

from conftest import vec

C = [1e-6, 0.0]          # grazing cosines: tiny and exactly 0


def extreme_directions():
    """(wi, wo) pairs: normal, grazing (cos 1e-6 and 0), wi = wo, mirrored below."""
    dirs = [np.array([0.0, 0.0, 1.0]), np.array([0.6, 0.0, 0.8])]
    for c in C:
        s = np.sqrt(1 - c * c)
        dirs += [np.array([s, 0.0, c]), np.array([0.0, -s, c])]
    wi, wo = [], []
    for a, b in itertools.product(dirs, dirs):
        wi += [a, a, a]
        wo += [b, a, -a]               # any pair, wi = wo, wi = -wo (below)
        wi.append(a)
        wo.append(b * [1, 1, -1])       # mirrored below the surface
    return np.array(wi), np.array(wo)


CONFIGS = [{"type": "lambert"}, {"type": "lambert", "mode": "scanline"}] + [
    {"type": "cook_torrance", "alpha": alpha, "f0": f0, "k": k, "mode": mode,
     "distribution": dist, "geometry": geom}
    for alpha in [0.0, 1e-4, 1.0]
    for f0 in [0.0, 1.0]
    for k in [0.0, 0.5]
    for mode in ["hdr", "scanline"]
    for dist in ["blinn", "beckmann", "ggx"]
    for geom in ["cook_torrance", "smith"]
]


def finite(x):
    return bool(np.all(np.isfinite(np.array(x))))


@pytest.mark.parametrize("config", CONFIGS, ids=lambda c: "-".join(str(v) for v in c.values()))
def test_no_nan_or_inf(config):
    bsdf = mi.load_dict(config)
    wi, wo = extreme_directions()
    ctx = mi.BSDFContext()
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = vec(wi)
    value, pdf = bsdf.eval_pdf(ctx, si, vec(wo))
    assert finite(value) and finite(pdf)
    assert np.all(np.array(value) >= 0) and np.all(np.array(pdf) >= 0)
    # Samples, including the corners of the unit square.
    u = np.array([0.0, 1e-7, 0.5, 1 - 1e-7])
    s1, s2x, s2y = (a.ravel() for a in np.meshgrid(u, u, u))
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi) * len(s1))
    si.wi = vec(np.repeat(wi, len(s1), axis=0))
    bs, weight = bsdf.sample(ctx, si, mi.Float(np.tile(s1, len(wi))),
                             mi.Point2f(np.tile(s2x, len(wi)), np.tile(s2y, len(wi))))
    assert finite(weight) and finite(bs.pdf) and finite(bs.wo)


@pytest.mark.parametrize("dist", ["blinn", "beckmann", "ggx"])
@pytest.mark.parametrize("geom", ["cook_torrance", "smith"])
@pytest.mark.parametrize("alpha", [0.0, 1e-4, 1.0])
def test_gradients_are_finite(dist, geom, alpha):
    bsdf = mi.load_dict({"type": "cook_torrance", "distribution": dist, "geometry": geom,
                         "alpha": alpha})
    params = mi.traverse(bsdf)
    keys = ["alpha.value", "k", "f0", "diffuse_reflectance.value", "specular_reflectance.value"]
    for key in keys:
        dr.enable_grad(params[key])
    params.update()
    wi, wo = extreme_directions()
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = vec(wi)
    value, pdf = bsdf.eval_pdf(mi.BSDFContext(), si, vec(wo))
    dr.backward(dr.sum(value) + dr.sum(pdf))
    for key in keys:
        assert finite(dr.grad(params[key])), key
