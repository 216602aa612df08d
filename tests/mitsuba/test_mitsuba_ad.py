"""Mitsuba 3.9.1's ``src/render/tests/test_ad.py`` (tag v3.9.1, commit
478e193a), tests 01-05 (those with a BSDF), ported onto ``lambert``.

What changed, and why (each change is also commented at its test):

- ``diffuse`` is ``lambert`` (hdr mode); the key ``rect.bsdf.reflectance.value``,
  the scenes, sample counts, JIT flag sets, optimisers and tolerances are
  upstream's. Tests 07 and 08 (optimiser bookkeeping, no BSDF) are not ported.
- Test 04/05's ``mi.unpolarized_spectrum`` and the polarized skips stay
  (our plugins are depolarizers in polarized variants, as ``diffuse`` is).
- test03 runs its 100 SGD steps once per spp as upstream (spp = 8, 3x3
  pixels): the average of the last 10 must recover the reflectance to 1e-3.
"""
import drjit as dr
import mitsuba as mi
import pytest

from upstream import lambert

KEY = "rect.bsdf.reflectance.value"

JIT_FLAGS = [
    {dr.JitFlag.VCallRecord: False, dr.JitFlag.VCallOptimize: False, dr.JitFlag.LoopRecord: False},
    {dr.JitFlag.VCallRecord: True, dr.JitFlag.VCallOptimize: False, dr.JitFlag.LoopRecord: False},
    {dr.JitFlag.VCallRecord: True, dr.JitFlag.VCallOptimize: True, dr.JitFlag.LoopRecord: False},
]
FLAG_IDS = ["plain", "recorded", "optimized"]


def set_flags(jit_flags):
    for k, v in jit_flags.items():
        dr.set_flag(k, v)


def make_simple_scene(res=1, integrator="path"):
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": integrator},
        "mysensor": {
            "type": "perspective",
            "near_clip": 0.1,
            "far_clip": 1000.0,
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4], target=[0, 0, 0],
                                                       up=[0, 1, 0]),
            "myfilm": {"type": "hdrfilm", "rfilter": {"type": "box"},
                       "width": res, "height": res},
            "mysampler": {"type": "independent", "sample_count": 1},
        },
        "rect": {"type": "rectangle",
                 "bsdf": lambert(reflectance={"type": "rgb", "value": [0.6, 0.6, 0.6]})},
        "emitter": {"type": "point", "position": [0, 0, 5]},
    })


@pytest.mark.parametrize("jit_flags", JIT_FLAGS, ids=FLAG_IDS)
@pytest.mark.parametrize("spp", [1, 4, 44])
def test01_bsdf_reflectance_backward(variants_all_ad_rgb, jit_flags, spp):
    set_flags(jit_flags)

    # Test correctness of the gradients taking one step of gradient descent on linear function
    scene = make_simple_scene()
    params = mi.traverse(scene)
    dr.enable_grad(params[KEY])

    img_1 = scene.integrator().render(scene, seed=0, spp=spp)

    loss = dr.sum(img_1, axis=None)
    dr.backward(loss)
    grad = dr.grad(params[KEY])

    lr = 0.01
    params[KEY][0] += lr
    params.update()

    img_2 = scene.integrator().render(scene, seed=0, spp=spp)
    new_loss = dr.sum(img_2, axis=None)

    assert dr.allclose(loss, new_loss - lr * grad[0])


@pytest.mark.parametrize("jit_flags", JIT_FLAGS, ids=FLAG_IDS)
@pytest.mark.parametrize("spp", [1, 4])
def test02_bsdf_reflectance_forward(variants_all_ad_rgb, jit_flags, spp):
    set_flags(jit_flags)

    scene = make_simple_scene()
    params = mi.traverse(scene)

    # Add differential value to the BSDF reflectance
    X = mi.Float(0.1)
    dr.enable_grad(X)
    params[KEY] += X
    params.update()

    img_1 = scene.integrator().render(scene, seed=0, spp=spp)

    assert dr.all(dr.grad(img_1) == 0.0, axis=None)
    dr.forward(X)
    grad = dr.grad(img_1)

    lr = 0.1
    params[KEY] += lr
    params.update()

    img_2 = scene.integrator().render(scene, seed=0, spp=spp)

    assert dr.allclose(img_1, img_2 - lr * grad)


