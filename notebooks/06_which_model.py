# %% [markdown]
# # Which model for which material
#
# `mi-brdfs fit` fits every course model to a material and measures each fit
# by what a user sees: the FLIP of its renders against the material's in
# three standard views (an environment map, a grazing key light, a frontal
# light), its BRDF error beside it, and its render cost relative to the
# material itself, a 90 % interval. Here are the Pareto fronts of the trade
# sweep (`mi_brdfs.tools.fit.trade`: gold, copper, aluminium and chromium,
# three plastics, two `principled` settings, `diffuse` and a brushed,
# anisotropic aluminium) — from the committed results in
# `docs/benchmarks/trade/` when they exist (its `trade.md` says when that run
# covered only some of the materials), else from a small sweep run here (set
# `MI_BRDFS_RERUN_TRADE=1` to always run one).

# %%
import mi_brdfs  # noqa: F401  (first: it sets up LLVM for drjit)
import json
import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

from mi_brdfs.tools.fit import rank, trade

QUICK = os.environ.get("MI_BRDFS_QUICK") == "1"
committed = Path("..") / "docs" / "benchmarks" / "trade" / "fits.json"
if os.environ.get("MI_BRDFS_RERUN_TRADE") == "1" or not committed.exists():
    # A small sweep: two materials and three models (QUICK), or every target
    # and model with the quick settings (about an hour on 2 cores).
    targets = [trade.TARGETS[1], trade.TARGETS[8]] if QUICK else trade.TARGETS
    models = ["lambert", "ward", "cook_torrance/beckmann/smith"] if QUICK else None
    out = os.path.join(tempfile.mkdtemp(), "trade")
    records = trade.fit_materials(out, quick=True, jobs=2, models=models, targets=targets)
    labels = dict((spec, label) for label, spec in targets)
else:
    records = json.loads(committed.read_text())
    labels = dict((spec, label) for label, spec in trade.TARGETS)
records = [r for r in records if "error" not in r]
print(len(records), "fits")

# %% [markdown]
# ## Image error against cost, per material
# Each point is one model's fit, its cost with its 90 % interval. The red
# line joins the Pareto front: the models no other model beats in image
# error at a lower cost — costs compare in classes a factor 1.05 wide, the
# fit's one comparison rule. The numbers follow the front from the cheapest.

# %%
specs = list(dict.fromkeys(r["target"] for r in records))
cols = min(3, len(specs))
rows = (len(specs) + cols - 1) // cols
fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.4 * rows), squeeze=False)
for ax, spec in zip(axes.ravel(), specs):
    mine = [r for r in records if r["target"] == spec]
    front = sorted(rank.front(mine), key=lambda r: r["cost_ratio"])
    for r in mine:
        on = r in front
        c, q = r["cost_ratio"], max(rank.quality(r), 1e-4)
        ax.errorbar([c], [q], xerr=[[c - r["cost_low"]], [r["cost_high"] - c]], fmt="o",
                    ms=4 if on else 2.5, color="C3" if on else "0.6", elinewidth=0.8)
    ax.plot([r["cost_ratio"] for r in front], [max(rank.quality(r), 1e-4) for r in front],
            "-", color="C3", lw=1)
    for i, r in enumerate(front, 1):
        ax.annotate(str(i), (r["cost_ratio"], max(rank.quality(r), 1e-4)), fontsize=7,
                    xytext=(3, 3), textcoords="offset points", color="C3")
    ax.set_yscale("log")
    ax.set_title(labels.get(spec, spec), fontsize=9)
    ax.set_xlabel("render cost / material's", fontsize=8)
    ax.set_ylabel("FLIP", fontsize=8)
    ax.text(0.98, 0.97, "\n".join(f"{i} {r['model']}" for i, r in enumerate(front, 1)),
            transform=ax.transAxes, fontsize=5.5, va="top", ha="right", family="monospace")
for ax in axes.ravel()[len(specs):]:
    ax.axis("off")
fig.tight_layout()
plt.show()

# %% [markdown]
# ## The table and the answer per material
# One row per model: its median cost over the materials (with the medians of
# its interval's ends) and of its traced operations, and on each material
# its FLIP · BRDF error (the first-ranked in bold); then the verdict per
# material.

# %%
print(trade.table(records, labels))

# %%
# What the sweep must show whatever the numbers: every fit has a FLIP and a
# cost inside its interval; the first-ranked fit's FLIP is within 0.01 of the
# best; on a conductor a microfacet model beats Lambert in the image.
assert all(rank.quality(r) >= 0 and r["cost_low"] <= r["cost_ratio"] <= r["cost_high"]
           for r in records)
for spec in specs:
    mine = [r for r in records if r["target"] == spec]
    assert rank.quality(rank.ranked(mine)[0]) <= min(map(rank.quality, mine)) + 0.01
    if spec.startswith("roughconductor"):
        flip = {r["model"]: r["image_flip"] for r in mine}
        assert flip["cook_torrance/beckmann/smith"] < flip["lambert"], flip
