"""The bench's figures: one function per group, named after it, given the
group's rows and returning {file name: matplotlib Figure}; :func:`save` writes
them. The ladder's needs its renders, not only its rows: its runner draws it
(:data:`LADDER`, the group's ``drawn``). Figures are made without pyplot (no
global backend change).
"""
from __future__ import annotations

import os

import numpy as np

from ..measures import pareto
from .report import header


def _figure(size):
    from matplotlib.figure import Figure    # optional: the reports extra
    return Figure(figsize=size)


def bars(rows: list[dict], key: str, title: str, ref: float = 1.0):
    """A horizontal bar per row (its ``name``), a line at ``ref``."""
    fig = _figure((6, 0.35 * len(rows) + 1.2))
    ax = fig.subplots()
    ax.barh([r["name"] for r in rows], [r[key] for r in rows])
    ax.axvline(ref, color="k", lw=0.6)
    ax.invert_yaxis()
    ax.tick_params(labelsize=7)
    ax.set_xlabel(header(key))
    ax.set_title(title, fontsize=9)
    return fig


def scatter(rows: list[dict], label, time_key: str, error_key: str, title: str):
    """Error against time, the Pareto front marked."""
    points = [(r[time_key], max(r[error_key], 1e-12)) for r in rows]
    front = pareto(points)
    fig = _figure((5, 3.6))
    ax = fig.subplots()
    from matplotlib.ticker import MaxNLocator   # optional: the reports extra
    for (t, e), r, on in zip(points, rows, front):
        ax.semilogy(t, e, "o", color="C3" if on else "C0")
        ax.annotate(label(r), (t, e), xytext=(4, 4), textcoords="offset points", fontsize=7)
    xs, ys = zip(*sorted(p for p, on in zip(points, front) if on))
    ax.plot(xs, ys, "-", color="C3", lw=0.8, label="Pareto front")
    ax.margins(x=0.25, y=0.2)                 # room for the labels beside the points
    ax.xaxis.set_major_locator(MaxNLocator(4))  # a few ticks: a narrow range has long ones
    ax.tick_params(labelsize=7)
    ax.tick_params(axis="y", which="minor", labelsize=6)
    ax.set_xlabel(header(time_key))
    ax.set_ylabel(header(error_key))
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    return fig


def save(out_dir: str, figures: dict) -> list[str]:
    """Write the figures as PNG files; their names."""
    for name, fig in figures.items():
        fig.tight_layout()
        fig.savefig(os.path.join(out_dir, name), dpi=90, bbox_inches="tight")  # labels kept
    return list(figures)


# ----------------------------------------------------------------------------
#  One per group
# ----------------------------------------------------------------------------

def builtin(rows):
    return {"builtin.png": bars(rows, "ratio", "plugin time / built-in time (parity: 1)")}


def models(rows):
    return {"models.png": bars(rows, "relative_to_lambert", "render time / lambert's")}


def oren_nayar(rows):
    return {"oren_nayar.png": scatter(rows, lambda r: r["name"], "median_s", "relmse_vs_exact",
                                      "Oren-Nayar table vs exact")}


def sampling(rows):
    figures = {}
    for i, name in enumerate(dict.fromkeys(r["name"] for r in rows)):
        lobe = [r for r in rows if r["name"] == name]
        figures[f"sampling_{i}.png"] = scatter(lobe, lambda r: r["strategy"], "median_s",
                                               "relmse", f"{name}, {lobe[0]['spp']} spp")
    return figures


def integrators(rows):
    return {"integrators.png": scatter(rows, lambda r: r["name"], "median_s", "relmse",
                                       "vs converged path tracing")}


def convergence(rows):
    fig = _figure((4.5, 3.2))
    ax = fig.subplots()
    ax.loglog([r["spp"] for r in rows], [r["relmse"] for r in rows], "o-")
    ax.set_xlabel("spp")
    ax.set_ylabel("relMSE")
    ax.set_title(f"convergence, slope {rows[0]['slope']:.2f}")
    return {"convergence.png": fig}


def scaling(rows):
    fig = _figure((8, 3.2))
    for ax, axis in zip(fig.subplots(1, 2), ("resolution", "lights")):
        along = [r for r in rows if r["axis"] == axis]
        ax.plot([r["value"] for r in along], [r["median_s"] for r in along], "o-")
        ax.set_xlabel(axis)
        ax.set_ylabel("seconds")
    return {"scaling.png": fig}


