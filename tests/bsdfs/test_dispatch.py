"""Every plugin as the target of Dr.Jit's virtual function calls, as
Mitsuba's integrators call BSDFs: an array of ``mi.BSDFPtr`` (one pointer per
lane, here every plugin and null pointers interleaved), called through
``dr.dispatch`` and through the array's own methods, with the calls recorded
(``JitFlag.VCallRecord``: one kernel for every target) or split per target,
and with instances freed before the call (holes in Mitsuba's registry of
instances). Each lane must get what a direct call of its plugin gives, and
derivatives must flow through the calls, backwards and forwards, to each
plugin's own parameters: equal to those of direct calls of fresh instances
(which the battery checks against finite differences).
"""
from __future__ import annotations

import gc

import numpy as np
import pytest

import drjit as dr
import mitsuba as mi

from support import (floats, jit_flags, plugin_configs, points, random_hemisphere, surface, vec)

LANES_PER_SLOT = 64
# Dr.Jit's flags for virtual calls: each call split per target, recorded once
# for all targets, recorded and optimised (constants of a single target
# propagated, unused outputs removed).
FLAG_SETS = {
    "split": {dr.JitFlag.VCallRecord: False, dr.JitFlag.VCallOptimize: False},
    "recorded": {dr.JitFlag.VCallRecord: True, dr.JitFlag.VCallOptimize: False},
    "optimised": {dr.JitFlag.VCallRecord: True, dr.JitFlag.VCallOptimize: True},
}


def pointers(bsdfs: list) -> tuple[mi.BSDFPtr, np.ndarray]:
    """A pointer per lane: lane i holds bsdfs[i % (k + 1)], the last slot a
    null pointer; and each lane's slot (k = len(bsdfs): null)."""
    k = len(bsdfs)
    slot = np.arange((k + 1) * LANES_PER_SLOT) % (k + 1)
    index = mi.UInt32(slot.tolist())
    ptr = dr.zeros(mi.BSDFPtr, len(slot))
    for i, bsdf in enumerate(bsdfs):
        ptr = dr.select(index == i, mi.BSDFPtr(bsdf), ptr)
    return ptr, slot


def inputs(n: int, seed: int = 11):
    rng = np.random.default_rng(seed)
    wi, wo = random_hemisphere(rng, n, 0.05), random_hemisphere(rng, n, 0.05)
    return wi, wo, rng.random((n, 3))


def per_lane(bsdfs, slot, call) -> np.ndarray:
    """``call(bsdf)`` (a NumPy array over all lanes) of each lane's own
    plugin, by direct calls; zero on null lanes."""
    out = None
    for i, bsdf in enumerate(bsdfs):
        value = call(bsdf)
        out = np.zeros_like(value) if out is None else out
        out[slot == i] = value[slot == i]
    return out


def as_numpy(x) -> np.ndarray:
    a = np.array(x, dtype=np.float64)
    return a.T if a.ndim == 2 else a


def check_dispatch(bsdfs, ptr, slot):
    """eval (dr.dispatch and the vcall method), pdf and sample through the
    pointers equal each lane's direct call; null lanes give zeros."""
    wi, wo, u = inputs(len(slot))
    ctx, si = mi.BSDFContext(), surface(wi)
    sample_args = (floats(u[:, 0]), points(u[:, 1], u[:, 2]))

    def evaluate(bsdf, si, wo):
        return bsdf.eval(mi.BSDFContext(), si, wo)

    dispatched = dr.dispatch(ptr, evaluate, si, vec(wo))
    bs, weight = ptr.sample(ctx, si, *sample_args)
    through = {"dispatch eval": dispatched, "eval": ptr.eval(ctx, si, vec(wo)),
               "pdf": ptr.pdf(ctx, si, vec(wo)), "sample wo": bs.wo, "sample pdf": bs.pdf,
               "sample weight": weight}
    dr.eval(*through.values())

    def direct(bsdf):
        b, w = bsdf.sample(ctx, si, *sample_args)
        value = bsdf.eval(ctx, si, vec(wo))
        return {"dispatch eval": value, "eval": value, "pdf": bsdf.pdf(ctx, si, vec(wo)),
                "sample wo": b.wo, "sample pdf": b.pdf, "sample weight": w}

    expected = {key: per_lane(bsdfs, slot, lambda b, key=key: as_numpy(direct(b)[key]))
                for key in through}
    for key, value in through.items():
        np.testing.assert_allclose(as_numpy(value), expected[key], rtol=1e-6, atol=1e-8,
                                   err_msg=key)
    null = slot == len(bsdfs)
    assert not expected["eval"][null].any() and not expected["sample weight"][null].any()
    for i in range(len(bsdfs)):
        assert expected["eval"][slot == i].max() > 0, f"slot {i} is black"
    return wi, wo


@pytest.mark.parametrize("recorded", [True, False], ids=["recorded", "split"])
def test_dispatch_reaches_every_plugin(recorded):
    configs = plugin_configs()
    with jit_flags({dr.JitFlag.VCallRecord: recorded}):
        bsdfs = [mi.load_dict(c) for c in configs.values()]
        ptr, slot = pointers(bsdfs)
        wi, wo = check_dispatch(bsdfs, ptr, slot)
    # One closed form, independent of the plugin: Lambert's ρ cos θ_o / π.
    lambert = list(configs).index("lambert")
    value = as_numpy(ptr.eval(mi.BSDFContext(), surface(wi), vec(wo)))[slot == lambert]
    rho = configs["lambert"]["reflectance"]
    np.testing.assert_allclose(value, rho / np.pi * wo[slot == lambert, 2:3] * np.ones(3),
                               rtol=1e-5)


