"""Differentiable parameters: traverse lists them, update() applies, gradients flow."""
import numpy as np
import pytest

import drjit as dr
import mitsuba as mi

from conftest import random_hemisphere, surface, vec

EXPECTED = {
    "lambert": {"reflectance.value"},
    "cook_torrance": {"diffuse_reflectance.value", "specular_reflectance.value",
                      "alpha.value", "k", "f0"},
}


@pytest.mark.parametrize("plugin", EXPECTED)
def test_traverse_lists_every_parameter_as_differentiable(plugin):
    params = mi.traverse(mi.load_dict({"type": plugin}))
    assert set(params.keys()) == EXPECTED[plugin]
    for key in params.keys():
        assert not (params.flags(key) & mi.ParamFlags.NonDifferentiable), key


def eval_numpy(bsdf, wi, wo):
    return np.array(bsdf.eval(mi.BSDFContext(), surface(wi), vec(wo)))


def test_update_changes_the_result_without_reloading(rng):
    bsdf = mi.load_dict({"type": "cook_torrance", "distribution": "ggx"})
    wi, wo = random_hemisphere(rng, 256, 0.1), random_hemisphere(rng, 256, 0.1)
    before = eval_numpy(bsdf, wi, wo)
    params = mi.traverse(bsdf)
    params["alpha.value"] = 0.6
    params["k"] = 0.9
    params.update()
    after = eval_numpy(bsdf, wi, wo)
    fresh = eval_numpy(mi.load_dict({"type": "cook_torrance", "distribution": "ggx",
                                     "alpha": 0.6, "k": 0.9}), wi, wo)
    assert not np.allclose(before, after)
    np.testing.assert_allclose(after, fresh, rtol=1e-6)


def test_update_of_k_to_one_keeps_the_specular_lobe_traced():
    """k changed through update() may change again: the specular lobe stays."""
    bsdf = mi.load_dict({"type": "cook_torrance"})
    flags = bsdf.flags()
    params = mi.traverse(bsdf)
    params["k"] = 1.0
    params.update()
    assert bsdf.flags() == flags


@pytest.mark.parametrize("key", sorted(EXPECTED["cook_torrance"]))
def test_gradient_matches_finite_differences(rng, key):
    """d(sum of eval)/d(parameter) by AD equals a central finite difference."""
    config = {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith",
              "alpha": 0.4, "k": 0.4, "f0": 0.3, "diffuse_reflectance": 0.5,
              "specular_reflectance": 0.7}
    wi, wo = random_hemisphere(rng, 512, 0.1), random_hemisphere(rng, 512, 0.1)
    bsdf = mi.load_dict(config)
    params = mi.traverse(bsdf)
    dr.enable_grad(params[key])
    params.update()
    value = bsdf.eval(mi.BSDFContext(), surface(wi), vec(wo))
    loss = dr.sum(dr.sum(value))
    dr.backward(loss)
    grad = float(dr.sum(dr.grad(params[key]))[0])

    name = key.split(".")[0]
    h = 1e-3

    def total(x):
        b = mi.load_dict({**config, name: x})
        return float(eval_numpy(b, wi, wo).astype(np.float64).sum())

    fd = (total(config[name] + h) - total(config[name] - h)) / (2 * h)
    assert abs(grad) > 1e-3
    np.testing.assert_allclose(grad, fd, rtol=2e-2)
