# %% [markdown]
# # Fitting parameters with gradients
#
# The plugins' parameters are differentiable in `llvm_ad_rgb`. Here gradient
# descent (`mi.ad.Adam`) recovers a Phong sphere's exponent and colours from a
# reference image, then fits Cook-Torrance and Blinn to a `roughconductor`
# reference: the first can match it, the cheaper second only approximately,
# and finally recovers textures (an 8 × 8 roughness map, a colour map started
# at black) from renders.
#
# Each step renders, computes the loss and backpropagates through one frozen
# function (`mi_brdfs.render.frozen.GradientStep`, Dr.Jit's `dr.freeze`): the
# first steps trace the plugins' Python code, the others replay the recorded
# kernels with the new parameter values and seed.

# %%
import mi_brdfs  # noqa: F401  (first: it sets up LLVM for drjit)
import os
import time

import drjit as dr
import matplotlib.pyplot as plt
import mitsuba as mi
import numpy as np

from mi_brdfs.render.frozen import GradientStep
from mi_brdfs.render.tonemap import to_srgb8
from mi_brdfs.tools.analysis import bitmap, fit_texture, sphere_scene

QUICK = os.environ.get("MI_BRDFS_QUICK") == "1"
RES, SPP = (48, 4) if QUICK else (96, 8)
SCANLINE = {"type": "scanline", "clamp": False}   # direct light, deterministic for point lights


def fit(scene, reference, keys, lr, steps, clamp={}, log_keys=(), freeze=True):
    """Adam on the given scene parameters (those in log_keys through their
    logarithm: an exponent moves on a multiplicative scale); returns the final
    values and the loss history."""
    params = mi.traverse(scene)
    opt = mi.ad.Adam(lr=lr)
    for k in keys:
        opt[k] = dr.log(mi.Float(params[k])) if k in log_keys else params[k]
    step = GradientStep(keys, SPP, freeze=freeze)    # render, MSE, backward
    losses = []
    for it in range(steps):
        for k in keys:
            params[k] = dr.exp(opt[k]) if k in log_keys else opt[k]
        params.update()
        loss = step(scene, reference, seed=it)
        opt.step()
        for k, (lo, hi) in clamp.items():
            opt[k] = dr.clip(opt[k], lo, hi)
        losses.append(float(loss.array[0]))
    for k in keys:
        params[k] = dr.exp(opt[k]) if k in log_keys else opt[k]
    params.update()
    return params, losses


# %% [markdown]
# ## 1. Recover Phong's exponent and colours

# %%
def phong(exponent, m_d, m_s):
    return {"type": "phong", "exponent": exponent,
            "diffuse_reflectance": {"type": "rgb", "value": m_d},
            "specular_reflectance": {"type": "rgb", "value": m_s}}


TRUTH = dict(exponent=40.0, m_d=[0.6, 0.25, 0.15], m_s=[0.3, 0.3, 0.3])
reference = mi.render(mi.load_dict(sphere_scene(phong(**TRUTH), RES, SCANLINE)), spp=SPP)
scene = mi.load_dict(sphere_scene(phong(10.0, [0.5, 0.5, 0.5], [0.5, 0.5, 0.5]), RES, SCANLINE))
keys = ["sphere.bsdf.exponent.value", "sphere.bsdf.diffuse_reflectance.value",
        "sphere.bsdf.specular_reflectance.value"]
params, losses = fit(scene, reference, keys, lr=0.05, steps=120 if QUICK else 200,
                     clamp={keys[1]: (0, 1), keys[2]: (0, 1)}, log_keys=(keys[0],))
exponent = float(params[keys[0]][0])
m_d = np.array(params[keys[1]]).ravel()
m_s = np.array(params[keys[2]]).ravel()
print(f"exponent {exponent:.2f} (truth {TRUTH['exponent']}), m_D {m_d.round(3)} "
      f"(truth {TRUTH['m_d']}), m_S {m_s.round(3)} (truth {TRUTH['m_s']})")
plt.semilogy(losses)
plt.xlabel("iteration")
plt.ylabel("MSE")
plt.show()

# %%
# The demonstration must keep working: stated tolerances.
assert abs(exponent - TRUTH["exponent"]) < 0.1 * TRUTH["exponent"], exponent
assert np.allclose(m_d, TRUTH["m_d"], atol=0.03), m_d
assert np.allclose(m_s, TRUTH["m_s"], atol=0.03), m_s

# %% [markdown]
# ### What freezing changes
#
# The same fit traced at every step (`freeze=False`) and frozen: with the same
# seeds it is the same descent; only the time per step differs (tracing is
# most of a step on a scene this small).

# %%
def time_per_step(freeze, steps=40):
    start_scene = mi.load_dict(sphere_scene(phong(10.0, [0.5] * 3, [0.5] * 3), RES, SCANLINE))
    start = time.perf_counter()
    _, history = fit(start_scene, reference, keys, lr=0.05, steps=steps,
                     clamp={keys[1]: (0, 1), keys[2]: (0, 1)}, log_keys=(keys[0],), freeze=freeze)
    return (time.perf_counter() - start) / steps, history


traced_s, traced_losses = time_per_step(False)
frozen_s, frozen_losses = time_per_step(True)
print(f"per step: traced {1e3 * traced_s:.2f} ms, frozen {1e3 * frozen_s:.2f} ms "
      f"({traced_s / frozen_s:.1f}x)")
assert np.allclose(frozen_losses, traced_losses, rtol=1e-4)      # the same descent

# %% [markdown]
# ## 2. Cook-Torrance and Blinn against a `roughconductor` reference

