"""Mitsuba's differentiable rendering through every plugin: the integrators
``prb`` (path replay backpropagation) and ``path`` (differentiated as a
whole), their ``render_forward`` and ``render_backward``, ``mi.render`` as a
custom differentiable operation (``dr.custom``), and gradient descent.

1. Every plugin, every parameter. In :func:`support.tiles_scene` (a tile per
   plugin, point lights only, direct light) each pixel is, for a fixed seed,
   a smooth function of the parameters: no light path depends on a sampled
   direction. So central finite differences of primal renders are the
   derivatives, and ``render_backward`` (every parameter at once, under an
   adjoint image), ``render_forward`` (along one tangent of all the
   parameters) and ``mi.render``'s custom operation must give them. The
   plugins share the scene: each call reaches them by a virtual call.
2. The plugins with a Mitsuba twin (lambert as ``diffuse``; cook_torrance
   as a Beckmann conductor, as ``roughconductor``) through ``prb`` on the
   scenes of Mitsuba 3.9.1's integrator tests
   (``src/integrators/tests/test_ad_integrators.py``) in which a BSDF is
   differentiated or carries the derivative: a plane's colour seen directly
   and the shading normals of a mesh (here one scene), a wall's colour seen
   through one more bounce. Primal images, forward derivatives and backward
   gradients equal those with Mitsuba's BSDFs, rendered in the same test
   with the same seed. The other plugins have no twin: part 1 is their check.
3. SGD with momentum recovers every plugin's colour from 0.1.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import drjit as dr
import mitsuba as mi

from mi_brdfs.bsdfs import BY_NAME
from support import floats, plugin_configs, tensor, tile, tiles_scene

SPP = 4
SEED = 3
SEED_GRAD = int(mi.sample_tea_32(SEED, 1)[0])   # the seed mi.render's gradient pass takes
INTEGRATORS = ["prb", "path"]


def differentiable(params) -> list[str]:
    """The scene's BSDF parameters that can be differentiated."""
    return [k for k in params.keys() if ".bsdf." in k and dr.is_float_v(params[k])
            and not (params.flags(k) & mi.ParamFlags.NonDifferentiable)]


def set_values(params, values: dict) -> None:
    """Write {key: NumPy value} into the scene as arrays in memory (not
    literals: one kernel for every value), and update."""
    for key, value in values.items():
        assert type(params[key]) is mi.Float, key
        params[key] = floats(np.atleast_1d(value))
    params.update()


def image(integrator, scene, seed=SEED_GRAD) -> np.ndarray:
    return np.array(integrator.render(scene, seed=seed, spp=SPP), dtype=np.float64)


# ----------------------------------------------------------------------------
#  1. Every plugin, every parameter, against finite differences
# ----------------------------------------------------------------------------

@pytest.fixture(scope="module", params=INTEGRATORS)
def tiles(request):
    """The tiles scene rendered by one integrator (max_depth 2: direct light),
    with its finite differences at SEED_GRAD: of the weighted sum
    Σ adjoint · image for each parameter, and of the image along a tangent."""
    integrator = mi.load_dict({"type": request.param, "max_depth": 2})
    scene = mi.load_dict(tiles_scene(plugin_configs(), {"type": "path", "max_depth": 2}, SPP))
    params = mi.traverse(scene)
    keys = differentiable(params)
    initial = {k: np.array(params[k], dtype=np.float64) for k in keys}
    rng = np.random.default_rng(8)
    adjoint = rng.uniform(0.5, 1.5, image(integrator, scene).shape)
    tangent = {k: rng.uniform(-1.0, 1.0, v.shape) for k, v in initial.items()}
    step = {k: 1e-3 * max(1.0, float(np.abs(v).max())) for k, v in initial.items()}

    def shifted(key, h):
        set_values(params, {key: initial[key] + h})
        out = image(integrator, scene)
        set_values(params, {key: initial[key]})
        return out

    gradient = {k: float(np.sum(adjoint * (shifted(k, step[k]) - shifted(k, -step[k]))))
                / (2 * step[k]) for k in keys}
    h = 1e-3

    def along(sign):
        set_values(params, {k: initial[k] + sign * h * tangent[k] for k in keys})
        return image(integrator, scene)

    directional = (along(1) - along(-1)) / (2 * h)
    set_values(params, initial)
    assert {k.split(".")[0] for k in keys} == set(BY_NAME), "a plugin has no parameter here"
    yield SimpleNamespace(integrator=integrator, scene=scene, params=params, keys=keys,
                          initial=initial, adjoint=adjoint, tangent=tangent, gradient=gradient,
                          directional=directional)