def lobes(rows):
    return {"lobes.png": bars(rows, "ratio", "lobe switched off / model without it")}


def materials(rows):
    fig = _figure((8, 3.2))
    names = list(dict.fromkeys(r["name"] for r in rows))
    for ax, name in zip(fig.subplots(1, len(names), squeeze=False)[0], names):
        pair = [r for r in rows if r["name"] == name]
        n = [r["materials"] for r in pair]
        for side, style in (("plugin", "o-"), ("builtin", "s--"), ("floor", "^:")):
            ax.plot(n, [r[f"{side}_warm_s"] for r in pair], style, label=f"{side} warm")
            ax.plot(n, [r[f"{side}_tracing_s"] for r in pair], style, alpha=0.5,
                    label=f"{side} tracing")
            ax.plot(n, [r[f"{side}_frozen_s"] for r in pair], style, alpha=0.25,
                    label=f"{side} frozen replay")
        ax.set_xlabel("materials")
        ax.set_ylabel("seconds")
        ax.set_title(name, fontsize=8)
        ax.legend(fontsize=6)
    return {"materials.png": fig}


def frozen(rows):
    named = [{"name": f"{r['passes']} passes{' frozen' if r['frozen'] else ''}",
              "first_vs_1_pass": r["first_vs_1_pass"]} for r in rows]
    return {"frozen.png": bars(named, "first_vs_1_pass", "time / one pass's (same spp)")}


def _per_method(rows, what):
    named = [{"name": f"{r['name'].split(' vs ')[0]}: {r['method']}", "ratio": r["ratio"]}
             for r in rows]
    return bars(named, "ratio", f"plugin / built-in, {what} (parity: 1)")


def kernels(rows):
    return {"kernels.png": _per_method(rows, "kernel execution")}


def tracing(rows):
    return {"tracing.png": _per_method(rows, "tracing one call")}


LADDER = ("ladder.png",)          # drawn by the ladder group's runner (it needs the renders)


def ladder(images: dict, samples: int) -> dict:
    """The ladder's renders, ``images[(material, lighting, column)]`` (H, W, 3),
    the converged walk each case's first column: a row per material and
    lighting, each rung's mean of ``samples`` samples per pixel and the
    converged walk, then each rung's difference from the converged walk, all
    in one exposure per row (the converged walk's 99.5th percentile is
    white), red where the rung is brighter."""
    from ...render.tonemap import srgb_encode
    cases = list(dict.fromkeys(k[:2] for k in images))
    columns = list(dict.fromkeys(k[2] for k in images))
    truth, rungs = columns[0], columns[1:]
    n = 2 * len(rungs) + 1                            # renders, the converged walk, differences
    fig = _figure((1.5 * n + 0.6, 1.6 * len(cases)))
    axes = fig.subplots(len(cases), n + 1, squeeze=False,
                        gridspec_kw={"width_ratios": [1] * n + [0.08]})   # last: the colour bar
    for row, (material, lighting) in zip(axes, cases):
        ref = images[(material, lighting, truth)]
        lit = ref[ref > 0]
        white = float(np.percentile(lit, 99.5)) if lit.size else 1.0
        for ax, column in zip(row, rungs + [truth]):
            ax.imshow(srgb_encode(np.clip(images[(material, lighting, column)] / white, 0, 1)))
            ax.set_title(column if column == truth else f"{column}, {samples} spp", fontsize=7)
        for ax, column in zip(row[len(rungs) + 1:], rungs):
            diff = (images[(material, lighting, column)] - ref).mean(axis=-1) / white
            shade = ax.imshow(diff, cmap="RdBu_r", vmin=-0.25, vmax=0.25)
            ax.set_title(f"{column} − converged", fontsize=7)
        for ax in row[:n]:
            ax.set_xticks([])
            ax.set_yticks([])
        row[0].set_ylabel(f"{material}\n{lighting}", fontsize=7)
    for ax in axes[1:, n]:
        ax.axis("off")
    bar = fig.colorbar(shade, cax=axes[0, n])
    bar.set_label("difference / white", fontsize=7)
    bar.ax.tick_params(labelsize=6)
    return {LADDER[0]: fig}
