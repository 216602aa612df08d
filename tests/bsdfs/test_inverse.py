"""Inverse rendering as Mitsuba users do it: spatially varying
parameters recovered from renders of a known scene by gradient descent (Adam),
through mi.traverse and params.update(), including a start at the bound 0.

The scene (:func:`mi_brdfs.tools.analysis.plane_scene`): a square plane seen
from above (it fills the view), lit by a point light at one of five places
(five scenes: five views of each texel's lobe), rendered by the scan-line
integrator without its clamp, 32² pixels, so each texel of an 8 x 8 texture
covers 4 x 4 pixels. The fitted values are compared with the known truth.
"""
import numpy as np
import pytest

from mi_brdfs.tools.analysis import bitmap, fit_texture

TEXELS = 8
LIGHTS = [[0.6, 0.6, 0.8], [-0.7, 0.2, 0.6], [0.1, -0.8, 1.0], [0.7, -0.6, 0.5], [-0.5, 0.8, 0.9]]


def test_roughness_texture_is_recovered(rng=np.random.default_rng(5)):
    """An 8 x 8 GGX roughness map in [0.1, 0.6], from a uniform start of 0.3."""
    truth = rng.uniform(0.1, 0.6, (TEXELS, TEXELS))
    base = {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith", "k": 0.0,
            "f0": 1.0, "specular_reflectance": 0.8}
    fitted, losses = fit_texture({**base, "alpha": bitmap(truth)},
                                 {**base, "alpha": bitmap(np.full((TEXELS, TEXELS), 0.3))},
                                 "plane.bsdf.alpha.data", LIGHTS, steps=60, lr=0.02,
                                 lo=1e-3, hi=1.0)
    error = np.abs(fitted[..., 0] - truth)
    assert losses[-1] < 0.01 * losses[0], losses
    assert np.median(error) < 0.01 and error.max() < 0.04, error


def test_colour_texture_is_recovered_from_black(rng=np.random.default_rng(6)):
    """An 8 x 8 Phong diffuse colour map, from black: the bound 0, where the
    gradient must already flow."""
    truth = rng.uniform(0.1, 0.9, (TEXELS, TEXELS, 3))
    base = {"type": "phong", "exponent": 30.0, "specular_reflectance": 0.3}
    fitted, losses = fit_texture({**base, "diffuse_reflectance": bitmap(truth)},
                                 {**base, "diffuse_reflectance": bitmap(np.zeros((TEXELS, TEXELS, 3)))},
                                 "plane.bsdf.diffuse_reflectance.data", LIGHTS, steps=100,
                                 lr=0.05, lo=0.0, hi=1.0)
    error = np.abs(fitted - truth)
    assert losses[-1] < 1e-3 * losses[0], losses
    assert error.max() < 0.02, error


def test_a_black_constant_colour_comes_back():
    """A constant diffuse colour of 0 has no lobe at load time; differentiated,
    its lobe is traced again and the colour is recovered (0 -> 0.6)."""
    base = {"type": "phong", "exponent": 30.0, "specular_reflectance": 0.3}
    fitted, _ = fit_texture({**base, "diffuse_reflectance": 0.6},
                            {**base, "diffuse_reflectance": 0.0},
                            "plane.bsdf.diffuse_reflectance.value", LIGHTS, steps=100, lr=0.02,
                            lo=0.0, hi=1.0)
    assert float(fitted.ravel()[0]) == pytest.approx(0.6, abs=0.01)
