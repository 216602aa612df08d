"""Mitsuba 3.9.1's ``src/render/tests/test_freeze.py`` (tag v3.9.1, commit
478e193a), the tests with a BSDF in them, ported onto the plugins: frozen
renders (``dr.freeze``) of scenes made of ``lambert`` and ``cook_torrance``,
in Mitsuba's adapters, equal the unfrozen renders and replay.

Ported: test01 (Cornell box, emitter updated between replays), test02b
(replay on another scene instance), test03 (a colour optimised through a
frozen gradient step), test04 and test05 (every BSDF of upstream's list that
holds a plugin: rendered frozen, and evaluated inside a frozen function).

What changed, and why (each change is also commented at its test):

- The Cornell box's ``diffuse`` materials (white, red, green) are all
  ``lambert`` with the same reflectances (:func:`cornell_box`).
- test04/test05's list keeps the entries where a plugin stands in for a
  Mitsuba BSDF: ``diffuse`` -> ``lambert``, ``roughconductor`` ->
  ``cook_torrance`` (k = 0, F0 = 1, Smith); in ``bumpmap``, ``normalmap``
  and ``blendbsdf`` the nested ``roughplastic`` -> ``cook_torrance`` (its
  default: a Lambert lobe under a Beckmann lobe, a plastic's structure);
  ``mask`` and ``twosided`` hold ``lambert``. ``blendbsdf``'s ``conductor``
  stays (no counterpart). Added: ``cook_torrance`` with
  ``energy_compensation`` (tabulated albedos, the one kind of plugin state
  that is not a scene parameter: the plugin holds them as Dr.Jit members,
  so a frozen function sees them as inputs). The entries without a plugin (dielectrics,
  conductor, hair, plastic, principled, the custom Python BSDF) test
  Mitsuba itself and are not ported.
- Textures: upstream reads ``wood.jpg``, ``leaf_mask.png``,
  ``floor_tiles_bumpmap.png``, ``floor_tiles_normalmap.jpg`` and
  ``noise_01.jpg`` from mitsuba-data; here the same roles (a colour, an
  opacity mask, a height field, a normal map, a blend weight) are 64 x 64
  bitmaps made by :func:`bitmap` from a fixed seed (no files).
- test02 (pose estimation of mitsuba-data's bunny: geometry, not a BSDF)
  and tests 06-14 (emitters, integrators, shapes, optimisers, media,
  samplers) are not ported: they hold no BSDF beyond the Cornell box's.
- Assertions, sizes (16 x 16), replay counts and recording counts are
  upstream's.
"""
import gc

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from upstream import cook_torrance, lambert

AUTO_OPAQUE = [False, True]


@pytest.fixture(autouse=True, scope="module")
def no_loose_bsdfs():
    """A frozen render traces every BSDF alive in the process: collect what
    earlier modules left for the garbage collector (as tests/render/test_passes.py)."""
    gc.collect()


def cornell_box(w=16, h=16, integrator=None) -> dict:
    """mi.cornell_box() with lambert for its diffuse materials (changed)."""
    scene = mi.cornell_box()
    for name in ("white", "red", "green"):
        assert scene[name]["type"] == "diffuse"
        scene[name] = lambert(reflectance=scene[name]["reflectance"])
    scene["sensor"]["film"]["width"] = w
    scene["sensor"]["film"]["height"] = h
    if integrator:
        scene["integrator"] = {"type": integrator}
    return scene


def mse(image, image_ref):
    return dr.sum(dr.square(image - image_ref), axis=None)


def assert_render(scene, n, update=None, n_recordings=2, spp=1, auto_opaque=True):
    def func(scene: mi.Scene) -> mi.TensorXf:
        return mi.render(scene, spp=spp)

    frozen = dr.freeze(func, auto_opaque=auto_opaque)
    for i in range(n):
        if update:
            params = mi.traverse(scene)
            update(i, params)
            params.update()

        res = frozen(scene)
        ref = func(scene)
        assert dr.allclose(ref, res)
        assert dr.max(ref, axis=None) > 0                 # added: a lit image
    assert frozen.n_recordings == n_recordings


@pytest.mark.parametrize("auto_opaque", AUTO_OPAQUE)
def test01_cornell_box(variants_vec_rgb, auto_opaque):
    k = "light.emitter.radiance.value"
    scene = mi.load_dict(cornell_box(), parallel=True)
    params = mi.traverse(scene)
    value = mi.Float(params[k].x)

    def update(i, params):
        params[k].x = value + 10.0 * i

    assert_render(scene, 5, update, auto_opaque=auto_opaque)


def test02b_cross_scene_rebind(variants_vec_rgb):
    def make_scene(green):
        d = cornell_box(32, 32)
        d["green"]["reflectance"]["value"] = green
        return mi.load_dict(d)

    def render(scene):
        return mi.render(scene, spp=16)

    frozen = dr.freeze(render)
    scene_a = make_scene([0.1, 0.4, 0.1])
    scene_b = make_scene([0.4, 0.1, 0.1])

    res_a = frozen(scene_a)
    res_b = frozen(scene_b)   # replay on a *different* scene instance
    ref_b = render(scene_b)   # non-frozen reference for scene B

    assert dr.allclose(res_b, ref_b, atol=1e-3)
    assert not dr.allclose(res_b, res_a, atol=1e-3)


