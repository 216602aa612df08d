"""Shared test helpers: random local directions and evaluation of a BSDF on them."""
import numpy as np
import pytest

import mi_brdfs  # noqa: F401  (LLVM set-up, variant, plugin registration)
import drjit as dr
import mitsuba as mi


def random_hemisphere(rng, n, min_cos=0.0):
    """n unit vectors with z > min_cos, as an (n, 3) NumPy array."""
    v = rng.normal(size=(4 * n + 64, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[:, 2] = np.abs(v[:, 2])
    v = v[v[:, 2] > min_cos]
    return v[:n]


def vec(a):
    a = np.asarray(a, dtype=np.float64)
    return mi.Vector3f(a[:, 0], a[:, 1], a[:, 2])


def surface(wi):
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = vec(wi)
    si.uv = mi.Point2f(0.5, 0.5)
    return si


def evaluate(bsdf, wi, wo):
    """eval (n, 3) and pdf (n,) of a BSDF on direction pairs (NumPy in and out)."""
    ctx = mi.BSDFContext()
    si = surface(wi)
    value = np.array(bsdf.eval(ctx, si, vec(wo)))
    pdf = np.array(bsdf.pdf(ctx, si, vec(wo)))
    return value.T if value.shape[0] == 3 else value, pdf


@pytest.fixture
def rng():
    return np.random.default_rng(1234)
