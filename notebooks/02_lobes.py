# %% [markdown]
# # Looking at a BRDF: lobes and albedo
#
# For every model: the BSDF in the plane of incidence as polar plots (as the
# Disney BRDF Explorer draws them; the plotted value is what Mitsuba's `eval`
# returns, f·cos θ_o), a 3-D lobe, and the directional albedo against the
# incident angle (white colours; values above 1 reflect more light than arrives).

# %%
import mi_brdfs  # noqa: F401  (first: it sets up LLVM for drjit)
import os

import matplotlib.pyplot as plt
import mitsuba as mi
import numpy as np

from mi_brdfs.bsdfs import BY_NAME
from mi_brdfs.bsdfs import cases
from mi_brdfs.tools import analysis

QUICK = os.environ.get("MI_BRDFS_QUICK") == "1"
STRATA = (128, 512) if QUICK else (512, 2048)
ANGLES = (0, 30, 60, 75, 85) if QUICK else (0, 15, 30, 45, 60, 70, 75, 80, 85, 88)

# %% [markdown]
# ## Polar lobes, both modes

# %%
for name, config in cases.lobe_configs().items():
    fig, axes = plt.subplots(1, 2, subplot_kw={"projection": "polar"}, figsize=(7, 3))
    for ax, mode in zip(axes, ("hdr", "scanline")):
        analysis.polar_lobes(ax, mi.load_dict({**config, "mode": mode}), title=f"{name} ({mode})")
    axes[1].legend(fontsize=7, loc="lower right", bbox_to_anchor=(1.4, 0))
    plt.show()

# %% [markdown]
# ## A 3-D lobe (Ward, anisotropic, θ_i = 45°)

# %%
bsdf = mi.load_dict({"type": "ward", "alpha_u": 0.08, "alpha_v": 0.3, "diffuse_reflectance": 0.0})
theta, phi, value = analysis.hemisphere(bsdf, 45, n=24 if QUICK else 96)
r = value / value.max()
ax = plt.figure(figsize=(4, 4)).add_subplot(projection="3d")
ax.plot_surface(r * np.sin(theta) * np.cos(phi), r * np.sin(theta) * np.sin(phi), r * np.cos(theta),
                cmap="viridis", linewidth=0)
ax.set_title("ward, θ_i = 45° (radius: eval / max)")
plt.show()

# %% [markdown]
# ## Directional albedo against incident angle

# %%
fig, axes = plt.subplots(1, 2, figsize=(10, 3.5), sharey=True)
for ax, mode in zip(axes, ("hdr", "scanline")):
    for name, configs in ((name, cases.report_furnace(name)) for name in cases.ALL):
        label, config = configs[0]
        e = analysis.directional_albedo(mi.load_dict({**config, "mode": mode}), ANGLES, STRATA)
        ax.plot(ANGLES, e, "o-", ms=3, label=name)
    ax.axhline(1, color="k", lw=0.6)
    ax.set_yscale("log")
    ax.set_title(f"mode = {mode}")
    ax.set_xlabel("θ_i (degrees)")
axes[0].set_ylabel("albedo")
axes[1].legend(fontsize=7)
plt.show()

# %% [markdown]
# ## With energy compensation
#
# The hdr models lose the light that would scatter more than once (microfacet
# shadowing) or that their lobe sends below the horizon. With
# `energy_compensation=true` a Kulla-Conty multiple-scattering lobe (and for
# `oren_nayar` the EON model) returns it: a white configuration reflects 1 at
# every angle (solid), against the single-scattering model (dashed). One white
# configuration per compensable model, from its cases.

# %%
fig, ax = plt.subplots(figsize=(6.5, 3.5))
for i, (name, configs) in enumerate(((name, cases.report_furnace(name)) for name in cases.ALL)):
    if not BY_NAME[name].compensable:
        continue
    white = [(label, c) for label, c in configs
             if cases.promises_one(name, {**c, "energy_compensation": True})]
    label, config = white[-1]
    for compensated, style in ((False, "--"), (True, "-")):
        bsdf = mi.load_dict({**config, "energy_compensation": compensated})
        e = analysis.directional_albedo(bsdf, ANGLES, STRATA)
        ax.plot(ANGLES, e, style, color=f"C{i}", label=f"{name}: {label}" if compensated else None)
ax.axhline(1, color="k", lw=0.6)
ax.set_ylim(0, 1.1)
ax.set_xlabel("θ_i (degrees)")
ax.set_ylabel("albedo (hdr)")
ax.set_title("energy compensation: solid on, dashed off", fontsize=9)
ax.legend(fontsize=6, loc="lower left")
fig.tight_layout()
plt.show()

# %% [markdown]
# ## Interactive (when ipywidgets is installed)

# %%
try:
    import ipywidgets as widgets

    @widgets.interact(exponent=(1, 500), theta=(0, 89))
    def phong_lobe(exponent=50, theta=30):
        ax = plt.subplot(projection="polar")
        analysis.polar_lobes(ax, mi.load_dict({"type": "phong", "exponent": exponent,
                                               "diffuse_reflectance": 0.0}), (theta,))
        plt.show()
except ImportError:
    print("ipywidgets is not installed: the static plots above show the same lobes.")
