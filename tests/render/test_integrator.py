"""The scanline integrator against an independent NumPy shading of the lecture's formula."""
import numpy as np
import pytest

import mitsuba as mi

from mi_brdfs._jit import from_numpy
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
    pos = from_numpy(mi.Point2f, ((i + 0.5) / RES, (j + 0.5) / RES))
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


# ----------------------------------------------------------------------------
#  Mitsuba's adapters: see-through surfaces (mask, null) and twosided
# ----------------------------------------------------------------------------

T = mi.ScalarTransform4f
HALF = 1.0                 # the orthographic camera sees x, y in [-1, 1]


def stage(integrator, light=(0.8, 0.6, 2.5), spp=1, **shapes):
    """A lambert plane (z = 0, facing +z, hdr mode) filling the view of an
    orthographic camera at +z, one point light, and the given ``shapes``.
    One sample per pixel at the pixel centre (no jitter) unless ``spp``
    (stratified: the pixels' areas are covered evenly)."""
    sampler = {"type": "stratified", "sample_count": spp, "jitter": spp > 1}
    return mi.load_dict({
        "type": "scene", "integrator": integrator,
        "sensor": {"type": "orthographic",
                   "to_world": T().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0])
                   @ T().scale([HALF, HALF, 1]),
                   "film": {"type": "hdrfilm", "width": RES, "height": RES,
                            "rfilter": {"type": "box"}},
                   "sampler": sampler},
        "plane": {"type": "rectangle", "to_world": T().scale(3.0),
                  "bsdf": {"type": "lambert", "reflectance": {"type": "rgb",
                                                              "value": [0.8, 0.6, 0.3]}}},
        "light": {"type": "point", "position": list(light),
                  "intensity": {"type": "rgb", "value": 8.0}},
        **shapes})


def card(opacity, at=(0.0, 0.0, 1.0), size=0.5, bsdf=None):
    """A square card facing +z holding a ``mask`` of the given opacity (a
    number or a texture) over a blue lambert."""
    inner = bsdf or {"type": "lambert", "reflectance": {"type": "rgb", "value": [0.1, 0.2, 0.9]}}
    return {"type": "rectangle", "to_world": T().translate(list(at)) @ T().scale(size),
            "bsdf": {"type": "mask", "opacity": opacity, "bsdf": inner}}


SCANLINE = {"type": "scanline", "clamp": False}


def image(scene):
    return np.array(mi.render(scene), dtype=np.float64)


@pytest.mark.parametrize("shadows", [False, True])
def test_a_transparent_card_is_invisible(shadows):
    """A fully transparent mask card in front of the lit plane (and between the
    light and the plane) changes nothing: it rendered black here once."""
    integrator = {**SCANLINE, "shadows": shadows}
    plain = image(stage(integrator))
    with_card = image(stage(integrator, front=card(0.0)))
    assert plain.max() > 0.1
    np.testing.assert_allclose(with_card, plain, rtol=1e-5, atol=1e-7)


A = card(0.3, at=(1.6, 0.0, 1.0), size=0.4)       # opacity 0.3: 70 % passes
B = card(0.5, at=(2.45, 0.15, 1.5), size=0.15)    # 50 %, nearer the light, partly behind A


@pytest.mark.parametrize("cards, passing", [
    ({"a": A}, {0.7}),
    ({"a": A, "b": B}, {0.7, 0.5, 0.35}),          # behind both: 0.7 x 0.5
    ({"a": card(1.0, at=(1.6, 0.0, 1.0), size=0.4)}, {0.0}),      # opaque: a full shadow
])
def test_shadow_rays_pass_through_by_the_opacity(cards, passing):
    """Cards outside the view, between the light and the plane: with shadows,
    the light reaching the plane behind them is the product of (1 - opacity)
    over the cards crossed (Mitsuba's eval_null_transmission); elsewhere
    nothing changes. Without shadows the cards have no effect at all."""
    light = (3.0, 0.0, 2.0)
    plain = image(stage({**SCANLINE, "shadows": True}, light))
    shadowed = image(stage({**SCANLINE, "shadows": True}, light, **cards))
    ratio = (shadowed / plain)[..., 0]
    for value in passing | {1.0}:
        assert (np.abs(ratio - value) < 1e-4).sum() > 20, value
    assert np.all(np.min([np.abs(ratio - v) for v in passing | {1.0}], axis=0) < 1e-4)
    # behind card A: the plane points whose ray to the light crosses it (at z = 1)
    x = (np.arange(RES) + 0.5) / RES * 2 * HALF - HALF
    behind_a = (np.abs((x[None, :] + 3.0) / 2 - 1.6) < 0.38) & (np.abs(x[:, None] / 2) < 0.38)
    assert behind_a.sum() > 100 and np.all(ratio[behind_a] < 0.7 + 1e-4)
    np.testing.assert_allclose(image(stage(SCANLINE, light, **cards)),
                               image(stage(SCANLINE, light)), rtol=1e-6)


