# %% [markdown]
# # Which model for which material
#
# `mi-brdfs fit` fits every course model to a material and measures each fit:
# its BRDF error (0 identical, 1 as far as black), its image error in a
# standard scene and its render cost relative to the material itself. Here
# are the Pareto fronts of the trade sweep (`mi_brdfs.tools.fit.trade`: gold,
# copper and aluminium, plastic, two `principled` settings and `diffuse`)
# — from the committed results in `docs/benchmarks/trade/` when they exist,
# else from a small sweep run here (set `MI_BRDFS_RERUN_TRADE=1` to always
# run one).

# %%
import mi_brdfs  # noqa: F401  (first: it sets up LLVM for drjit)
import json
import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

from mi_brdfs.tools.fit import report, trade

QUICK = os.environ.get("MI_BRDFS_QUICK") == "1"
committed = Path("..") / "docs" / "benchmarks" / "trade" / "fits.json"
if os.environ.get("MI_BRDFS_RERUN_TRADE") == "1" or not committed.exists():
    # A small sweep: two materials and three models (QUICK), or every target
    # and model with the quick settings (about half an hour on 2 cores).
    targets = [trade.TARGETS[1], trade.TARGETS[7]] if QUICK else trade.TARGETS
    models = ["lambert", "ward", "cook_torrance/beckmann/smith"] if QUICK else None
    out = os.path.join(tempfile.mkdtemp(), "trade")
    records = trade.run(out, quick=True, jobs=2, models=models, targets=targets)
    labels = dict((spec, label) for label, spec in targets)
else:
    records = json.loads(committed.read_text())
    labels = dict((spec, label) for label, spec in trade.TARGETS)
records = [r for r in records if "error" not in r]
print(len(records), "fits")

# %% [markdown]
# ## Error against cost, per material
# Each point is one model's best fit; the red line joins the Pareto front: the
# models that no other model beats in both error and cost.

# %%
specs = list(dict.fromkeys(r["target"] for r in records))
cols = min(3, len(specs))
rows = (len(specs) + cols - 1) // cols
fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.4 * rows), squeeze=False)
for ax, spec in zip(axes.ravel(), specs):
    mine = [r for r in records if r["target"] == spec]
    points = [(r["cost_ratio"], max(r["brdf_error"], 1e-6)) for r in mine]
    front = report.pareto(points)
    ax.scatter(*zip(*points), s=12, color="C0")
    line = sorted(p for p, on in zip(points, front) if on)
    ax.plot(*zip(*line), "o-", color="C3", ms=4)
    for r, p, on in zip(mine, points, front):
        if on:
            ax.annotate(r["model"], p, fontsize=6, xytext=(3, 2), textcoords="offset points")
    ax.set_yscale("log")
    ax.set_title(labels.get(spec, spec), fontsize=9)
    ax.set_xlabel("render cost / target's", fontsize=8)
    ax.set_ylabel("BRDF error", fontsize=8)
for ax in axes.ravel()[len(specs):]:
    ax.axis("off")
fig.tight_layout()
plt.show()

# %% [markdown]
# ## The table
# One row per model: its median cost over the materials and its BRDF error
# on each (the best per material in bold).

# %%
print(trade.table(records, labels))

# %%
# What the sweep must show whatever the numbers: every fit has an error in
# [0, ~1] and a positive cost, and on a conductor a microfacet model beats Lambert.
assert all(0 <= r["brdf_error"] < 1.5 and r["cost_ratio"] > 0 for r in records)
for spec in specs:
    if spec.startswith("roughconductor"):
        errors = {r["model"]: r["brdf_error"] for r in records if r["target"] == spec}
        assert errors["cook_torrance/beckmann/smith"] < errors["lambert"], errors
