"""What phong and blinn share: the same plugin glue (blinn subclasses phong),
so the same checks, run on both: sample weight x pdf = eval, no NaN/Inf at the
extremes (values and gradients), load-time errors, traverse/update, gradients
against finite differences. Model-specific tests stay in test_phong/test_blinn."""
import itertools
import math

import numpy as np
import pytest

from conftest import random_hemisphere, surface, vec
import drjit as dr
import mitsuba as mi

import test_blinn
import test_phong
from test_phong import _case_id, eval_np, f32, rgb

PAIRS = {"phong": test_phong.pairs, "blinn": test_blinn.pairs}   # near each model's lobe
MODELS = pytest.mark.parametrize("model", sorted(PAIRS))


def make(model, **params):
    return mi.load_dict({"type": model, **params})


def finite(x):
    return bool(np.all(np.isfinite(np.array(x))))


CONSISTENCY_CONFIGS = [
    {"exponent": 0.0}, {"exponent": 1.0}, {"exponent": 50.0, "diffuse_reflectance": 0.0},
    {"exponent": 1e4}, {"exponent": 1e6, "diffuse_reflectance": 0.0},
    {"mode": "scanline", "exponent": 30.0, "diffuse_reflectance": rgb([1.5, 0.3, 0.0]),
     "specular_reflectance": rgb([0.9, 0.9, 2.0])},
    {"specular_reflectance": 0.0},
]


