# %% [markdown]
# # The course models, in scan-line and HDR modes
#
# Every model of the lecture *BRDF Models* rendered on the same sphere, under one
# point light: the scan-line mode (the lecture's formulas, each lobe clamped to
# [0, 1], rendered by the `scanline` integrator) and the HDR mode (normalised,
# unclamped BSDFs, path traced with direct light, shown with the ACES tone curve).
# Then the lecture's parameter sweeps.
#
# Set `MI_BRDFS_QUICK=1` for a small, fast run (CI does).

# %%
import mi_brdfs  # noqa: F401  (first: sets up LLVM for drjit, registers the plugins)
import os

import matplotlib.pyplot as plt

from mi_brdfs.tools.analysis import render_sphere
from mi_brdfs.render.tonemap import to_srgb8

QUICK = os.environ.get("MI_BRDFS_QUICK") == "1"
RES, SPP = (40, 4) if QUICK else (160, 64)


def show(row, title=""):
    """A row of (label, bsdf dict) rendered side by side."""
    fig, axes = plt.subplots(1, len(row), figsize=(2.2 * len(row), 2.5))
    for ax, (label, bsdf) in zip(axes, row):
        mode = bsdf.get("mode", "hdr")
        image = render_sphere(bsdf, RES, SPP, env=0.0)
        ax.imshow(to_srgb8(image, "clamp" if mode == "scanline" else "aces", 0 if mode == "scanline" else 1))
        ax.set_title(label, fontsize=8)
        ax.axis("off")
    fig.suptitle(title)
    plt.show()


# %% [markdown]
# ## Every model, both modes

# %%
MODELS = {
    "lambert": {"type": "lambert", "reflectance": [0.8, 0.3, 0.2]},
    "oren_nayar": {"type": "oren_nayar", "reflectance": [0.8, 0.6, 0.4], "sigma": 0.6},
    "toon": {"type": "toon", "diffuse_reflectance": [0.3, 0.7, 0.9]},
    "phong": {"type": "phong", "diffuse_reflectance": [0.2, 0.5, 0.2], "specular_reflectance": 0.5,
              "exponent": 60},
    "blinn": {"type": "blinn", "diffuse_reflectance": [0.5, 0.2, 0.5], "specular_reflectance": 0.5,
              "exponent": 60},
    "ward": {"type": "ward", "diffuse_reflectance": [0.3, 0.25, 0.1], "specular_reflectance": 0.6,
             "alpha_u": 0.08, "alpha_v": 0.3},
    "cook_torrance": {"type": "cook_torrance", "diffuse_reflectance": [0.2, 0.3, 0.8], "k": 0.4,
                      "f0": 0.3, "alpha": 0.25, "distribution": "ggx"},
}


def rgb(config):
    """Lists of three numbers become Mitsuba rgb textures."""
    return {k: ({"type": "rgb", "value": v} if isinstance(v, list) else v) for k, v in config.items()}


for mode in ("scanline", "hdr"):
    show([(name, rgb({**config, "mode": mode})) for name, config in MODELS.items()], f"mode = {mode}")

# %% [markdown]
# ## Phong and Blinn: the exponent γ, and the two at equal γ
#
# The lecture: "the Blinn has usually a larger decay area than the Phong with
# similar parameters".

# %%
for name in ("phong", "blinn"):
    show([(f"γ = {g}", {"type": name, "mode": "scanline", "diffuse_reflectance": 0.2,
                        "specular_reflectance": 0.8, "exponent": g}) for g in (5, 20, 80, 300)],
         f"{name}, scan-line")

# %% [markdown]
# ## Oren-Nayar: σ (σ = 0 is Lambert)

# %%
show([("lambert", {"type": "lambert", "mode": "scanline", "reflectance": 0.8})]
     + [(f"σ = {s}", {"type": "oren_nayar", "mode": "scanline", "reflectance": 0.8, "sigma": s})
        for s in (0.0, 0.3, 0.8, 1.5)], "Oren-Nayar, scan-line")

# %% [markdown]
# ## Ward: α_t vs α_b (the tangent is the sphere's s axis, along its parallels)

# %%
show([(f"α_t={a}, α_b={b}", {"type": "ward", "mode": "scanline", "diffuse_reflectance": 0.1,
                             "specular_reflectance": 0.8, "alpha_u": a, "alpha_v": b})
      for a, b in ((0.1, 0.1), (0.05, 0.3), (0.3, 0.05), (0.3, 0.3))], "Ward, scan-line")

# %% [markdown]
# ## Cook-Torrance: D and G, and the roughness ρ

# %%
show([(f"{d} / {g}", {"type": "cook_torrance", "mode": "hdr", "k": 0.2, "alpha": 0.3,
                      "distribution": d, "geometry": g})
      for d in ("blinn", "beckmann", "ggx") for g in ("cook_torrance", "smith")],
     "Cook-Torrance D / G, hdr")
show([(f"ρ = {a}", {"type": "cook_torrance", "mode": "scanline", "k": 0.3, "alpha": a,
                    "distribution": "beckmann"}) for a in (0.1, 0.33, 0.67, 1.0)],
     "Cook-Torrance roughness, scan-line")

# %% [markdown]
# ## Toon: thresholds and smooth bands

# %%
show([(f"t_D = {t}, smooth {w}", {"type": "toon", "mode": "scanline", "diffuse_threshold": t,
                                  "smoothness": w, "specular_threshold": 0.92})
      for t, w in ((0.2, 0.0), (0.5, 0.0), (0.8, 0.0), (0.5, 0.2))], "Toon, scan-line")