def test03_optimizer(variants_all_ad_rgb, spp=8, res=3):
    scene = make_simple_scene(res=res, integrator="direct")

    params = mi.traverse(scene)
    param_ref = mi.Color3f(params[KEY])
    params.keep(KEY)

    image_ref = scene.integrator().render(scene, seed=0, spp=spp)

    opt = mi.ad.SGD(lr=250.0, momentum=0.8, params=params)
    opt[KEY] = mi.Color3f(0.1)
    params.update(opt)

    avrg_params = mi.Color3f(0)
    N, W = 100, 10                # iterations, averaging window
    for it in range(N):
        image = scene.integrator().render(scene, seed=0, spp=spp)
        ob_val = dr.sum(dr.square(image - image_ref), axis=None) / len(image.array)
        dr.backward(ob_val)
        opt.step()
        params.update(opt)
        if it >= N - W:
            avrg_params += params[KEY]
    avrg_params /= W

    assert dr.allclose(avrg_params, param_ref, atol=1e-3)


def red_and_blue(indirect: bool = False):
    """Test 04's and 05's BSDFs: a red and a blue lambert, reflectance grad-enabled."""
    bsdf1 = mi.load_dict(lambert(reflectance={"type": "rgb", "value": [1.0, 0.0, 0.0]}))
    bsdf2 = mi.load_dict(lambert(reflectance={"type": "rgb", "value": [0.0, 0.0, 1.0]}))
    bsdf1_params = mi.traverse(bsdf1)
    p1 = bsdf1_params["reflectance.value"]
    dr.enable_grad(p1)
    bsdf1_params.update()

    bsdf2_params = mi.traverse(bsdf2)
    if indirect:
        p2 = mi.Color3f(1e-10, 1e-10, 1)
        dr.enable_grad(p2)
        bsdf2_params["reflectance.value"] = dr.minimum(p2, mi.Color3f(100))
    else:
        p2 = bsdf2_params["reflectance.value"]
        dr.enable_grad(p2)
    bsdf2_params.update()
    return bsdf1, bsdf2, p1, p2, bsdf1_params


def eval_at_45(bsdf_ptr, N):
    """eval of the pointers at wi = n, wo at 45 degrees; and its expected cos/pi."""
    si = dr.zeros(mi.SurfaceInteraction3f, N)
    si.t = 0.0
    si.p = [0, 0, 0]
    si.n = [0, 0, 1]
    si.wi = [0, 0, 1]
    si.sh_frame = mi.Frame3f(si.n)
    theta = 0.5 * (dr.pi / 2)
    wo = [dr.sin(theta), 0, dr.cos(theta)]
    return bsdf_ptr.eval(mi.BSDFContext(), si, wo), dr.cos(theta) * dr.inv_pi


