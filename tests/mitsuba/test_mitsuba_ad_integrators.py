"""Mitsuba 3.9.1's ``src/integrators/tests/test_ad_integrators.py`` (tag
v3.9.1, commit 478e193a), ported onto ``lambert``: primal renders, forward
gradients and backward gradients of Mitsuba's differentiable integrators
against references rendered with Mitsuba's ``diffuse``.

What changed, and why:

- **The BSDF.** Every ``diffuse`` is ``lambert`` (hdr mode), including the
  default BSDF Mitsuba gives a shape without one (the sphere, the plain
  plane of the GI scene): each configuration builds its scene with either
  material. Resolution (128 x 128), keys, parameter updates, integrator
  depths, spp (1024; 128 backward; 256 in test04), finite-difference steps,
  error measures and every threshold are upstream's.
- **The references.** Upstream reads them from mitsuba-data
  (``tests/integrators/test_<config>_image_{primal,fwd}_ref.exr``), which its
  generator renders with ``path`` and ``diffuse`` at 12,000 spp (primal)
  and central finite differences of such renders (forward). Here that
  generator, rewritten, runs with ``diffuse`` at :data:`REF_SPP` (``python
  tests/mitsuba/test_mitsuba_ad_integrators.py`` writes
  ``tests/data/ad_integrators/``, half floats), in passes averaged in
  float64 (:func:`write_references` says why). The references are Mitsuba's
  built-in; the renders under test are the plugin's.
- **The subset** (upstream runs 60 configuration x integrator pairs, most
  at 128 x 128 x 1024 spp, three tests each: too long for this suite).
  Kept, the three scenes where the BSDF itself is what is differentiated or
  what the derivative passes through: the plane's reflectance
  (``diffuse_albedo``), a reflectance seen through an indirect bounce
  (``diffuse_albedo_g_i``), the shading normals the BSDF's frame follows
  (``rotate_shading_normals_plane``); each with ``prb`` (primal, forward,
  backward) and ``path`` (primal, backward; path's forward pass
  differentiates through its whole loop, several times prb's cost); and
  test04 (``mi.render`` as a custom op, prb). Left out: the configurations
  that differentiate a light (their BSDF is a passive grey ``diffuse``),
  ``CropWindow`` (a film feature), the moving-geometry and discontinuous
  lists (the integrators' boundary terms, up to 16,768 spp per render), and
  the projective integrators, which on these continuous scenes compute what
  ``prb`` computes.
- **Shading normals.** ``RotateShadingNormalsPlane`` loads mitsuba-data's
  ``rectangle.obj``; here the same four-vertex rectangle is built by
  :func:`rectangle_mesh` (its vertex normals computed by Mitsuba, as the
  OBJ loader computes them for a file without normals). Its forward
  reference takes a finite-difference step of 1e-2 radians instead of
  upstream's 1e-3 (the config says why; at 1e-3 single pixels of the
  reference came out several times above the largest derivative in
  mitsuba-data's, while the image's mean agreed). Its primal test is a strict xfail
  (``primal_xfail``): upstream's maximum-error bound fails for Mitsuba's own
  ``diffuse`` too, which renders the very same image at the same seed;
  ``--runxfail -k "primal and rotate"`` prints the errors.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import mi_brdfs  # noqa: F401  (LLVM set-up before drjit, when run as a script)
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

DATA = Path(__file__).resolve().parents[1] / "data" / "ad_integrators"
RES = 128                 # upstream's
REF_SPP = 12_000          # upstream's reference spp (its generator's default)


def T():
    return mi.ScalarTransform4f()


def rectangle_mesh(bsdf: dict) -> mi.Mesh:
    """mitsuba-data's common/meshes/rectangle.obj, built here: the square
    [-1, 1]² in z = 0 as two triangles with texture coordinates, and vertex
    normals computed by Mitsuba (as its OBJ loader does), with ``bsdf``."""
    props = mi.Properties()
    props["bsdf"] = mi.load_dict(bsdf)
    mesh = mi.Mesh("plane", 4, 2, props, has_vertex_normals=True, has_vertex_texcoords=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float([-1, -1, 0, 1, -1, 0, -1, 1, 0, 1, 1, 0])
    params["faces"] = mi.UInt32([1, 2, 0, 1, 3, 2])
    params["vertex_texcoords"] = mi.Float([1, 1, 0, 0, 0, 1, 1, 0])
    params.update()
    mesh.recompute_vertex_normals()
    return mesh


# ----------------------------------------------------------------------------
#  The configurations (upstream's classes as data)
# ----------------------------------------------------------------------------

@dataclass
class Config:
    name: str                                  # upstream's reference file stem
    scene: Callable[[Callable[..., dict]], dict]   # material -> scene dict (no sensor)
    key: str
    error_mean_threshold: float
    error_max_threshold: float
    error_mean_threshold_bwd: float
    max_depth: int = 2
    spp: int = 1024
    ref_fd_epsilon: float = 1e-3
    rotate_normals: bool = False               # the update rotates vertex normals
    primal_xfail: str = ""    # why upstream's primal bounds fail here for Mitsuba's diffuse too

    def load(self, material: Callable[..., dict]):
        """The scene with ``material(**properties)`` as its diffuse BSDF, its
        parameters kept to the key, and the key's initial value."""
        d = self.scene(material)
        d["sensor"] = {
            "type": "perspective",
            "to_world": T().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "rfilter": {"type": "box"}, "width": RES,
                     "height": RES, "sample_border": True, "pixel_format": "rgb",
                     "component_format": "float32"}}
        scene = mi.load_dict(d, optimize=False, parallel=False)
        params = mi.traverse(scene)
        params.keep([self.key])
        initial = type(params[self.key])(params[self.key])
        return scene, params, initial

    def update(self, params, initial, theta):
        if self.rotate_normals:
            normals = dr.unravel(mi.Normal3f, initial)
            params[self.key] = dr.ravel(
                mi.Transform4f().rotate(angle=theta, axis=[0.0, 1.0, 0.0]) @ normals)
        else:
            params[self.key] = initial + theta
        params.update()
        dr.eval()


