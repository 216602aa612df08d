# %% [markdown]
# # Validation: built-ins, white furnace, χ²
#
# The same checks as `mi-brdfs validate`, through its Python API
# (`mi_brdfs.validate`, `mi_brdfs.compare`): do the course models match
# Mitsuba's built-ins, which conserve energy, and does every sampler match its pdf?

# %%
import mi_brdfs  # noqa: F401  (first: it sets up LLVM for drjit)
import os
import tempfile

import matplotlib.pyplot as plt

from mi_brdfs.tools import compare, validate

QUICK = os.environ.get("MI_BRDFS_QUICK") == "1"
out = os.path.join(tempfile.mkdtemp(), "report")
results = validate.validate(out, quick=True, log=lambda *a: None)
print("report written to", os.path.join(out, "index.html"))

# %% [markdown]
# ## 1. Built-in equivalence
# Each pair rendered in independent passes; a per-pixel Welch t-test (Bonferroni
# over pixels) decides "identical up to noise".

# %%
for r in results["equivalence"]:
    t = r["test"]
    print(f"{r['title']}\n   expected: {r['expected']}\n   measured: "
          + ("identical up to noise" if t["identical"] else
             f"differs ({t['significant_pixels']} of {t['pixels']} pixels significant)")
          + f", mean relative difference {100 * t['mean_relative_difference']:.2f} %")

# %% [markdown]
# The difference images of the last pair (Schlick's approximation against the
# exact Fresnel term of `roughplastic`): the rim, at grazing angles, differs.

# %%
files = results["equivalence"][-1]["files"]
fig, axes = plt.subplots(1, 3, figsize=(10, 3.4))
for ax, kind in zip(axes, ("reference", "test", "difference")):
    ax.imshow(plt.imread(os.path.join(out, files[kind])))
    ax.set_title(kind)
    ax.axis("off")
plt.show()

# %% [markdown]
# ## The compare API on two renders of our own

# %%
from mi_brdfs.tools.analysis import render_sphere  # noqa: E402

a = render_sphere({"type": "cook_torrance", "distribution": "ggx", "alpha": 0.3}, 64, 16)
b = render_sphere({"type": "cook_torrance", "distribution": "beckmann", "alpha": 0.3}, 64, 16)
m = compare.metrics(a, b)
print({k: round(v, 5) for k, v in m.items() if isinstance(v, float)})

# %% [markdown]
# ## 2. White furnace

# %%
print(f"{'model':14} {'configuration':40} {'mode':9} {'max':>7} {'at':>5} {'flag'}")
for r in results["furnace"]:
    flag = ("exceeds 1" if r["exceeds_1"] else "loses energy" if r["loses_energy"] else "")
    print(f"{r['model']:14} {r['config']:40} {r['mode']:9} {r['max']:7.3f} {r['max_at']:5g} {flag}")

# %% [markdown]
# ## 3. Sampling: χ² p-values and the variance of the sample weights

# %%
for r in results["sampling"]:
    print(f"{r['model']:14} {r['config']:28} θ_i={r['theta']:>3}°  p = {r['p_value']:.3f}  "
          f"{'pass' if r['passed'] else 'FAIL'}  weight variance {r['weight_variance']:.3g}")
assert all(r["passed"] for r in results["sampling"])