def attached(t) -> None:
    """Every parameter grad-enabled, at its initial value."""
    set_values(t.params, t.initial)
    for k in t.keys:
        dr.enable_grad(t.params[k])
    t.params.update()


def assert_gradients(t, grads: dict) -> None:
    """Each parameter's gradient equals its finite difference (2 % or 1e-3
    of the largest gradient of its plugin)."""
    for key in t.keys:
        plugin = key.split(".")[0]
        scale = max(abs(g) for k, g in t.gradient.items() if k.startswith(plugin + "."))
        assert scale > 0, plugin
        assert grads[key] == pytest.approx(t.gradient[key], rel=2e-2, abs=1e-3 * scale), key


def assert_directional(t, derivative: np.ndarray) -> None:
    """The forward derivative equals the finite difference pixel by pixel,
    on every tile."""
    for i, plugin in enumerate(BY_NAME):
        fd = tile(t.directional, i)
        assert np.abs(fd).max() > 0, plugin
        np.testing.assert_allclose(tile(derivative, i), fd, rtol=2e-2,
                                   atol=1e-3 * np.abs(fd).max(), err_msg=plugin)


def test_render_backward_matches_finite_differences(tiles):
    attached(tiles)
    tiles.integrator.render_backward(tiles.scene, tiles.params,
                                     grad_in=tensor(tiles.adjoint),
                                     seed=SEED_GRAD, spp=SPP)
    grads = {k: float(np.sum(np.array(dr.grad(tiles.params[k])))) for k in tiles.keys}
    assert_gradients(tiles, grads)


def tangent_scene(t) -> mi.Float:
    """Every parameter written as initial + θ · tangent, θ = 0 grad-enabled."""
    set_values(t.params, t.initial)
    theta = mi.Float(0.0)
    dr.enable_grad(theta)
    for k in t.keys:
        t.params[k] = t.params[k] + theta * floats(t.tangent[k])
    t.params.update()
    return theta


# Forwards and through mi.render: prb only, as Mitsuba's own tests (path's
# forward pass differentiates its whole loop: several times the cost).
@pytest.mark.parametrize("tiles", ["prb"], indirect=True)
def test_render_forward_matches_finite_differences(tiles):
    theta = tangent_scene(tiles)
    dr.forward(theta, dr.ADFlag.ClearEdges)
    derivative = tiles.integrator.render_forward(tiles.scene, params=theta, seed=SEED_GRAD,
                                                 spp=SPP)
    assert_directional(tiles, np.array(derivative, dtype=np.float64))


@pytest.mark.parametrize("tiles", ["prb"], indirect=True)
def test_mi_render_custom_op_matches_finite_differences(tiles):
    """The primal image at SEED, and derivatives of the gradient pass (at
    SEED_GRAD), backwards and forwards."""
    attached(tiles)
    rendered = mi.render(tiles.scene, tiles.params, integrator=tiles.integrator, seed=SEED,
                         seed_grad=SEED_GRAD, spp=SPP)
    np.testing.assert_allclose(np.array(dr.detach(rendered)),
                               image(tiles.integrator, tiles.scene, seed=SEED), rtol=1e-5,
                               atol=1e-7)
    dr.backward(dr.sum(rendered * tensor(tiles.adjoint), axis=None))
    assert_gradients(tiles, {k: float(np.sum(np.array(dr.grad(tiles.params[k]))))
                             for k in tiles.keys})
    theta = tangent_scene(tiles)
    rendered = mi.render(tiles.scene, tiles.params, integrator=tiles.integrator, seed=SEED,
                         seed_grad=SEED_GRAD, spp=SPP)
    dr.forward(theta)
    assert_directional(tiles, np.array(dr.grad(rendered), dtype=np.float64))


# ----------------------------------------------------------------------------
#  2. Against Mitsuba's own BSDFs, on the scenes of its integrator tests
# ----------------------------------------------------------------------------
# Each scene holds lambert (Mitsuba: diffuse) and cook_torrance as a Beckmann
# conductor (roughconductor); it is rendered with ours and with Mitsuba's, at
# the same seed: the same sample paths. Left out: oren_nayar, which is lambert
# at σ = 0 (tests/bsdfs/test_oren_nayar.py compares it with diffuse there), and
# toon, phong, blinn and ward, which no Mitsuba BSDF computes (part 1 checks all).
TWINS = [({"type": "lambert"}, {"type": "diffuse"}),
         ({"type": "cook_torrance", "k": 0.0, "f0": 1.0, "geometry": "smith",
           "distribution": "beckmann", "alpha": 0.3, "specular_reflectance": 1.0},
          {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.3,
           "specular_reflectance": 1.0})]