def grey_sphere(material) -> dict:
    return {"type": "sphere", "to_world": T().scale(0.25), "bsdf": material()}


def side_light(radiance: float = 3.0) -> dict:
    return {"type": "rectangle",
            "to_world": T().translate([1.25, 0.0, 1.0]) @ T().rotate([0, 1, 0], -90),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [radiance] * 3}}}


CONFIGS = [
    # BSDF albedo of a directly visible grey plane lit by a constant emitter
    Config("diffuse_albedo", lambda m: {
        "type": "scene", "plane": {"type": "rectangle", "bsdf": m()},
        "sphere": grey_sphere(m), "light": {"type": "constant"}},
        key="plane.bsdf.reflectance.value",
        error_mean_threshold=0.015, error_max_threshold=0.25, error_mean_threshold_bwd=0.0005),
    # BSDF albedo of an off-camera plane bleeding onto a directly visible grey plane
    Config("diffuse_albedo_g_i", lambda m: {
        "type": "scene", "plane": {"type": "rectangle", "bsdf": m()}, "sphere": grey_sphere(m),
        "green": {"type": "rectangle",
                  "bsdf": m(reflectance={"type": "rgb", "value": [0.1, 1.0, 0.1]}),
                  "to_world": T().translate([1.25, 0.0, 1.0]) @ T().rotate([0, 1, 0], -90)},
        "light": {"type": "constant", "radiance": 3.0}},
        key="green.bsdf.reflectance.value", max_depth=3,
        error_mean_threshold=0.04, error_max_threshold=0.4, error_mean_threshold_bwd=0.0005),
    # Rotating the plane's shading normals (no discontinuities)
    Config("rotate_shading_normals_plane", lambda m: {
        "type": "scene", "plane": rectangle_mesh(m()),
        "light": side_light()},
        key="plane.vertex_normals", rotate_normals=True,
        # Changed (reference only): upstream's step 1e-3 turns the frame so
        # little that the few paths it moves across the geometric horizon
        # make rare O(1)/1e-3 jumps, single-pixel spikes in the reference;
        # at 1e-2 they are ten times smaller and ten times as many.
        ref_fd_epsilon=1e-2,
        primal_xfail="upstream's max-error bound (0.3) is exceeded by Mitsuba's diffuse as "
                     "well (the same samples give the same image), also against "
                     "mitsuba-data's own reference",
        error_mean_threshold=0.02, error_max_threshold=0.3, error_mean_threshold_bwd=0.00002),
]