@pytest.mark.parametrize("auto_opaque", AUTO_OPAQUE)
def test03_optimize_color(variants_vec_rgb, auto_opaque):
    k = "red.reflectance.value"
    n = 10

    def optimize(scene, image_ref):
        params = mi.traverse(scene)
        params.keep(k)
        image = mi.render(scene, params, spp=1)
        loss = mse(image, image_ref)
        dr.backward(loss)
        return image, loss

    frozen = dr.freeze(optimize, auto_opaque=auto_opaque)

    def run(n, optimize):
        scene = mi.load_dict(cornell_box(integrator="prb"), parallel=True)
        image_ref = mi.render(scene, spp=512)

        opt = mi.ad.Adam(lr=0.05)
        opt[k] = mi.Color3f(0.01, 0.2, 0.9)
        for _ in range(n):
            params = mi.traverse(scene)
            params.keep(k)
            params.update(opt)
            optimize(scene, image_ref)
            opt.step()
        return opt[k]

    param_ref = run(n, optimize)
    param_frozen = run(n, frozen)

    assert frozen.n_recordings == 2
    assert dr.allclose(param_ref, param_frozen)
    # Added: the descent moved the colour (a zero gradient would pass the above).
    assert not dr.allclose(param_ref, mi.Color3f(0.01, 0.2, 0.9), atol=0.05)


# ----------------------------------------------------------------------------
#  Tests 04 and 05: each BSDF of upstream's list that holds a plugin
# ----------------------------------------------------------------------------

def bitmap(role: str, size: int = 64) -> mi.Bitmap:
    """A fixed-seed stand-in for upstream's texture files (changed): smooth
    noise in [0.05, 0.95]; RGB for a colour, one channel for a mask, a height
    or a weight; for a normal map, unit normals tilted by up to ~30 degrees,
    stored as n/2 + 1/2."""
    rng = np.random.default_rng(["colour", "mask", "height", "normals", "weight"].index(role))
    coarse = rng.random((8, 8, 3))
    fine = np.kron(coarse, np.ones((size // 8, size // 8, 1)))
    value = 0.05 + 0.9 * fine
    if role == "normals":
        n = np.dstack([value[..., :2] - 0.5, np.ones((size, size))])
        value = 0.5 * n / np.linalg.norm(n, axis=-1, keepdims=True) + 0.5
    elif role != "colour":
        value = value[..., :1]
    return mi.Bitmap(value.astype(np.float32))


def texture(role: str, **properties) -> dict:
    return {"type": "bitmap", "bitmap": bitmap(role), **properties}


def bsdf_dict(bsdf: str) -> dict:
    """Upstream's default configuration of each BSDF, with the plugins in
    Mitsuba's place (see the module docstring)."""
    if bsdf == "twosided":
        return {"type": "twosided",
                "material": lambert(reflectance={"type": "rgb", "value": 0.4})}
    if bsdf == "mask":
        return {"type": "mask",
                "material": {"type": "twosided",
                             "bsdf": lambert(reflectance=texture("colour"))},
                "opacity": texture("mask")}
    if bsdf == "bumpmap":
        return {"type": "bumpmap", "arbitrary": texture("height", raw=True),
                "bsdf": {"type": "cook_torrance"}}
    if bsdf == "normalmap":
        return {"type": "normalmap", "normalmap": texture("normals", raw=True),
                "bsdf": {"type": "cook_torrance"}}
    if bsdf == "blendbsdf":
        return {"type": "blendbsdf", "weight": texture("weight"),
                "bsdf_0": {"type": "conductor"},
                "bsdf_1": {"type": "cook_torrance", "diffuse_reflectance": 0.1}}
    if bsdf == "lambert":
        return lambert(reflectance=texture("colour"))
    if bsdf == "cook_torrance_compensated":
        return cook_torrance(energy_compensation=True)
    assert bsdf == "cook_torrance"
    return cook_torrance()


BSDFS = ["lambert", "cook_torrance", "cook_torrance_compensated", "bumpmap", "normalmap",
         "blendbsdf", "mask", "twosided"]


@pytest.mark.parametrize("bsdf", BSDFS)
@pytest.mark.parametrize("auto_opaque", AUTO_OPAQUE)
def test04_bsdf(variants_vec_rgb, bsdf, auto_opaque):
    def load_scene(bsdf: str):
        scene = cornell_box()
        scene["white"] = bsdf_dict(bsdf)
        return mi.load_dict(scene, parallel=True)

    scene2 = load_scene(bsdf)    # noqa: F841  (upstream: a second live copy)
    scene = load_scene(bsdf)
    assert_render(scene, 5, auto_opaque=auto_opaque)


@pytest.mark.parametrize("bsdf", BSDFS)
@pytest.mark.parametrize("auto_opaque", AUTO_OPAQUE)
def test05_bsdf_eval(variants_vec_rgb, bsdf, auto_opaque):
    n = 5

    def func(bsdf: mi.BSDF, uv: mi.Point2f) -> mi.Spectrum:
        si = mi.SurfaceInteraction3f()
        si.t = 0.1
        si.dp_du = mi.Vector3f(0.5514372, 0.84608955, 0.41559092)
        si.dp_dv = mi.Vector3f(0.14551054, 0.54917541, 0.39286475)
        si.p = mi.Point3f(0, 0, 0)
        si.n = mi.Vector3f(0, 0, 1)
        si.sh_frame = mi.Frame3f(0, 0, 1)
        si.wi = mi.Vector3f(0, 0, 1)
        si.uv = uv
        wo = mi.Vector3f(0, 0, 1)
        return bsdf.eval(mi.BSDFContext(), si, wo, active=True)

    frozen = dr.freeze(func, auto_opaque=auto_opaque)
    bsdf = mi.load_dict(bsdf_dict(bsdf))

    for i in range(n):
        uv = dr.full(mi.Point2f, 0.5, n + 2)
        res = frozen(bsdf, uv)
        ref = func(bsdf, uv)
        assert dr.allclose(res, ref)

    assert frozen.n_recordings > 0 and frozen.n_recordings <= 2