def blocks(img, n=4):
    """Means over n x n pixel blocks (the noise of a stochastic render averages out)."""
    h, w, c = img.shape
    return img.reshape(h // n, n, w // n, n, c).mean(axis=(1, 3))


CHECKER = {"type": "checkerboard", "color0": 0.0, "color1": 1.0,
           "to_uv": mi.ScalarTransform3f().scale(3)}
SEE_THROUGH = {"mask 0.3": card(0.3), "mask 0.7": card(0.7), "mask checkerboard": card(CHECKER),
               "null": {**card(0.0), "bsdf": {"type": "null"}},
               "thindielectric": {**card(0.0), "bsdf": {"type": "thindielectric"}}}


@pytest.mark.parametrize("kind", SEE_THROUGH)
def test_see_through_surfaces_agree_with_volpath(kind):
    """hdr-mode BSDFs, clamp off, shadows on: the scan-line integrator and
    Mitsuba's volpath at max_depth 2 compute the same direct light through a
    see-through card seen by the camera and shadowing the plane. volpath
    picks the card or what lies behind at random (the mask's sample), so it is
    compared over 4 x 4 pixel blocks at 1024 spp (and ours at 256 spp, so that
    both average over the pixels' areas at the edges)."""
    front = {**SEE_THROUGH[kind], "to_world": T().translate([0.2, 0.1, 1.0]) @ T().scale(0.55)}
    ours = image(stage({**SCANLINE, "shadows": True}, spp=256, front=front))
    theirs = image(stage({"type": "volpath", "max_depth": 2}, spp=1024, front=front))
    plain = image(stage(SCANLINE))
    if kind != "null":
        assert np.abs(blocks(ours) - blocks(plain)).max() > 0.02       # the card shows
    np.testing.assert_allclose(blocks(ours), blocks(theirs), rtol=0.01, atol=1e-3)


@pytest.mark.parametrize("mode", ["hdr", "scanline"])
def test_twosided_from_behind(mode):
    """Seen from below, a plane is black unless its BSDF is twosided, in both
    modes; twosided, it is the mirror image of the plane seen from above with
    the light mirrored too."""
    bsdf = {"type": "lambert", "mode": mode, "reflectance": 0.7}
    light = [0.8, 0.6, 2.5]

    def view(z, bsdf):
        return mi.load_dict({
            "type": "scene", "integrator": {"type": "scanline"},
            "sensor": {"type": "orthographic",
                       "to_world": T().look_at(origin=[0, 0, 5 * z], target=[0, 0, 0],
                                               up=[0, 1, 0]) @ T().scale([HALF, HALF, 1]),
                       "film": {"type": "hdrfilm", "width": RES, "height": RES,
                                "rfilter": {"type": "box"}},
                       "sampler": {"type": "stratified", "sample_count": 1, "jitter": False}},
            "plane": {"type": "rectangle", "to_world": T().scale(3.0), "bsdf": bsdf},
            "light": {"type": "point", "position": light[:2] + [light[2] * z],
                      "intensity": {"type": "rgb", "value": 3.0}}})
    above = image(view(1, bsdf))
    assert above.max() > 0.05
    assert image(view(-1, bsdf)).max() == 0.0                      # one-sided, from behind
    below = image(view(-1, {"type": "twosided", "bsdf": bsdf}))
    np.testing.assert_allclose(below, above[:, ::-1], rtol=1e-5, atol=1e-6)


def test_twosided_agrees_with_the_path_tracer():
    """Direct light from a point light through a twosided hdr-mode lambert seen
    from behind: the scan-line integrator (clamp off) and Mitsuba's path tracer
    at max_depth 2 compute the same value per pixel (and path the same with
    Mitsuba's diffuse)."""
    light = (0.5, -0.4, 2.0)                # on the camera's side: the plane's back
    back = T().rotate([1, 0, 0], 180) @ T().scale(3.0)               # facing -z

    def scene(integrator, inner):
        s = stage(integrator, light)
        return mi.load_dict({
            "type": "scene", "integrator": integrator, "sensor": s.sensors()[0],
            "plane": {"type": "rectangle", "to_world": back,
                      "bsdf": {"type": "twosided", "bsdf": inner}},
            "light": {"type": "point", "position": list(light),
                      "intensity": {"type": "rgb", "value": 8.0}}})
    ours = image(scene(SCANLINE, {"type": "lambert", "reflectance": 0.6}))
    path = image(scene({"type": "path", "max_depth": 2}, {"type": "lambert", "reflectance": 0.6}))
    builtin = image(scene({"type": "path", "max_depth": 2}, {"type": "diffuse", "reflectance": 0.6}))
    assert ours.max() > 0.1
    np.testing.assert_allclose(ours, path, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(ours, builtin, rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("mode, kind", [("scanline", "Scanline"), ("hdr", "PathIntegrator")])
def test_course_is_the_integrator_its_mode_names(mode, kind):
    """``course`` picks the scan-line integrator or Mitsuba's path tracer by its
    mode (the bundled scenes' one default for the BSDFs and the integrator),
    passes its other properties on, and refuses another mode in one line."""
    integrator = mi.load_dict({"type": "course", "mode": mode, "max_depth": 5})
    assert kind in type(integrator).__name__ or kind in str(integrator)
    if mode == "hdr":
        assert "max_depth = 5" in str(integrator)
    with pytest.raises(Exception, match="course: parameter 'mode' = 'foo' is invalid; valid: "
                                        '"scanline", "hdr"'):
        mi.load_dict({"type": "course", "mode": "foo"})
