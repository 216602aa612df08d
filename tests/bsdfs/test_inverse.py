"""Inverse rendering as Mitsuba users do it (issue 11): spatially varying
parameters recovered from renders of a known scene by gradient descent (Adam),
through mi.traverse and params.update(), including a start at the bound 0.

The scene: a square plane seen from above (it fills the view), lit by a point
light at one of three places (three scenes: three views of each texel's lobe), rendered by
the scan-line integrator without its clamp (direct light, deterministic for a
fixed seed), 32² pixels, so each texel of an 8 x 8 texture covers 4 x 4 pixels.
"""
import numpy as np
import pytest

import drjit as dr
import mitsuba as mi

RES, TEXELS, SPP = 32, 8, 4
LIGHTS = [[0.6, 0.6, 0.8], [-0.7, 0.2, 0.6], [0.1, -0.8, 1.0], [0.7, -0.6, 0.5], [-0.5, 0.8, 0.9]]


def bitmap(values):
    """An 8 x 8 texture, nearest texels, values as stored (no sRGB)."""
    data = np.asarray(values, dtype=np.float32)
    if data.ndim == 2:
        data = data[..., None]
    return {"type": "bitmap", "bitmap": mi.Bitmap(data), "raw": True,
            "filter_type": "nearest", "wrap_mode": "clamp"}


def scene(bsdf, light):
    T = mi.ScalarTransform4f
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "scanline", "clamp": False, "hide_emitters": True},
        "sensor": {"type": "perspective", "fov": 40,
                   "to_world": T().look_at(origin=[0, 0, 3.0], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": RES, "height": RES,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": SPP}},
        "plane": {"type": "rectangle", "bsdf": bsdf, "to_world": T().scale(1.05)},
        "light": {"type": "point", "position": light,
                  "intensity": {"type": "rgb", "value": 2.0}},
    })


def descend(truth_bsdf, start_bsdf, key, steps, lr, lo, hi):
    """Fit ``key`` of start_bsdf to renders of truth_bsdf, one scene per light
    (moving one light through params between renders would leave the earlier
    renders' gradients computed with the last position: Mitsuba 3.9, measured
    with its roughconductor too); returns (the fitted values, the losses)."""
    reference = [dr.detach(mi.render(scene(truth_bsdf, light), spp=SPP, seed=3))
                 for light in LIGHTS]
    fits = [scene(start_bsdf, light) for light in LIGHTS]
    params = [mi.traverse(s) for s in fits]
    opt = mi.ad.Adam(lr=lr)
    opt[key] = params[0][key]
    losses = []
    for _ in range(steps):
        loss = mi.Float(0.0)
        for s, p, ref in zip(fits, params, reference):
            p.update(opt)                           # the one variable in every scene
            image = mi.render(s, p, spp=SPP, seed=3)
            # relative squared error: a highlight does not outweigh the rest
            loss += dr.mean(dr.square(image - ref) / dr.square(ref + 0.01), axis=None)
        dr.backward(loss)
        opt.step()
        opt[key] = dr.clip(opt[key], lo, hi)          # the parameter's valid range
        losses.append(float(np.array(loss).ravel()[0]))
    return np.array(opt[key]), np.array(losses)


def test_roughness_texture_is_recovered(rng=np.random.default_rng(5)):
    """An 8 x 8 GGX roughness map in [0.1, 0.6], from a uniform start of 0.3."""
    truth = rng.uniform(0.1, 0.6, (TEXELS, TEXELS))
    base = {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith", "k": 0.0,
            "f0": 1.0, "specular_reflectance": 0.8}
    fitted, losses = descend({**base, "alpha": bitmap(truth)},
                             {**base, "alpha": bitmap(np.full((TEXELS, TEXELS), 0.3))},
                             "plane.bsdf.alpha.data", steps=60, lr=0.02, lo=1e-3, hi=1.0)
    error = np.abs(fitted[..., 0] - truth)
    assert losses[-1] < 0.01 * losses[0], losses
    assert np.median(error) < 0.01 and error.max() < 0.04, error


def test_colour_texture_is_recovered_from_black(rng=np.random.default_rng(6)):
    """An 8 x 8 Phong diffuse colour map, from black: the bound 0, where the
    gradient must already flow."""
    truth = rng.uniform(0.1, 0.9, (TEXELS, TEXELS, 3))
    base = {"type": "phong", "exponent": 30.0, "specular_reflectance": 0.3}
    fitted, losses = descend({**base, "diffuse_reflectance": bitmap(truth)},
                             {**base, "diffuse_reflectance": bitmap(np.zeros((TEXELS, TEXELS, 3)))},
                             "plane.bsdf.diffuse_reflectance.data", steps=100, lr=0.05,
                             lo=0.0, hi=1.0)
    error = np.abs(fitted - truth)
    assert losses[-1] < 1e-3 * losses[0], losses
    assert error.max() < 0.02, error


def test_a_black_constant_colour_comes_back():
    """A constant diffuse colour of 0 has no lobe at load time; differentiated,
    its lobe is traced again and the colour is recovered (0 -> 0.6)."""
    base = {"type": "phong", "exponent": 30.0, "specular_reflectance": 0.3}
    fitted, _ = descend({**base, "diffuse_reflectance": 0.6}, {**base, "diffuse_reflectance": 0.0},
                        "plane.bsdf.diffuse_reflectance.value", steps=100, lr=0.02,
                        lo=0.0, hi=1.0)
    assert float(fitted.ravel()[0]) == pytest.approx(0.6, abs=0.01)