@pytest.mark.parametrize("eval_grad", [False, True])
@pytest.mark.parametrize("N", [1, 10])
@pytest.mark.parametrize("jit_flags", JIT_FLAGS, ids=FLAG_IDS)
def test04_vcall_autodiff_bsdf_single_inst_and_masking(variants_all_ad_rgb, eval_grad, N,
                                                       jit_flags):
    if "polarized" in mi.variant():
        pytest.skip("Test must be adapted for polarized variants")
    set_flags(jit_flags)

    bsdf, _, p, _, bsdf_params = red_and_blue()
    mask = dr.arange(mi.UInt32, N) & 1 == 0
    bsdf_ptr = dr.select(mask, mi.BSDFPtr(bsdf), dr.zeros(mi.BSDFPtr))

    v_eval, v = eval_at_45(bsdf_ptr, N)
    v = mi.Float(v)
    v_ref = dr.select(mask, mi.Color3f(v, 0, 0), mi.Color3f(0))
    assert dr.allclose(mi.unpolarized_spectrum(v_eval), v_ref)

    loss = dr.sum(v_eval)

    # Backpropagate through vcall
    if eval_grad:
        loss_grad = dr.arange(mi.Float, N)
        dr.eval(loss_grad)
    else:
        loss_grad = mi.Float(1)

    dr.set_grad(loss, loss_grad)
    dr.enqueue(dr.ADMode.Backward, loss)
    dr.traverse(dr.ADMode.Backward, dr.ADFlag.ClearVertices)

    grad = dr.grad(bsdf_params["reflectance.value"])
    assert dr.allclose(grad, v * dr.sum(dr.select(mask, loss_grad, 0.0)))

    # Forward propagate gradients to loss
    dr.forward(bsdf_params["reflectance.value"], dr.ADFlag.ClearVertices)
    assert dr.allclose(dr.grad(loss), dr.select(mask, 3 * v, 0.0))


@pytest.mark.parametrize("mode", ["backward", "forward"])
@pytest.mark.parametrize("eval_grad", [False, True])
@pytest.mark.parametrize("N", [1, 10])
@pytest.mark.parametrize("jit_flags", JIT_FLAGS, ids=FLAG_IDS)
@pytest.mark.parametrize("indirect", [False, True])
def test05_vcall_autodiff_bsdf(variants_all_ad_rgb, mode, eval_grad, N, jit_flags, indirect):
    if mi.is_polarized:
        pytest.skip("Test must be adapted for polarized rendering")
    set_flags(jit_flags)

    bsdf1, bsdf2, p1, p2, _ = red_and_blue(indirect)
    mask = (dr.arange(mi.UInt32, N) & 1) == 0
    bsdf_ptr = dr.select(mask, mi.BSDFPtr(bsdf1), mi.BSDFPtr(bsdf2))

    v_eval, v = eval_at_45(bsdf_ptr, N)
    v_ref = dr.select(mask, mi.Color3f(v, 0, 0), mi.Color3f(0, 0, v))
    assert dr.allclose(mi.unpolarized_spectrum(v_eval), v_ref)

    # Make their gradients a bit different
    mult1 = mi.Float(0.5)
    mult2 = mi.Float(4.0)
    v_eval *= dr.select(mask, mult1, mult2)

    loss = dr.sum(v_eval)

    if mode == "backward":
        if eval_grad:
            loss_grad = dr.arange(mi.Float, N)
            dr.eval(loss_grad)
        else:
            loss_grad = mi.Float(1)

        dr.set_grad(loss, loss_grad)
        dr.enqueue(dr.ADMode.Backward, loss)
        dr.traverse(dr.ADMode.Backward, dr.ADFlag.ClearVertices)

        grad1 = dr.grad(p1)
        grad2 = dr.grad(p2)
        assert dr.allclose(grad1, v * mult1 * dr.sum(dr.select(mask, loss_grad, 0.0)))
        assert dr.allclose(grad2, v * mult2 * dr.sum(dr.select(~mask, loss_grad, 0.0)))

    if mode == "forward":
        # Forward propagate gradients to loss, one BSDF at a time
        dr.set_grad(p1, 1)
        dr.set_grad(p2, 0)
        dr.enqueue(dr.ADMode.Forward, p1)
        dr.enqueue(dr.ADMode.Forward, p2)
        dr.traverse(dr.ADMode.Forward, dr.ADFlag.ClearVertices)

        dr.set_grad(p1, 0)
        dr.set_grad(p2, 1)
        dr.enqueue(dr.ADMode.Forward, p1)
        dr.enqueue(dr.ADMode.Forward, p2)
        dr.traverse(dr.ADMode.Forward, dr.ADFlag.ClearVertices)

        assert dr.allclose(dr.grad(loss), 3 * v * dr.select(mask, mult1, mult2))
