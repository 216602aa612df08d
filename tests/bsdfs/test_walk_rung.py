"""cook_torrance with multiple_scattering="walk" (mi_brdfs/bsdfs/walk.py): the
random walk of Heitz et al. 2016 in Dr.Jit, against the project's NumPy walk
(mi_brdfs/tools/groundtruth, float64, its own code path) and physics:

- the mean of many stochastic evals at (wi, wo) pairs, grazing ones included,
  equals the NumPy walk's BRDF within their combined standard error;
- the mean sample weight equals the NumPy walk's albedo (white: 1, the furnace);
- the sampler's histogram equals eval integrated over the same cells (a χ²
  with the statistical error of both; its pdf p̃ is no density of the sampler,
  so Mitsuba's χ² against pdf() does not apply: walk.py says why);
- eval is reciprocal per call; pdf, eval_pdf and the sample's pdf agree;
- nothing NaN at α 1e-4, at huge α or at grazing; bad combinations refused.
"""
import importlib
import json
import math
import subprocess
import sys

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from scipy import stats

from mi_brdfs.tools.groundtruth import Alpha
from support import assert_refused

gw = importlib.import_module("mi_brdfs.tools.groundtruth.walk")

SIGMA = 4.5              # allowed difference, in combined standard errors
LANES = 1 << 16


def direction(theta, phi=0.0):
    t, p = math.radians(theta), math.radians(phi)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def vec(a):
    """(n, 3) NumPy directions as a Vector3f."""
    a = np.asarray(a, dtype=np.float32)
    return mi.Vector3f(*(mi.Float(a[:, i]) for i in range(3)))


def plugin(**kwargs):
    return mi.load_dict({"type": "cook_torrance", "geometry": "smith", "k": 0.0,
                         "multiple_scattering": "walk", **kwargs})


def interaction(wi, rng):
    """A SurfaceInteraction3f per lane with viewer wi (n, 3) and random uv (the
    eval's random numbers are a hash of its inputs, uv among them)."""
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = vec(wi)
    si.uv = mi.Point2f(mi.Float(rng.random(len(wi))), mi.Float(rng.random(len(wi))))
    return si


PAIRS = [(0, 45, 0), (30, 60, 180), (60, 60, 90), (75, 75, 180), (85, 85, 180),
         (85, 75, 0), (60, 85, 0), (85, 85, 90), (89, 30, 180)]


@pytest.mark.parametrize("kind, alpha, f0", [("ggx", 0.1, 1.0), ("ggx", 0.6, 0.5),
                                             ("ggx", 1.0, 1.0), ("beckmann", 0.3, 1.0),
                                             ("beckmann", 1.0, 0.5), ("ggx", (0.1, 0.5), 1.0),
                                             ("beckmann", (0.6, 0.2), 0.5)])
def test_eval_is_the_numpy_walks_brdf(kind, alpha, f0, rng):
    """Anisotropic too: (α_u, α_v) along s and t, viewers at azimuth 0 and
    lights at 0, 90 and 180°."""
    if isinstance(alpha, tuple):
        bsdf, walked = plugin(distribution=kind, alpha_u=alpha[0], alpha_v=alpha[1], f0=f0), \
            Alpha(*alpha)
    else:
        bsdf, walked = plugin(distribution=kind, alpha=alpha, f0=f0), alpha
    wi = np.array([direction(t) for t, _, _ in PAIRS])
    wo = np.array([direction(t, p) for _, t, p in PAIRS])
    ref, ref_err = gw.brdf(kind, wi, wo, walked, f0, paths=40_000, seed=5, error=True)
    si = interaction(np.repeat(wi, LANES, 0), rng)               # every pair in one call
    v = np.array(bsdf.eval(mi.BSDFContext(), si, vec(np.repeat(wo, LANES, 0))))[0]
    assert np.all(np.isfinite(v)) and np.all(v >= 0)
    v = v.reshape(len(PAIRS), LANES)
    ours, ours_err = v.mean(axis=1), v.std(axis=1) / math.sqrt(LANES)
    # (+ 5e-4 of the value: where bounces k >= 2 are rare, as Beckmann 0.3 seen from
    # the normal, the reference's 40,000 paths may hold none of them and its
    # standard error then misses their ~3e-5 of 0.18)
    bound = SIGMA * np.hypot(ours_err, ref_err) + 5e-4 * ref + 1e-6
    assert np.all(np.abs(ours - ref) <= bound), \
        [(p, float(o), float(r), float(e)) for p, o, r, e, ok in
         zip(PAIRS, ours, ref, bound, np.abs(ours - ref) <= bound) if not ok]