# Per pixel, 1 % (measured: at most 0.3 %; Mitsuba's rational fit of
# Beckmann's G1, 0.35 % per G1, tests/bsdfs/test_cook_torrance.py), or 0.1 % of
# the brightest where the derivatives of the colours and the normals cancel.
RTOL = 1e-2
RES, TWIN_SPP = 24, 16


def T():
    return mi.ScalarTransform4f()


def wall() -> mi.ScalarTransform4f:
    """The wall of Mitsuba's scenes: at x = 1.25, facing the origin."""
    return T().translate([1.25, 0.0, 1.0]) @ T().rotate([0, 1, 0], -90)


def strip_mesh(name: str, bsdf, x0: float, x1: float) -> mi.Mesh:
    """The strip [x0, x1] × [-1, 1] of the plane z = 0 as two triangles, with
    texture coordinates and the vertex normals Mitsuba computes (those of a
    mesh file without normals): a plane whose shading normals are parameters."""
    props = mi.Properties()
    props["bsdf"] = bsdf
    mesh = mi.Mesh(name, 4, 2, props, has_vertex_normals=True, has_vertex_texcoords=True)
    params = mi.traverse(mesh)
    corners = [(x0, -1.0), (x1, -1.0), (x1, 1.0), (x0, 1.0)]
    params["vertex_positions"] = mi.Float([c for x, y in corners for c in (x, y, 0.0)])
    params["vertex_texcoords"] = mi.Float([c for x, y in corners
                                           for c in ((x - x0) / (x1 - x0), (y + 1) / 2)])
    params["faces"] = mi.UInt32([0, 1, 2, 0, 2, 3])
    params.update()
    mesh.recompute_vertex_normals()
    return mesh


def plane_and_sphere(diffuse, glossy) -> dict:
    """A diffuse plane and a small glossy sphere on it, in a constant environment."""
    return {"plane": {"type": "rectangle", "bsdf": diffuse},
            "sphere": {"type": "sphere", "to_world": T().scale(0.25), "bsdf": glossy},
            "light": {"type": "constant"}}


def lit_strips(diffuse, glossy):
    """Mitsuba's first and third scenes in one: the plane, diffuse on the left
    and glossy on the right, whose vertex normals turn about the y axis, and
    the sphere; lit by the environment and an area light on the wall. The
    diffuse strip's and the sphere's colours are differentiated too."""
    scene = plane_and_sphere(diffuse, glossy)
    del scene["plane"]
    scene["left"] = strip_mesh("left", mi.load_dict(diffuse), -1.0, 0.0)
    scene["right"] = strip_mesh("right", mi.load_dict(glossy), 0.0, 1.0)
    scene["wall_light"] = {"type": "rectangle", "to_world": wall(),
                           "emitter": {"type": "area",
                                       "radiance": {"type": "rgb", "value": 3.0}}}
    return scene, ["left.bsdf.reflectance.value", "sphere.bsdf.specular_reflectance.value",
                   "left.vertex_normals", "right.vertex_normals"], 2


def wall_colour(diffuse, glossy):
    """Mitsuba's second scene: the plane and the sphere, brighter, beside a
    green glossy wall out of view whose colour is differentiated: its
    derivative reaches the image by one more bounce."""
    scene = plane_and_sphere(diffuse, glossy)
    scene["light"]["radiance"] = 3.0
    scene["green"] = {"type": "rectangle", "to_world": wall(),
                      "bsdf": {**glossy, "specular_reflectance": {"type": "rgb",
                                                                  "value": [0.1, 1.0, 0.1]}}}
    return scene, ["green.bsdf.specular_reflectance.value"], 3


SCENES = {"lit_strips": lit_strips, "wall_colour": wall_colour}


