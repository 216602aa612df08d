# %% [markdown]
# # Speed against accuracy
#
# The numbers come from `mi-brdfs bench` (committed in `docs/benchmarks/`, from one
# run on one machine; re-run with `mi-brdfs bench -o docs/benchmarks`). Set
# `MI_BRDFS_RERUN_BENCH=1` to run a quick bench here instead.

# %%
import mi_brdfs  # noqa: F401  (first: it sets up LLVM for drjit)
import json
import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

from mi_brdfs.tools import bench

committed = Path("..") / "docs" / "benchmarks" / "results.json"
if os.environ.get("MI_BRDFS_RERUN_BENCH") == "1" or not committed.exists():
    results = bench.run(tempfile.mkdtemp(), quick=True, log=lambda *a: None)
else:
    results = json.loads(committed.read_text())
groups = results["groups"]
print(results["settings_name"], "run on", results["machine"])

# %% [markdown]
# ## Python plugins against Mitsuba's C++ built-ins
# Both become one Dr.Jit kernel: the execution times should match; a larger
# ratio comes from tracing the Python code (done again for every render).

# %%
for r in groups["builtin"]:
    print(f"{r['name']}: ratio {r['ratio']:.2f}; execution {1e3 * r['plugin_execution_s']:.2f} vs "
          f"{1e3 * r['builtin_execution_s']:.2f} ms, tracing {1e3 * r['plugin_tracing_s']:.2f} vs "
          f"{1e3 * r['builtin_tracing_s']:.2f} ms")

# %% [markdown]
# ## What each model costs, relative to Lambert

# %%
rows = groups["models"]
plt.figure(figsize=(6, 4))
plt.barh([r["name"] for r in rows], [r["relative_to_lambert"] for r in rows])
plt.axvline(1, color="k", lw=0.6)
plt.xlabel("render time / lambert's")
plt.tight_layout()
plt.show()

# %% [markdown]
# ## Importance sampling against cosine sampling (efficiency = 1 / (relMSE × time))

# %%
for r in groups["sampling"]:
    print(f"{r['name']:32} {r['strategy']:18} relMSE {r['relmse']:.4g}  "
          f"efficiency ×{r['efficiency_vs_first']:.3f} of the default")

# %% [markdown]
# ## Oren-Nayar: the table's speed and error; scan-line against path tracing

# %%
fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
tables = [r for r in groups["oren_nayar"] if r["table_resolution"]]
axes[0].loglog([r["table_resolution"] for r in tables],
               [max(r["relmse_vs_exact"], 1e-12) for r in tables], "o-")
axes[0].set_xlabel("table resolution")
axes[0].set_ylabel("relMSE vs exact")
for r in groups["integrators"]:
    axes[1].loglog(r["median_s"], r["relmse"], "o")
    axes[1].annotate(r["name"], (r["median_s"], r["relmse"]), fontsize=7)
axes[1].set_xlabel("seconds")
axes[1].set_ylabel("relMSE vs converged path tracing")
plt.tight_layout()
plt.show()