@pytest.mark.parametrize("params", CONSISTENCY_CONFIGS, ids=lambda p: _case_id((p, 0)))
@MODELS
def test_sample_weight_matches_eval_over_pdf(model, rng, params):
    n = 100_000
    wi = random_hemisphere(rng, n)
    t = np.radians(rng.uniform(80, 89.9, n // 8))
    wi[: n // 8] = f32(np.column_stack([np.sin(t), np.zeros(n // 8), np.cos(t)]))   # near grazing
    wi[n // 8: n // 4, 2] *= -1                                          # below
    below = wi[:, 2] <= 0
    bsdf = make(model, **params)
    ctx = mi.BSDFContext()
    si = surface(wi)
    bs, weight = bsdf.sample(ctx, si, mi.Float(rng.random(n)),
                             mi.Point2f(rng.random(n), rng.random(n)))
    value = np.array(bsdf.eval(ctx, si, bs.wo)).T
    pdf = np.array(bsdf.pdf(ctx, si, bs.wo))
    weight, bs_pdf, wo = np.array(weight).T, np.array(bs.pdf), np.array(bs.wo).T
    for a in (weight, bs_pdf, value, pdf):
        assert np.all(np.isfinite(a)) and np.all(a >= 0)
    ok = bs_pdf > 0
    assert np.count_nonzero(ok & ~below) > 0.5 * np.count_nonzero(~below)
    assert not np.any(ok & below) and np.all(weight[~ok] == 0) and np.all(wo[ok, 2] > 0)
    np.testing.assert_allclose(weight[ok] * bs_pdf[ok, None], value[ok], rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(pdf[ok], bs_pdf[ok], rtol=1e-4)


# ----------------------------------------------------------------------------
#  Extremes: no NaN or Inf from eval, pdf, sample or gradients
# ----------------------------------------------------------------------------

def extreme_directions():
    """(wi, wo): normal, 45 deg, grazing (cos 1e-6 and 0), each against every
    other, itself (wi = wo), its mirror (the highlight), -wi, and mirrored below."""
    dirs = [np.array([0.0, 0.0, 1.0]), np.array([0.6, 0.0, 0.8])]
    for c in (1e-6, 0.0):
        s = math.sqrt(1 - c * c)
        dirs += [np.array([s, 0.0, c]), np.array([0.0, -s, c])]
    wi, wo = [], []
    for a, b in itertools.product(dirs, dirs):
        wi += [a] * 5
        wo += [b, a, a * [-1, -1, 1], -a, b * [1, 1, -1]]
    return np.array(wi), np.array(wo)


EXTREME_CONFIGS = [
    {"exponent": g, "mode": mode, "diffuse_reflectance": m_d, "specular_reflectance": m_s}
    for g in (0.0, 1.0, 1e4, 1e6, 1e8)
    for mode in ("hdr", "scanline")
    for m_d, m_s in ((0.5, 0.5), (0.0, 1.0), (1.0, 0.0))
]



@pytest.mark.parametrize("params", EXTREME_CONFIGS, ids=lambda p: _case_id((p, 0)))
@MODELS
def test_no_nan_or_inf(model, params):
    bsdf = make(model, **params)
    keys = [k for k in mi.traverse(bsdf).keys()]
    wi, wo = extreme_directions()
    u = np.array([0.0, 1e-7, 0.5, 1 - 1e-7, 1 - 2.0**-24])
    s1, s2x, s2y = (a.ravel() for a in np.meshgrid(u, u, u))
    for with_grad in (False, True):
        params_ = mi.traverse(bsdf)
        if with_grad:
            for key in keys:
                dr.enable_grad(params_[key])
            params_.update()
        ctx = mi.BSDFContext()
        si = surface(wi)
        value, pdf = bsdf.eval_pdf(ctx, si, vec(wo))
        si2 = surface(np.repeat(wi, len(s1), axis=0))
        bs, weight = bsdf.sample(ctx, si2, mi.Float(np.tile(s1, len(wi))),
                                 mi.Point2f(np.tile(s2x, len(wi)), np.tile(s2y, len(wi))))
        if not with_grad:
            for a in (value, pdf, bs.wo, bs.pdf, weight):
                assert finite(a)
            assert np.all(np.array(value) >= 0) and np.all(np.array(pdf) >= 0)
        else:
            dr.backward(dr.sum(dr.sum(value)) + dr.sum(pdf) + dr.sum(dr.sum(weight)) + dr.sum(bs.pdf))
            for key in keys:
                assert finite(dr.grad(params_[key])), key


# ----------------------------------------------------------------------------
#  Load-time errors
# ----------------------------------------------------------------------------

ERRORS = [
    ({"exponent": -1.0}, "exponent", "-1.0", "[0, 1e+08]"),
    ({"exponent": 2e8}, "exponent", "200000000.0", "[0, 1e+08]"),
    ({"exponent": float("nan")}, "exponent", "nan", "[0, 1e+08]"),
    ({"exponent": float("inf")}, "exponent", "inf", "[0, 1e+08]"),
    ({"exponent": {"type": "checkerboard", "color0": 10.0, "color1": -3.0}},
     "exponent", "-3.0", "[0, 1e+08]"),
    ({"diffuse_reflectance": -0.1}, "diffuse_reflectance", "-0.1", "[0, inf]"),
    ({"diffuse_reflectance": rgb([0.5, -1.0, 0.5])}, "diffuse_reflectance", "-1.0", "[0, inf]"),
    ({"specular_reflectance": -2.0}, "specular_reflectance", "-2.0", "[0, inf]"),
    ({"mode": "ldr"}, "mode", "'ldr'", '"scanline", "hdr"'),
]


@pytest.mark.parametrize("params, name, value, valid", ERRORS, ids=[f"{e[1]}={e[2]}" for e in ERRORS])
@MODELS
def test_bad_parameter_is_a_load_time_error(model, params, name, value, valid):
    with pytest.raises(Exception) as info:
        make(model, **params)
    last = str(info.value).strip().splitlines()[-1]
    assert f"{model}: parameter '{name}' = {value} is invalid" in last, last
    assert valid in last, last


@pytest.mark.parametrize("params", [{"exponent": 0.0}, {"exponent": 1e8},
                                    {"diffuse_reflectance": 3.0, "specular_reflectance": 0.0}])
@MODELS
def test_edge_values_are_accepted(model, params):
    make(model, **params)


# ----------------------------------------------------------------------------
#  Parameters: traverse, update, gradients
# ----------------------------------------------------------------------------

KEYS = {"diffuse_reflectance.value", "specular_reflectance.value", "exponent.value"}


@MODELS
def test_traverse_lists_every_parameter_as_differentiable(model):
    params = mi.traverse(make(model))
    assert set(params.keys()) == KEYS
    for key in params.keys():
        assert not (params.flags(key) & mi.ParamFlags.NonDifferentiable), key


@MODELS
def test_update_changes_the_result_and_the_lobes(model, rng):
    bsdf = make(model)
    d, w = PAIRS[model](rng, 512, 40.0, min_cos=0.1)
    params = mi.traverse(bsdf)
    params["exponent.value"] = 40.0
    params["diffuse_reflectance.value"] = 0.2
    params.update()
    after, _ = eval_np(bsdf, w, d)
    fresh, _ = eval_np(make(model, exponent=40.0, diffuse_reflectance=0.2), w, d)
    np.testing.assert_allclose(after, fresh, rtol=1e-6)
    flags = bsdf.flags()
    params["specular_reflectance.value"] = 0.0       # may change again: the lobe stays
    params.update()
    assert bsdf.flags() == flags
    after, _ = eval_np(bsdf, w, d)
    fresh, _ = eval_np(make(model, exponent=40.0, diffuse_reflectance=0.2,
                            specular_reflectance=0.0), w, d)
    np.testing.assert_allclose(after, fresh, rtol=1e-6)


CONFIG = {"diffuse_reflectance": 0.4, "specular_reflectance": 0.6, "exponent": 20.0}


@pytest.mark.parametrize("mode", ["hdr", "scanline"])
@pytest.mark.parametrize("key", sorted(KEYS))
@MODELS
def test_gradient_matches_finite_differences(model, rng, key, mode):
    d, w = PAIRS[model](rng, 512, CONFIG["exponent"], min_cos=0.1)
    scale = 0.3 if mode == "scanline" else 1.0      # keep scanline lobes below the clamp
    config = {**CONFIG, "mode": mode, "specular_reflectance": CONFIG["specular_reflectance"] * scale}
    bsdf = make(model, **config)
    params = mi.traverse(bsdf)
    dr.enable_grad(params[key])
    params.update()
    dr.backward(dr.sum(dr.sum(bsdf.eval(mi.BSDFContext(), surface(w), vec(d)))))
    grad = float(dr.sum(dr.grad(params[key]))[0])
    name = key.split(".")[0]
    h = 1e-3 * max(1.0, config[name])

    def total(x):
        return eval_np(make(model, **{**config, name: x}), w, d)[0].sum()

    fd = (total(config[name] + h) - total(config[name] - h)) / (2 * h)
    assert abs(grad) > 1e-3
    np.testing.assert_allclose(grad, fd, rtol=1e-2)
