"""The fit report's figures: the Pareto plot of image error against render
cost (with the cost's 90 % interval), the lobe slices per colour channel, and
the renders of the standard views side by side."""
from __future__ import annotations

import numpy as np

import mitsuba as mi

from ...render.tonemap import to_srgb8
from . import rank

CHANNELS = (("R", "#c0392b"), ("G", "#27ae60"), ("B", "#2e6fd8"))
SHOWN_IN_SLICES = 3          # the target and this many first-ranked models


def _figure(width, height):
    from matplotlib.figure import Figure      # the reports extra; no pyplot: no global backend
    return Figure(figsize=(width, height), dpi=100)


def pareto_plot(path: str, title: str, rows: list[dict]) -> None:
    """FLIP against the verdict's cost (:func:`.rank.cost`: the time to the
    same noise, else the time per sample), each with its interval; the front
    (:func:`.rank.front`) in red, numbered from the cheapest and listed beside
    the plot (labels never overlap); the first-ranked fit a star."""
    fig = _figure(8.4, 4.4)
    ax = fig.add_axes([0.08, 0.12, 0.55, 0.78])
    measured = [r for r in rows if r.get("cost_ratio") is not None]
    x = {id(r): rank.cost(r) for r in measured}
    order = rank.front(measured)
    first = rank.ranked(rows)[0] if rank.ranked(rows) else None
    for r in measured:
        c, lo, hi = rank.cost_interval(r)
        q = max(rank.quality(r), 1e-4)
        lo, hi = lo or c, hi or c
        on = r in order
        colour = "C3" if on else "0.6"
        ax.errorbar([c], [q], xerr=[[c - lo], [min(hi, 10 * c) - c]], fmt="o", ms=5 if on else 3,
                    color=colour, ecolor=colour, elinewidth=1, capsize=2, zorder=3 if on else 2)
    if first is not None and first in measured:
        ax.plot([x[id(first)]], [max(rank.quality(first), 1e-4)], marker="*", ms=14,
                color="C3", markeredgecolor="black", zorder=4, ls="none")
    for i, r in enumerate(order, 1):
        ax.annotate(str(i), (x[id(r)], max(rank.quality(r), 1e-4)), fontsize=8,
                    xytext=(4, 4), textcoords="offset points", color="C3")
    if order:
        ax.plot([x[id(r)] for r in order], [max(rank.quality(r), 1e-4) for r in order],
                color="C3", lw=1, alpha=0.6)
    ax.set_yscale("log")
    name = rank.cost_name(measured[0]) if measured else "render cost"
    ax.set_xlabel(f"{name} / target's (90 % interval)")
    ax.set_ylabel("image error (FLIP, mean of the views)")
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    lines = [f"{i}{' ★' if r is first else '  '} {r['model']}\n     FLIP {rank.quality(r):.3f}, "
             f"cost {x[id(r)]:.2f}×" for i, r in enumerate(order, 1)]
    fig.text(0.66, 0.9, f"Pareto front (equal cost: the same\n{rank.COST_BAND:.0%} cost class); "
             "★ first-ranked\n\n" + "\n".join(lines), fontsize=7, va="top", family="monospace")
    fig.savefig(path)


def slice_plot(path: str, title: str, target_record: dict, rows: list[dict]) -> None:
    """eval in the plane of incidence, one row per colour channel, one column
    per viewer angle: the target (black) and the first-ranked models (on a
    cube-root axis, as the objective sees them)."""
    angles = target_record["slices"]["angles"]
    fig = _figure(3.0 * len(angles), 2.3 * len(CHANNELS))
    axes = fig.subplots(len(CHANNELS), len(angles), sharex=True, squeeze=False)
    points = len(target_record["slices"]["target"][0][0])
    theta = np.linspace(-89.5, 89.5, points)
    shown = rows[:SHOWN_IN_SLICES]
    for k, a in enumerate(angles):
        for c, (name, colour) in enumerate(CHANNELS):
            ax = axes[c][k]
            ax.plot(theta, np.maximum(target_record["slices"]["target"][k][c], 0), color="black",
                    lw=2, label="target")
            for i, r in enumerate(shown):
                ax.plot(theta, np.maximum(r["slices"]["model"][k][c], 0), lw=1, color=f"C{i}",
                        ls=("-", "--", ":")[i % 3], label=r["model"])
            ax.set_yscale("function", functions=(np.cbrt, lambda y: y ** 3))
            ax.tick_params(labelsize=6)
            if c == 0:
                ax.set_title(f"viewer at θ = {a:g}° (mirror side > 0)", fontsize=8)
            if k == 0:
                ax.set_ylabel(f"{name}: eval (f·cos θ)", fontsize=8, color=colour)
            if c == len(CHANNELS) - 1:
                ax.set_xlabel("light θ (degrees)", fontsize=8)
    axes[0][-1].legend(fontsize=6)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path)


def views_strip(path: str, images: dict, operator: str) -> None:
    """The views side by side (tone mapped) as one JPEG."""
    strip = np.concatenate([to_srgb8(images[v], operator) for v in images], axis=1)
    mi.Bitmap(np.ascontiguousarray(strip), mi.Bitmap.PixelFormat.RGB).write(path, quality=90)