def sample(bsdf, theta, n, seed, phi=0.0):
    rng = np.random.default_rng(seed)
    si = interaction(np.repeat(direction(theta, phi)[None], n, 0), rng)
    bs, w = bsdf.sample(mi.BSDFContext(), si, mi.Float(rng.random(n)),
                        mi.Point2f(mi.Float(rng.random(n)), mi.Float(rng.random(n))))
    return si, bs, np.array(w)


@pytest.mark.parametrize("kind, alpha, f0", [("ggx", 0.3, 0.5), ("ggx", 1.0, 0.2),
                                             ("beckmann", 0.6, 0.5), ("beckmann", 1.0, 1.0),
                                             ("ggx", 2.0, 1.0), ("ggx", 10.0, 1.0),
                                             ("beckmann", 10.0, 1.0)])
def test_albedo_is_the_numpy_walks(kind, alpha, f0):
    thetas = (0.0, 60.0, 85.0)
    ref, ref_err = gw.albedo(kind, np.cos(np.radians(thetas)), alpha, (f0,), paths=100_000,
                             error=True)
    bsdf = plugin(distribution=kind, alpha=alpha, f0=f0)
    for t, r, e in zip(thetas, ref[:, 0], ref_err[:, 0]):
        _, bs, w = sample(bsdf, t, LANES * 4, seed=int(t))
        w = w[0]
        assert np.all(np.isfinite(w)) and np.all(w >= 0)
        err = math.hypot(w.std() / math.sqrt(len(w)), e)
        assert abs(w.mean() - r) <= SIGMA * err + 1e-6, (t, w.mean(), r, err)
        if f0 == 1.0:               # the white furnace: every path leaves with weight 1
            assert np.mean(w == 1.0) > 1 - 1e-4 and np.all(w <= 1.0)


def test_albedo_with_a_diffuse_lobe_beside():
    """k m_D + (1 - k) W: the mixture picks the walk or Lambert, each weighted by its pick."""
    k, m_d = 0.3, 0.5
    ref = gw.albedo("ggx", np.array([0.5]), 0.5, (0.4,), paths=100_000)[0, 0]
    bsdf = plugin(distribution="ggx", alpha=0.5, f0=0.4, k=k, diffuse_reflectance=m_d)
    _, _, w = sample(bsdf, 60.0, LANES * 4, seed=9)
    assert abs(w[0].mean() - (k * m_d + (1 - k) * ref)) < 5e-3


def cell_counts(wo, res):
    """Histogram of directions over res x 2res cells of (cos θ, φ)."""
    wo = np.asarray(wo, dtype=np.float64)     # (in float32, 1 - 1e-9 rounds to 1: a row too many)
    mu = np.clip(wo[:, 2], 0, 1 - 1e-9)
    phi = np.mod(np.arctan2(wo[:, 1], wo[:, 0]), 2 * np.pi)
    column = np.minimum((phi / (2 * np.pi) * 2 * res).astype(int), 2 * res - 1)   # φ = 2π
    i = (mu * res).astype(int) * 2 * res + column
    return np.bincount(i[wo[:, 2] > 0], minlength=2 * res * res)