@pytest.mark.parametrize("recorded", [True, False], ids=["recorded", "split"])
def test_dispatch_with_holes_in_the_registry(recorded):
    """Instances loaded between the ones called and freed before the call (so
    that the called ones are not numbered 1, 2, ... in Mitsuba's registry):
    the same results, twice (the second call reuses what the first traced)."""
    configs = list(plugin_configs().values())
    with jit_flags({dr.JitFlag.VCallRecord: recorded}):
        kept, freed = [], []
        for config in configs:
            freed.append(mi.load_dict(config))
            kept.append(mi.load_dict(config))
        del freed
        gc.collect()
        ptr, slot = pointers(kept)
        for _ in range(2):
            check_dispatch(kept, ptr, slot)


# ----------------------------------------------------------------------------
#  Derivatives through virtual calls
# ----------------------------------------------------------------------------

def differentiable(params) -> list[str]:
    return [k for k in params.keys() if not (params.flags(k) & mi.ParamFlags.NonDifferentiable)
            and dr.is_float_v(params[k])]


def attach(bsdf, indirect: bool) -> list:
    """Enable the derivatives of every parameter of ``bsdf``; returns the
    leaves. ``indirect``: its first parameter is written as a function of a
    leaf (min(leaf, 100)), so its derivative passes through that function too."""
    params = mi.traverse(bsdf)
    keys = differentiable(params)
    leaves = []
    for i, key in enumerate(keys):
        leaf = type(params[key])(params[key])
        dr.enable_grad(leaf)
        params[key] = dr.minimum(leaf, 100.0) if indirect and i == 0 else leaf
        leaves.append(leaf)
    params.update()
    return leaves


def loss_lanes(call, wi, wo) -> mi.Float:
    """Each lane's eval, summed over the channels (the value a loss weighs)."""
    value = call(mi.BSDFContext(), surface(wi), vec(wo))
    return value[0] + value[1] + value[2]


@pytest.mark.parametrize("flags, indirect", [
    pytest.param(FLAG_SETS[name], indirect, id=f"{name}-{'indirect' if indirect else 'direct'}")
    for name, indirect in (("split", False), ("recorded", False), ("optimised", False),
                           ("recorded", True))])
def test_derivatives_through_virtual_calls(flags, indirect):
    """Reverse mode: a loss weighting each lane differently (0, 1, 2, ...)
    through the pointers gives each plugin's parameters the gradient that the
    same loss over its own lanes gives by direct calls. Forward mode: a unit
    tangent on one plugin's parameters moves its lanes as in direct calls and
    no other lane. (A parameter written as a function of a leaf: with the
    recorded calls, the ones integrators make.)"""
    configs = list(plugin_configs().values())
    wi, wo, _ = inputs((len(configs) + 1) * LANES_PER_SLOT, seed=5)
    lane_weight = np.arange(len(wi), dtype=np.float64)
    with jit_flags(flags):
        bsdfs = [mi.load_dict(c) for c in configs]
        leaves = [attach(b, indirect) for b in bsdfs]
        ptr, slot = pointers(bsdfs)
        dr.backward(dr.sum(loss_lanes(ptr.eval, wi, wo) * floats(lane_weight)))
        for i, config in enumerate(configs):
            mine = slot == i
            fresh = mi.load_dict(config)
            own = attach(fresh, indirect)
            dr.backward(dr.sum(loss_lanes(fresh.eval, wi[mine], wo[mine])
                               * floats(lane_weight[mine])))
            keys = differentiable(mi.traverse(fresh))
            for key, ours, theirs in zip(keys, leaves[i], own):
                expected = as_numpy(dr.grad(theirs))
                assert np.abs(expected).max() > 0, f"{config['type']}.{key}: no gradient"
                np.testing.assert_allclose(as_numpy(dr.grad(ours)), expected, rtol=1e-4,
                                           atol=1e-6 * np.abs(expected).max(),
                                           err_msg=f"{config['type']}.{key}")

        bsdfs = [mi.load_dict(c) for c in configs]
        leaves = [attach(b, indirect) for b in bsdfs]
        ptr, slot = pointers(bsdfs)
        for i, config in enumerate(configs):
            mine = slot == i
            for j, group in enumerate(leaves):          # one unit along each of its parameters
                for x in group:
                    dr.set_grad(x, 1.0 if j == i else 0.0)
            lanes = loss_lanes(ptr.eval, wi, wo)
            dr.forward_to(lanes, flags=dr.ADFlag.ClearVertices)
            tangent = as_numpy(dr.grad(lanes))
            fresh = mi.load_dict(config)
            for x in attach(fresh, indirect):
                dr.set_grad(x, 1.0)
            own_lanes = loss_lanes(fresh.eval, wi[mine], wo[mine])
            dr.forward_to(own_lanes)
            expected = as_numpy(dr.grad(own_lanes))
            assert np.abs(expected).max() > 0, config["type"]
            np.testing.assert_allclose(tangent[mine], expected, rtol=1e-4,
                                       atol=1e-6 * np.abs(expected).max(), err_msg=config["type"])
            assert not tangent[~mine].any(), f"{config['type']} moves other lanes"
