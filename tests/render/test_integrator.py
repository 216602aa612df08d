"""The scanline integrator against an independent NumPy shading of the lecture's formula."""
import numpy as np
import pytest

import mitsuba as mi

import lecture

RES = 40
LIGHT = np.array([2.0, 2.5, 3.0])
INTENSITY = 6.0


def scene_dict(bsdf, integrator, plane=False, light_intensity=INTENSITY):
    d = {
        "type": "scene",
        "integrator": integrator,
        "sensor": {"type": "orthographic",
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0],
                                                              up=[0, 1, 0]) @
                   mi.ScalarTransform4f().scale([1.3, 1.3, 1]),
                   "film": {"type": "hdrfilm", "width": RES, "height": RES,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "stratified", "sample_count": 1, "jitter": False}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "light": {"type": "point", "position": LIGHT.tolist(),
                  "intensity": {"type": "rgb", "value": light_intensity}},
    }
    if plane:
        d["plane"] = {"type": "rectangle", "bsdf": {"type": "lambert", "mode": "scanline"},
                      "to_world": mi.ScalarTransform4f().translate([0, 0, -1.5]) @
                      mi.ScalarTransform4f().scale(4.0)}
    return d


def camera_rays(scene):
    """Origins and directions of the pixel-centre rays, from the sensor itself
    (the geometry of the camera is not what is under test)."""
    sensor = scene.sensors()[0]
    j, i = np.meshgrid(np.arange(RES), np.arange(RES), indexing="ij")
    pos = mi.Point2f(((i + 0.5) / RES).ravel(), ((j + 0.5) / RES).ravel())
    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    return np.array(ray.o).T, np.array(ray.d).T


def numpy_shading(o, d, f_r):
    """Per pixel: the unit sphere's hit point and normal, then L = I/r² · f_r(lx, w_r)."""
    b = np.sum(o * d, axis=1)
    c = np.sum(o * o, axis=1) - 1.0
    disc = b * b - c
    hit = disc > 0
    t = -b - np.sqrt(np.where(hit, disc, 0.0))
    x = o + t[:, None] * d
    n = x / np.linalg.norm(x, axis=1, keepdims=True)
    to_light = LIGHT - x
    r2 = np.sum(to_light**2, axis=1)
    lx = to_light / np.sqrt(r2)[:, None]
    w_r = -d
    # Express both in the normal's frame: only dot products with n and each other matter
    # for isotropic models, so build any orthonormal frame around n.
    helper = np.where(np.abs(n[:, 2:3]) < 0.9, [0, 0, 1.0], [1.0, 0, 0])
    s = np.cross(helper, n)
    s /= np.linalg.norm(s, axis=1, keepdims=True)
    tt = np.cross(n, s)
    local = lambda v: np.stack([np.sum(v * s, 1), np.sum(v * tt, 1), np.sum(v * n, 1)], axis=1)
    value = INTENSITY / r2[:, None] * f_r(local(lx), local(w_r))
    return np.where(hit[:, None], value, 0.0)


M_D = np.array([0.9, 0.5, 0.2])


def lambert_scanline(d, w):
    return np.clip(M_D[None, :] * np.clip(d[:, 2:3], 0, 1), 0, 1)


def cook_torrance_scanline(d, w):
    with np.errstate(all="ignore"):
        v = lecture.cook_torrance_scanline(d, w, M_D, np.ones(3), 0.5, 0.3, 0.3, "ggx", "smith")
    ok = (d[:, 2] > 0) & (w[:, 2] > 0)
    return np.where(ok[:, None], np.nan_to_num(v), 0.0)


M_S, GAMMA = 0.8, 30.0