def eval_cells(bsdf, theta, res, per_cell, seed):
    """∫ f cos θ_o over each (cos θ, φ) cell, by eval at uniform points of the
    cell (dω = dcos θ dφ), and its standard error."""
    rng = np.random.default_rng(seed)
    cells = 2 * res * res
    c = np.repeat(np.arange(cells), per_cell)
    mu = (c // (2 * res) + rng.random(len(c))) / res
    phi = (c % (2 * res) + rng.random(len(c))) / (2 * res) * 2 * np.pi
    s = np.sqrt(1 - mu * mu)
    wo = np.stack([s * np.cos(phi), s * np.sin(phi), mu], axis=1)
    si = interaction(np.repeat(direction(theta)[None], len(c), 0), rng)
    v = np.array(bsdf.eval(mi.BSDFContext(), si, vec(wo)))[0].reshape(cells, per_cell)
    area = (1.0 / res) * (2 * np.pi / (2 * res))
    return area * v.mean(axis=1), area * v.std(axis=1) / math.sqrt(per_cell)


def chi2_pvalue(bsdf_sampled, bsdf_eval, theta, n=1 << 20, res=12, per_cell=2048):
    """p-value of the sampler's histogram against eval's cell integrals, the
    variance of each cell that of both (Poisson and the eval's mean)."""
    _, bs, w = sample(bsdf_sampled, theta, n, seed=3)
    counts = cell_counts(np.array(bs.wo).T, res)
    expected, err = eval_cells(bsdf_eval, theta, res, per_cell, seed=4)
    expected, var_e = expected * n, (err * n) ** 2
    keep = expected > 20
    chi2 = np.sum((counts[keep] - expected[keep]) ** 2 / (expected[keep] + var_e[keep]))
    return stats.chi2.sf(chi2, keep.sum())


@pytest.mark.parametrize("kind, alpha, theta", [("ggx", 0.6, 0.0), ("ggx", 0.3, 75.0),
                                                ("beckmann", 1.0, 60.0)])
def test_sampler_is_distributed_as_eval(kind, alpha, theta):
    """White (F0 = 1): every path leaves with weight 1, so the sampler's density
    is f cos θ_o itself, eval's expectation."""
    bsdf = plugin(distribution=kind, alpha=alpha, f0=1.0)
    assert chi2_pvalue(bsdf, bsdf, theta) > 1e-3


def test_sampler_against_another_roughness_is_rejected():
    """The test has power: α 0.6 sampled against α 0.5 evaluated fails."""
    assert chi2_pvalue(plugin(distribution="ggx", alpha=0.6, f0=1.0),
                       plugin(distribution="ggx", alpha=0.5, f0=1.0), 45.0) < 1e-6


def test_pdf_is_consistent_and_covers_the_samples():
    bsdf = plugin(distribution="beckmann", alpha=0.4, f0=0.3, k=0.4)
    si, bs, w = sample(bsdf, 70.0, 1 << 14, seed=2)
    value, p = bsdf.eval_pdf(mi.BSDFContext(), si, bs.wo)
    np.testing.assert_allclose(np.array(p), np.array(bs.pdf), rtol=1e-6)
    np.testing.assert_allclose(np.array(bsdf.pdf(mi.BSDFContext(), si, bs.wo)), np.array(p),
                               rtol=1e-6)
    up = np.array(bs.wo.z) > 0
    assert np.all(np.array(bs.pdf)[up] > 0) and np.all(w[:, ~up] == 0)


def test_eval_is_reciprocal_per_call(rng):
    bsdf = plugin(distribution="ggx", alpha=0.5, f0=0.3, specular_reflectance=[0.9, 0.6, 0.3])
    n = 4096
    a = rng.normal(size=(n, 3)); a[:, 2] = np.abs(a[:, 2]); a /= np.linalg.norm(a, axis=1)[:, None]
    b = rng.normal(size=(n, 3)); b[:, 2] = np.abs(b[:, 2]); b /= np.linalg.norm(b, axis=1)[:, None]
    si = interaction(a, rng)
    ab = np.array(bsdf.eval(mi.BSDFContext(), si, vec(b))) / b[:, 2].astype(np.float32)
    si.wi = vec(b)
    ba = np.array(bsdf.eval(mi.BSDFContext(), si, vec(a))) / a[:, 2].astype(np.float32)
    np.testing.assert_allclose(ab, ba, rtol=2e-4, atol=1e-6)


@pytest.mark.parametrize("config", [
    {"distribution": "ggx", "alpha": 1e-4}, {"distribution": "beckmann", "alpha": 1e-4},
    {"distribution": "ggx", "alpha": 1e6}, {"distribution": "beckmann", "alpha": 30.0},
    {"distribution": "ggx", "alpha_u": 1e-4, "alpha_v": 0.8, "k": 0.5},
    {"distribution": "beckmann", "alpha": 0.2, "fresnel": "conductor", "material": "Cu"},
    {"distribution": "ggx", "alpha": 0.3, "fresnel": "dielectric", "int_ior": 1.5}],
    ids=lambda c: ",".join(f"{k}={v}" for k, v in c.items()))
def test_no_nan_at_the_extremes(config, rng):
    bsdf = plugin(**config)
    cos = np.array([1.0, 0.5, 1e-2, 1e-4, 1e-6, 0.0])
    grid = np.array([(ci, co, p) for ci in cos for co in cos for p in (0.0, 1.0, 3.14159)])
    n = len(grid) * 64
    g = np.repeat(grid, 64, 0)
    si_, so = np.sqrt(1 - g[:, 0] ** 2), np.sqrt(1 - g[:, 1] ** 2)
    wi = np.stack([si_, 0 * si_, g[:, 0]], 1)
    wo = np.stack([so * np.cos(g[:, 2]), so * np.sin(g[:, 2]), g[:, 1]], 1)
    si = interaction(wi, rng)
    value, p = bsdf.eval_pdf(mi.BSDFContext(), si, vec(wo))
    bs, w = bsdf.sample(mi.BSDFContext(), si, mi.Float(rng.random(n)),
                        mi.Point2f(mi.Float(rng.random(n)), mi.Float(rng.random(n))))
    for x in (value, p, w, bs.pdf, bs.wo):
        x = np.array(x)
        assert np.all(np.isfinite(x)), config
    assert np.all(np.array(value) >= 0) and np.all(np.array(w) >= 0)


@pytest.mark.parametrize("config, name, shown, valid", [
    ({"geometry": "cook_torrance"}, "geometry", "'cook_torrance'", '"smith" with'),
    ({"distribution": "blinn"}, "distribution", "'blinn'", '"beckmann" or "ggx" with'),
    ({"mode": "scanline"}, "mode", "'scanline'", '"hdr" with'),
    ({"energy_compensation": True}, "energy_compensation", "True", "false with"),
    ({"base": "plastic", "fresnel": "dielectric"}, "base", "'plastic'", '"lambert" with'),
    ({"multiple_scattering": "walks"}, "multiple_scattering", "'walks'", "walk")])
def test_bad_combinations_are_refused_in_one_line(config, name, shown, valid):
    assert_refused({"type": "cook_torrance", "geometry": "smith", "distribution": "ggx",
                    "multiple_scattering": "walk", **config}, name, shown, valid)


SCALAR = r'''
import json, math
import mi_brdfs, mitsuba as mi, drjit as dr
mi.set_variant(VARIANT)
mi_brdfs.register()
b = mi.load_dict(json.loads(CONFIG))
out = {"weight": [], "wo": [], "eval": []}
for t, u0, u1, u2 in json.loads(INPUTS):
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(math.sin(t), 0.0, math.cos(t))
    if mi.is_spectral:
        si.wavelengths = mi.UnpolarizedSpectrum(550.0)
    bs, w = b.sample(mi.BSDFContext(), si, u0, mi.Point2f(u1, u2))
    si.uv = mi.Point2f(u1, u2)
    out["weight"].append(w[0])
    out["wo"].append(bs.wo.z)
    out["eval"].append(b.eval(mi.BSDFContext(), si, mi.Vector3f(0.6, 0.0, 0.8))[0])
print(json.dumps(out))
'''


@pytest.mark.parametrize("variant", ["scalar_rgb", "scalar_spectral"])
def test_scalar_variants_give_llvm_values(variant):
    """The same random numbers in the scalar variants (float64 arithmetic
    where their Float is a Python float) as in llvm_ad_rgb (float32): the same
    samples and evaluations (measured: 64 of 64 lanes within 1e-3, 61 of the
    64 evaluations within 1e-4)."""
    config = {"type": "cook_torrance", "geometry": "smith", "distribution": "beckmann",
              "alpha": 0.5, "k": 0.3, "f0": 0.6, "multiple_scattering": "walk"}
    i = np.arange(64)
    inputs = np.stack([1.5 * ((i * 0.381966) % 1.0), (i * 0.618034) % 1.0,
                       (i * 0.414214) % 1.0, (i * 0.732051) % 1.0], axis=1).astype(np.float32)
    script = SCALAR.replace("VARIANT", repr(variant)).replace(
        "CONFIG", repr(json.dumps(config))).replace(
        "INPUTS", repr(json.dumps(inputs.tolist())))
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True)
    scalar = {k: np.array(v) for k, v in json.loads(out.stdout.strip().splitlines()[-1]).items()}
    b = mi.load_dict(config)
    si = dr.zeros(mi.SurfaceInteraction3f, 64)
    t = inputs[:, 0].astype(np.float64)
    si.wi = vec(np.stack([np.sin(t), 0 * t, np.cos(t)], axis=1))
    bs, w = b.sample(mi.BSDFContext(), si, mi.Float(inputs[:, 1]),
                     mi.Point2f(mi.Float(inputs[:, 2]), mi.Float(inputs[:, 3])))
    si.uv = mi.Point2f(mi.Float(inputs[:, 2]), mi.Float(inputs[:, 3]))
    v = b.eval(mi.BSDFContext(), si, vec(np.repeat([[0.6, 0.0, 0.8]], 64, 0)))
    llvm = {"weight": np.array(w)[0], "wo": np.array(bs.wo.z), "eval": np.array(v)[0]}
    for key in ("weight", "wo", "eval"):
        a, b = scalar[key], llvm[key]
        assert np.all(np.isfinite(a))
        same = np.isclose(a, b, rtol=1e-3, atol=1e-5)
        assert same.all(), (key, np.stack([a[~same], b[~same]]).T.tolist())