def differentiated(scene_name: str, side: int):
    """(scene, θ, max_depth): the scene with ours (side 0) or Mitsuba's (1)
    BSDFs, its parameters written as functions of θ = 0 (a colour plus θ;
    normals turned by θ radians)."""
    scene, keys, depth = SCENES[scene_name](*(pair[side] for pair in TWINS))
    scene["sensor"] = {"type": "perspective",
                       "to_world": T().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
                       "film": {"type": "hdrfilm", "width": RES, "height": RES,
                                "rfilter": {"type": "box"}, "sample_border": True}}
    scene = mi.load_dict({"type": "scene", **scene}, optimize=False)
    params = mi.traverse(scene)
    params.keep(keys)
    theta = mi.Float(0.0)
    dr.enable_grad(theta)
    for key in keys:
        if key.endswith("vertex_normals"):
            turn = mi.Transform4f().rotate(axis=[0.0, 1.0, 0.0], angle=theta)
            params[key] = dr.ravel(turn @ dr.unravel(mi.Normal3f, params[key]))
        else:
            params[key] = params[key] + theta
    params.update()
    return scene, theta, depth


def prb_renders(scene_name: str, side: int) -> dict[str, np.ndarray]:
    """prb's primal image, forward derivative image and backward gradient of
    θ (under the constant adjoint 10⁻³ of Mitsuba's tests)."""
    scene, theta, depth = differentiated(scene_name, side)
    prb = mi.load_dict({"type": "prb", "max_depth": depth})
    out = {"primal": np.array(prb.render(scene, seed=SEED, spp=TWIN_SPP))}
    dr.forward(theta, dr.ADFlag.ClearEdges)
    out["forward"] = np.array(prb.render_forward(scene, params=theta, seed=SEED, spp=TWIN_SPP))
    scene, theta, _ = differentiated(scene_name, side)
    prb.render_backward(scene, params=theta, grad_in=dr.full(mi.TensorXf, 1e-3, (RES, RES, 3)),
                        seed=SEED, spp=TWIN_SPP)
    out["backward"] = np.array(dr.grad(theta))
    return out


@pytest.mark.parametrize("scene_name", SCENES)
def test_prb_renders_as_with_mitsuba_bsdfs(scene_name):
    ours, theirs = prb_renders(scene_name, 0), prb_renders(scene_name, 1)
    for what, reference in theirs.items():
        assert np.abs(reference).max() > 0, f"{what}: nothing to compare"
        np.testing.assert_allclose(ours[what], reference, rtol=RTOL,
                                   atol=1e-3 * np.abs(reference).max(), err_msg=what)


# ----------------------------------------------------------------------------
#  3. Gradient descent
# ----------------------------------------------------------------------------

def colour_key(name: str, config: dict) -> str:
    """The traverse key of the first colour the plugin's configuration gives."""
    p = next(p for p in BY_NAME[name].PARAMS if p.role == "colour" and p.name in config)
    return f"{name}.bsdf.{p.name}.value"


def test_sgd_recovers_every_plugins_colour():
    """Every plugin's first colour, started at 0.1, recovered from a render of
    the tiles by SGD with momentum (Mitsuba's optimiser; its own test's
    settings: momentum 0.8, 100 steps, 8 spp, the `direct` integrator, the
    mean of the last 10 steps within 10⁻³). The loss is each tile's squared
    error relative to its reference, summed: one step size suits every plugin."""
    configs = plugin_configs()
    scene = mi.load_dict(tiles_scene(configs, {"type": "direct"}, spp=8))
    integrator = scene.integrator()
    reference = integrator.render(scene, seed=SEED)
    params = mi.traverse(scene)
    keys = {name: colour_key(name, config) for name, config in configs.items()}
    params.keep(list(keys.values()))
    truth = {key: configs[name][key.split(".")[2]] for name, key in keys.items()}
    scale = [dr.mean(dr.square(tile(reference, i)), axis=None).array[0] for i in range(len(keys))]
    opt = mi.ad.SGD(lr=0.1, momentum=0.8)
    for key in truth:
        opt[key] = mi.Float(0.1)
    params.update(opt)
    steps, window = 100, 10
    mean = {key: 0.0 for key in truth}
    for step in range(steps):
        rendered = integrator.render(scene, seed=SEED)
        loss = sum(dr.mean(dr.square(tile(rendered, i) - tile(reference, i)), axis=None) / scale[i]
                   for i in range(len(keys)))
        dr.backward(loss)
        opt.step()
        params.update(opt)
        if step >= steps - window:
            for key in truth:
                mean[key] += float(params[key][0]) / window
    for key, value in truth.items():
        assert mean[key] == pytest.approx(value, abs=1e-3), key