def phong_scanline(d, w):
    """The lecture: clamp01(m_D·clamp(d·n)) + clamp01(m_S·clamp(w·r)^gamma), r = 2(d·n)n - d."""
    n = np.array([0.0, 0.0, 1.0])
    dn = d @ n
    r = 2 * dn[:, None] * n - d
    spec = M_S * np.clip(np.sum(w * r, axis=1), 0, 1) ** GAMMA
    value = (np.clip(M_D[None, :] * np.clip(dn, 0, 1)[:, None], 0, 1)
             + np.clip(spec, 0, 1)[:, None])
    ok = (d[:, 2] > 0) & (w[:, 2] > 0)
    return np.where(ok[:, None], value, 0.0)


CASES = {
    "lambert": ({"type": "lambert", "mode": "scanline",
                 "reflectance": {"type": "rgb", "value": M_D.tolist()}}, lambert_scanline),
    "cook_torrance": ({"type": "cook_torrance", "mode": "scanline", "k": 0.5, "f0": 0.3,
                       "alpha": 0.3, "distribution": "ggx", "geometry": "smith",
                       "diffuse_reflectance": {"type": "rgb", "value": M_D.tolist()}},
                      cook_torrance_scanline),
    "phong": ({"type": "phong", "mode": "scanline", "specular_reflectance": M_S,
               "exponent": GAMMA, "diffuse_reflectance": {"type": "rgb", "value": M_D.tolist()}},
              phong_scanline),
}


@pytest.mark.parametrize("model", CASES)
def test_scanline_equals_numpy_shading(model):
    bsdf, f_r = CASES[model]
    scene = mi.load_dict(scene_dict(bsdf, {"type": "scanline", "clamp": False}))
    image = np.array(mi.render(scene)).reshape(-1, 3)
    o, d = camera_rays(scene)
    expected = numpy_shading(o.astype(np.float64), d.astype(np.float64), f_r)
    assert expected.max() > 0.2 and (expected[:, 0] > 0).mean() > 0.3
    np.testing.assert_allclose(image, expected, rtol=2e-3, atol=2e-3 * expected.max())


def render(bsdf, **integrator):
    return np.array(mi.render(mi.load_dict(scene_dict(bsdf, {"type": "scanline", **integrator},
                                                      plane=True))))


def test_shadows_only_when_asked():
    bsdf = {"type": "lambert", "mode": "scanline"}
    plain, shadowed = render(bsdf), render(bsdf, shadows=True)
    darker = (shadowed.sum(-1) < plain.sum(-1) - 1e-4)
    # A shadow appears on the plane behind the sphere, and only there.
    assert darker.sum() > 20
    assert np.all(shadowed <= plain + 1e-6)


def test_final_clamp():
    bright = {"type": "lambert", "mode": "hdr", "reflectance": 0.9}
    scene = lambda clamp: mi.load_dict(scene_dict(bright, {"type": "scanline", "clamp": clamp},
                                                  light_intensity=200.0))
    clamped = np.array(mi.render(scene(True)))
    unclamped = np.array(mi.render(scene(False)))
    assert clamped.max() <= 1.0 and clamped.min() >= 0.0
    assert unclamped.max() > 2.0
    np.testing.assert_allclose(clamped, np.clip(unclamped, 0, 1), rtol=1e-6, atol=1e-7)


def test_every_light_is_summed():
    """Two lights: the image is the sum of the single-light images, exactly (no random light pick)."""
    bsdf = {"type": "lambert", "mode": "scanline"}
    one = scene_dict(bsdf, {"type": "scanline", "clamp": False})
    two = dict(one, light2={"type": "point", "position": [-3.0, 0.0, 2.0],
                            "intensity": {"type": "rgb", "value": 4.0}})
    other = dict(one, light={"type": "point", "position": [-3.0, 0.0, 2.0],
                             "intensity": {"type": "rgb", "value": 4.0}})
    img = [np.array(mi.render(mi.load_dict(s), spp=1)) for s in (one, other, two)]
    np.testing.assert_allclose(img[2], img[0] + img[1], rtol=1e-5, atol=1e-6)