def test_white_furnace_render():
    """A white sphere (F0 = 1, m_S = 1) under a constant sky, path traced with
    Mitsuba's integrator (the walk's loops inside its own): every pixel of the
    sphere is 1 in expectation (each bounce keeps the light); single
    scattering alone is darker."""
    from mi_brdfs.tools.analysis import camera

    def render(**extra):
        scene = mi.load_dict({
            "type": "scene", "integrator": {"type": "path", "max_depth": 2, "hide_emitters": True},
            "sensor": camera(24, 30.0, origin=(0.0, 0.0, 4.5)),
            "sky": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
            "sphere": {"type": "sphere", "bsdf": {
                "type": "cook_torrance", "geometry": "smith", "distribution": "ggx",
                "alpha": 0.8, "k": 0.0, "f0": 1.0, "specular_reflectance": 1.0, **extra}}})
        image = np.array(mi.render(scene, spp=64, seed=1))[..., :3]
        lit = image.mean(axis=2) > 0
        inner = lit.copy()                   # the pixels the sphere covers whole
        inner[1:-1, 1:-1] &= lit[:-2, 1:-1] & lit[2:, 1:-1] & lit[1:-1, :-2] & lit[1:-1, 2:]
        return image[inner]

    walked, single = render(multiple_scattering="walk"), render()
    assert np.all(np.isfinite(walked))
    assert abs(walked.mean() - 1.0) < 0.01, walked.mean()
    assert single.mean() < 0.97