def cases(integrators: list[str], primal: bool = False) -> list:
    """(integrator, config) pairs; for the primal test, each config's
    ``primal_xfail`` as a strict xfail."""
    return [pytest.param(i, c, id=f"{i}-{c.name}", marks=[pytest.mark.xfail(
                strict=True, raises=AssertionError, reason=c.primal_xfail)]
            if primal and c.primal_xfail else [])
            for i in integrators for c in CONFIGS]


def lambert(**properties):
    return {"type": "lambert", **properties}


def diffuse(**properties):
    return {"type": "diffuse", **properties}


# ----------------------------------------------------------------------------
#  Upstream's error checks
# ----------------------------------------------------------------------------

def reference(config: Config, kind: str) -> mi.TensorXf:
    image = np.array(mi.Bitmap(str(DATA / f"{config.name}_{kind}.exr")), dtype=np.float32)
    return mi.TensorXf(image)


def image_error(actual, ref, config: Config, epsilon: float) -> tuple[float, float]:
    """Upstream's relative error: |actual - ref| / max(|ref|, epsilon), mean and max."""
    error = dr.abs(actual - ref) / dr.maximum(dr.abs(ref), epsilon)
    return dr.mean(error, axis=None).item(), dr.max(error, axis=None).item()


def assert_image(actual, ref, config: Config, epsilon: float) -> None:
    mean, worst = image_error(actual, ref, config, epsilon)
    assert mean <= config.error_mean_threshold and worst <= config.error_max_threshold, \
        (f"{config.name}: error mean {mean:.5f} (threshold {config.error_mean_threshold}), "
         f"max {worst:.4f} (threshold {config.error_max_threshold})")


def assert_gradient(grad, grad_ref, threshold: float, epsilon: float = 1e-3) -> None:
    error = (dr.abs(grad - grad_ref) / dr.maximum(dr.abs(grad_ref), epsilon)).item()
    assert error <= threshold, f"grad {grad}, reference {grad_ref}: error {error} > {threshold}"


def integrator(name: str, config: Config):
    it = mi.load_dict({"type": name, "max_depth": config.max_depth}, parallel=False)
    if "projective" in name:
        it.proj_seed_spp = 4192
    return it


# ----------------------------------------------------------------------------
#  The tests
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("integrator_name, config", cases(["prb", "path"], primal=True))
def test01_rendering_primal(variants_all_ad_rgb, integrator_name, config):
    scene, _, _ = config.load(lambert)
    image = integrator(integrator_name, config).render(scene, seed=0, spp=config.spp)
    assert_image(image, reference(config, "primal"), config, epsilon=2e-2)


@pytest.mark.parametrize("integrator_name, config", cases(["prb"]))
def test02_rendering_forward(variants_all_ad_rgb, integrator_name, config):
    scene, params, initial = config.load(lambert)
    theta = mi.Float(0.0)
    dr.enable_grad(theta)
    config.update(params, initial, theta)
    dr.forward(theta, dr.ADFlag.ClearEdges)

    image_fwd = integrator(integrator_name, config).render_forward(
        scene, seed=0, spp=config.spp, params=theta)
    assert_image(dr.detach(image_fwd), reference(config, "fwd"), config, epsilon=2e-1)