# %%
conductor = {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3}
reference = mi.render(mi.load_dict(sphere_scene(conductor, RES, SCANLINE)), spp=SPP)

ct = mi.load_dict(sphere_scene({"type": "cook_torrance", "distribution": "ggx", "geometry": "smith",
                                "k": 0.0, "f0": 1.0, "alpha": 0.6}, RES, SCANLINE))
ct_params, ct_losses = fit(ct, reference, ["sphere.bsdf.alpha.value"], lr=0.03,
                           steps=80 if QUICK else 150, clamp={"sphere.bsdf.alpha.value": (0.01, 1)})
alpha = float(ct_params["sphere.bsdf.alpha.value"][0])

blinn = mi.load_dict(sphere_scene({"type": "blinn", "diffuse_reflectance": 0.0,
                                   "specular_reflectance": 0.5, "exponent": 10.0}, RES, SCANLINE))
b_keys = ["sphere.bsdf.exponent.value", "sphere.bsdf.specular_reflectance.value"]
b_params, b_losses = fit(blinn, reference, b_keys, lr=0.05, steps=80 if QUICK else 150,
                         clamp={b_keys[1]: (0, 2)}, log_keys=(b_keys[0],))
print(f"cook_torrance alpha {alpha:.3f} (roughconductor: 0.3), final MSE {ct_losses[-1]:.3g}")
print(f"blinn exponent {float(b_params[b_keys[0]][0]):.1f}, m_S "
      f"{float(b_params[b_keys[1]][0]):.3f}, final MSE {b_losses[-1]:.3g} — "
      "Blinn has no Fresnel or masking term: its best fit keeps a residual.")

fig, axes = plt.subplots(1, 3, figsize=(9, 3))
images = [reference, mi.render(ct, spp=SPP), mi.render(blinn, spp=SPP)]
for ax, image, title in zip(axes, images, ("roughconductor", "cook_torrance fit", "blinn fit")):
    ax.imshow(to_srgb8(np.array(image), "aces"))
    ax.set_title(title)
    ax.axis("off")
plt.show()

# %%
assert abs(alpha - 0.3) < 0.02, alpha
assert ct_losses[-1] < b_losses[-1]      # the same model family fits better than the cheaper one

# %% [markdown]
# ## 3. Textures: an 8 × 8 roughness map and a colour map from black
#
# Inverse rendering as Mitsuba users do it: a spatially varying parameter (a
# `bitmap` texture) is recovered from renders of a known scene. A square plane
# fills the view; a point light at five places gives five views of each
# texel's lobe (five scenes: moving one light through `params` between renders
# would leave the earlier renders' gradients computed with the last position,
# in Mitsuba 3.9). The loss is the relative squared error summed over the
# five renders, so a highlight does not outweigh the rest
# (`mi_brdfs.tools.analysis.fit_texture` holds the loop).
#
# The colour map starts at black: a colour of exactly 0 has no lobe at load
# time ("model only what a scene requires"), but a parameter being
# differentiated keeps its lobe traced, so the gradient flows from the bound.

# %%
TEX = 8
LIGHTS = [[0.6, 0.6, 0.8], [-0.7, 0.2, 0.6], [0.1, -0.8, 1.0], [0.7, -0.6, 0.5], [-0.5, 0.8, 0.9]]

rng = np.random.default_rng(5)
rough_truth = rng.uniform(0.1, 0.6, (TEX, TEX))
ct = {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith", "k": 0.0, "f0": 1.0,
      "specular_reflectance": 0.8}
rough_fit, rough_losses = fit_texture({**ct, "alpha": bitmap(rough_truth)},
                                      {**ct, "alpha": bitmap(np.full((TEX, TEX), 0.3))},
                                      "plane.bsdf.alpha.data", LIGHTS, steps=60, lr=0.02,
                                      lo=1e-3, hi=1.0)
rough_fit = rough_fit[..., 0]

colour_truth = rng.uniform(0.1, 0.9, (TEX, TEX, 3))
ph = {"type": "phong", "exponent": 30.0, "specular_reflectance": 0.3}
colour_fit, colour_losses = fit_texture({**ph, "diffuse_reflectance": bitmap(colour_truth)},
                                        {**ph, "diffuse_reflectance": bitmap(np.zeros((TEX, TEX, 3)))},
                                        "plane.bsdf.diffuse_reflectance.data", LIGHTS, steps=100,
                                        lr=0.05, lo=0.0, hi=1.0)
rough_err, colour_err = np.abs(rough_fit - rough_truth), np.abs(colour_fit - colour_truth)
print(f"roughness map: median error {np.median(rough_err):.4f}, largest {rough_err.max():.4f}")
print(f"colour map (from black): largest error {colour_err.max():.4f}")

fig, axes = plt.subplots(1, 5, figsize=(12, 2.8))
panels = [(rough_truth, "alpha: truth"), (rough_fit, "alpha: fitted"),
          (colour_truth, "m_D: truth"), (colour_fit, "m_D: fitted")]
for ax, (image, title) in zip(axes, panels):
    ax.imshow(np.clip(image, 0, 1), cmap="viridis" if image.ndim == 2 else None, vmin=0, vmax=1)
    ax.set_title(title, fontsize=9)
    ax.axis("off")
axes[4].semilogy(rough_losses, label="roughness")
axes[4].semilogy(colour_losses, label="colour")
axes[4].set_xlabel("iteration")
axes[4].legend(fontsize=7)
fig.tight_layout()
plt.show()

# %%
# The stated errors (tests/bsdfs/test_inverse.py asserts the same).
assert np.median(rough_err) < 0.01 and rough_err.max() < 0.04, rough_err
assert colour_err.max() < 0.02, colour_err