@pytest.mark.parametrize("integrator_name, config", cases(["prb", "path"]))
def test03_rendering_backward(variants_all_ad_rgb, integrator_name, config):
    scene, params, initial = config.load(lambert)
    image_fwd_ref = reference(config, "fwd")
    grad_in = 0.001
    image_adj = dr.full(mi.TensorXf, grad_in, image_fwd_ref.shape)

    theta = mi.Float(0.0)
    dr.enable_grad(theta)
    config.update(params, initial, theta)
    # upstream: 128 spp ("higher spp will run into single-precision accumulation issues")
    integrator(integrator_name, config).render_backward(
        scene, grad_in=image_adj, seed=0, spp=128, params=theta)

    grad = dr.grad(theta) / dr.width(image_fwd_ref)
    grad_ref = dr.mean(image_fwd_ref, axis=None) * grad_in
    assert_gradient(grad, grad_ref, config.error_mean_threshold_bwd)


def test04_render_custom_op(variants_all_ad_rgb):
    config = CONFIGS[0]                                  # diffuse_albedo
    scene, params, initial = config.load(lambert)
    prb = integrator("prb", config)
    image_primal_ref = reference(config, "primal")
    image_fwd_ref = reference(config, "fwd")

    theta = mi.Float(0.0)
    dr.enable_grad(theta)
    config.update(params, initial, theta)

    # Higher spp will run into single-precision accumulation issues
    image_primal = mi.render(scene, params, integrator=prb, seed=0, spp=256)
    assert_image(dr.detach(image_primal), image_primal_ref, config, epsilon=2e-2)

    # Backward comparison
    dr.backward(dr.mean(image_primal, axis=None))
    assert_gradient(dr.grad(theta)[0], dr.mean(image_fwd_ref, axis=None),
                    config.error_mean_threshold)

    # Forward comparison
    theta = mi.Float(0.0)
    dr.enable_grad(theta)
    config.update(params, initial, theta)
    image_primal = mi.render(scene, params, integrator=prb, seed=0, spp=config.spp)
    dr.forward(theta)
    assert_image(dr.grad(image_primal), image_fwd_ref, config, epsilon=2e-1)


# ----------------------------------------------------------------------------
#  The references: Mitsuba's diffuse, path tracer, finite differences
# ----------------------------------------------------------------------------

def write_references(spp: int, pass_spp: int, names: list[str]) -> None:
    """Upstream's generator, with ``diffuse``: the primal image and central
    finite differences of the key (step ``ref_fd_epsilon``), by ``path`` at
    ``spp`` samples per pixel, rendered in passes of ``pass_spp`` (seeds 0,
    1, ...; the two sides of a difference share each pass's seed) averaged
    in float64. One pass of 12,000 spp would sum each pixel in float32,
    whose rounding swamps a difference of 1e-3 (run with ``--pass-spp
    12000`` to see it in the printed means)."""
    DATA.mkdir(parents=True, exist_ok=True)
    passes = max(1, round(spp / pass_spp))
    for config in (c for c in CONFIGS if not names or c.name in names):
        scene, params, initial = config.load(diffuse)
        path = mi.load_dict({"type": "path", "max_depth": config.max_depth})

        def render(theta: float, seed: int) -> np.ndarray:
            config.update(params, initial, mi.Float(theta))
            return np.array(path.render(scene, seed=seed, spp=pass_spp), dtype=np.float64)

        h = config.ref_fd_epsilon
        primal = sum(render(0.0, seed) for seed in range(passes)) / passes
        fwd = sum(render(h / 2, seed) - render(-h / 2, seed) for seed in range(passes)) \
            / (passes * h)
        for kind, image in (("primal", primal), ("fwd", fwd)):
            # half floats: 1e-3 relative, far below every threshold here
            mi.Bitmap(image.astype(np.float16)).write(str(DATA / f"{config.name}_{kind}.exr"))
        print(f"{config.name}: {passes} x {pass_spp} spp; mean primal {primal.mean():.4f}, "
              f"mean derivative {fwd.mean():.4f}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=write_references.__doc__)
    parser.add_argument("--spp", type=int, default=REF_SPP)
    parser.add_argument("--pass-spp", type=int, default=64)
    parser.add_argument("--config", action="append", default=[],
                        help="only this configuration (repeatable; default: all)")
    args = parser.parse_args()
    write_references(args.spp, args.pass_spp, args.config)
