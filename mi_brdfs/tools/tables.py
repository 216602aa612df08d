"""Build and check the shipped albedo tables of energy compensation (:mod:`mi_brdfs.bsdfs.compensation`).

    python -m mi_brdfs.tools.tables                 # rebuild mi_brdfs/bsdfs/data/albedo.npz
    python -m mi_brdfs.tools.tables --only walk/ggx # rebuild some tables, keep the others
    python -m mi_brdfs.tools.tables --check         # measure the tables' errors

Single-scattering tables (E, by quadrature over each model's sampler) take
seconds; the random-walk tables (W, :mod:`.groundtruth`) minutes, as do the
directional lobe's (``--only directional/ggx directional/beckmann``: its pair
table, the scale that gives it the walk's albedo, :func:`calibrate`, and its
albedo).

``--check`` measures, for every single-scattering table, (1) the quadrature
error: the largest difference between the shipped values and a fresh build
with half the samples per axis, and (2) the interpolation error: the largest
difference between E computed at the centres of the cells (every axis refined
2x) and the table's interpolation there, over the whole table and over the
incident angles up to 85° (cos θ >= 0.087), where the model accepts the
parameters (Blinn: α <= 1). The white compensated albedo is 1 + (E - E~), so
(2) bounds the white furnace's deviation from 1. For every walk table it
measures (1) the Monte-Carlo noise: the difference between the shipped
values and a walk with another seed and a quarter of the paths, on a few μ
rows, and (2) the interpolation error of W along α and F0 at cell centres of
those rows (with the same seed: the walk's noise, correlated between nodes,
mostly cancels).

Needs SciPy (the ``reports`` extra), as the walk does.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import replace

import numpy as np

import drjit as dr
import mitsuba as mi

from .._jit import from_numpy
from ..bsdfs import PLUGINS, compensation, directional
from ..bsdfs.grid import hemisphere_direction
from . import groundtruth
from .groundtruth import MU_MIN, WALK_SEED

MU_85 = 0.0871557      # cos 85°


# ----------------------------------------------------------------------------
#  Building the single-scattering tables (JIT variants)
# ----------------------------------------------------------------------------

SEED = 20261130           # of the quadrature's jitter


def build(spec: compensation.AlbedoSpec, samples: int | None = None, batch: int = 1 << 22) -> np.ndarray:
    """E at every node of ``spec``, by quadrature over the model's sampler
    (``samples`` strata per axis, default the spec's). A parameter node at
    infinity (a roughness axis's last) holds E = 0."""
    samples = samples or spec.samples
    nodes = [a.nodes() for a in spec.axes]
    grid = np.stack(np.meshgrid(*nodes, indexing="ij"), axis=-1).reshape(-1, len(nodes))
    d = spec.directions
    infinite = np.isinf(grid).any(axis=1)
    grid = grid[~infinite]
    mu = np.maximum(grid[:, 0], MU_MIN)
    wi_np = hemisphere_direction(mu, np.sin(compensation.azimuth(spec.axes[1], grid[:, 1])) ** 2
                                 if d == 2 else None)
    params_np = grid[:, d:]
    # Jittered strata (a fixed seed): the midpoints alone alias with samplers
    # that split the square (GGX's visible normals: 0.998 instead of 0.976).
    rng = np.random.default_rng(SEED)
    i, j = (a.ravel() for a in np.meshgrid(np.arange(samples), np.arange(samples), indexing="ij"))
    ux = (i + rng.random(i.size)) / samples
    uy = (j + rng.random(j.size)) / samples
    per = samples * samples
    out = np.empty(len(grid))
    step = max(1, batch // per)
    for start in range(0, len(grid), step):
        sl = slice(start, min(start + step, len(grid)))
        n = sl.stop - sl.start
        node = from_numpy(mi.UInt32, np.repeat(np.arange(n, dtype=np.uint32), per))
        take = lambda a: dr.gather(mi.Float, from_numpy(mi.Float, a[sl]), node)
        wi = mi.Vector3f(take(wi_np[:, 0]), take(wi_np[:, 1]), take(wi_np[:, 2]))
        params = [take(params_np[:, k]) for k in range(params_np.shape[1])]
        sample2 = from_numpy(mi.Point2f, (np.tile(ux, n), np.tile(uy, n)))
        wo = spec.sample(wi, sample2, *params)
        pdf = spec.pdf(wi, wo, *params)
        ok = (pdf > 0) & (mi.Frame3f.cos_theta(wo) > 0)
        value = dr.select(ok, spec.f(wi, wo, *params) / dr.select(ok, pdf, 1.0), 0.0)
        total = dr.block_sum(mi.Float64(value), per)
        out[sl] = np.asarray(total) / per
    values = np.zeros(len(infinite))
    values[~infinite] = np.clip(out, 0.0, 1.0)
    values = values.reshape(tuple(a.n for a in spec.axes))
    if spec.valid_up_to is not None:
        k = spec.directions
        x = spec.axes[k].nodes()
        last = int(np.searchsorted(x, spec.valid_up_to, side="right")) - 1   # last valid node
        v = np.moveaxis(values, k, 0)
        d1 = 1.5 * v[last] - 2.0 * v[last - 1] + 0.5 * v[last - 2]     # one-sided slope
        d2 = v[last] - 2.0 * v[last - 1] + v[last - 2]                 # and curvature
        for j in range(last + 1, len(x)):
            v[j] = v[last] + (j - last) * d1 + 0.5 * (j - last) ** 2 * d2
        values = np.clip(np.moveaxis(v, 0, k), 0.0, 1.0)
    return values


# ----------------------------------------------------------------------------
#  Building the directional tables (the walk's bounces k >= 2 by pair, JIT variants)
# ----------------------------------------------------------------------------

PAIR_SEED = 20261207      # of the directional tables' walks
PAIR_F0S = ((0.0, 0.2, 0.4), (0.6, 0.8, 1.0))    # F0_AXIS's nodes, three per walk (a colour)


def _walk_surface(distribution: str, alpha: float):
    """The walk's Smith microsurface of ``distribution`` at one α (at least 1e-4)."""
    from ..bsdfs import walk
    from ..bsdfs.microfacet import Microfacet
    return walk.surface(Microfacet(distribution, mi.Float(max(alpha, 1e-4)), visible=True))


def _schlick_colour(f0s):
    """Schlick's F of three F0s as the channels of one colour, for a walk that
    takes all three on the same paths. (Not :func:`.fresnel.schlick` of a
    colour F0: its 1 - F0 in float32 differs from this one's by an ulp, and
    the shipped tables were walked with this one.)"""
    return lambda c: mi.Color3f(*[float(f) + (1.0 - float(f)) * dr.power(dr.fmax(1.0 - c, 0.0), 5)
                                  for f in f0s])


def walk_pairs(distribution: str, alpha: float, wi: np.ndarray, wo: np.ndarray, paths: int,
               seed: int = PAIR_SEED, batch: int = 1 << 22) -> np.ndarray:
    """S = E[X + Y] of the walk's bounces k >= 2 at each pair (wi, wo) (N, 3),
    X the next-event estimate from wi toward wo and Y from wo toward wi
    (:func:`mi_brdfs.bsdfs.walk.scattered`), for each F0 of :data:`PAIR_F0S`
    (shape (N, 6)), Schlick's F at every bounce; ``paths`` per pair and end,
    the same random numbers for every F0 and, path by path, for every pair.
    f_ms = S / (cos θ_i + cos θ_o)."""
    from ..bsdfs import walk
    s = _walk_surface(distribution, alpha)
    out = np.zeros((len(wi), 6))
    step = max(1, batch // paths)
    for start in range(0, len(wi), step):
        stop = min(start + step, len(wi))
        n = stop - start
        lanes = lambda v: mi.Vector3f(*[from_numpy(mi.Float, np.repeat(v[start:stop, c], paths)
                                                   .astype(np.float32)) for c in range(3)])
        a, b = lanes(wi), lanes(wo)
        path = dr.arange(mi.UInt32, n * paths) % paths
        sums = []
        for f0s in PAIR_F0S:
            schlick = _schlick_colour(f0s)
            x = walk.scattered(s, a, b, schlick, mi.PCG32(n * paths, path, 2 * seed + 1))
            y = walk.scattered(s, b, a, schlick, mi.PCG32(n * paths, path, 2 * seed + 3))
            total = x + y
            dr.eval(total)
            sums.append(np.asarray(total).reshape(3, n, paths).mean(axis=-1).T)
        out[start:stop] = np.concatenate(sums, axis=1)
    return out


def build_pairs(spec, paths: int | None = None, log=None) -> np.ndarray:
    """S at every node of a :class:`mi_brdfs.bsdfs.directional.PairSpec`
    (μ_i, μ_o, u, α, F0), symmetrised in (μ_i, μ_o). μ = 0 is walked at
    ``MU_MIN``."""
    paths = paths or spec.paths
    mu_i, mu_o, u, alpha_axis, f0_axis = spec.axes
    mi_, mo_, u_ = (g.ravel() for g in np.meshgrid(np.maximum(mu_i.nodes(), MU_MIN),
                                                   np.maximum(mu_o.nodes(), MU_MIN), u.nodes(),
                                                   indexing="ij"))
    wi, wo = directional.pair_directions(mi_, mo_, directional.azimuth_at(mi_, mo_, u_))
    out = np.zeros((mu_i.n, mu_o.n, u.n, alpha_axis.n, f0_axis.n))
    for k, alpha in enumerate(alpha_axis.nodes()):
        s = walk_pairs(spec.distribution, float(alpha), wi, wo, paths)
        out[:, :, :, k, :] = s.reshape(mu_i.n, mu_o.n, u.n, f0_axis.n)
        if log:
            log(f"  {spec.name}: alpha {alpha:.3g} walked")
    return 0.5 * (out + out.transpose(1, 0, 2, 3, 4))


SCALE_SEED = 20261208      # of the scale's target walks


def walk_multiple_albedo(distribution: str, alpha: float, mus: np.ndarray, f0s: np.ndarray,
                         paths: int, seed: int = SCALE_SEED) -> np.ndarray:
    """The walk's directional albedo of bounces k >= 2 from each cos θ of
    ``mus``, Schlick's F with each of ``f0s`` at every bounce: the mean of
    the sampled walk's weight over the paths that met two facets or more
    (:func:`mi_brdfs.bsdfs.walk.sample`), (len(mus), len(f0s)). The same
    random numbers, path by path, for every cos θ, F0 and α."""
    from ..bsdfs import walk
    s = _walk_surface(distribution, alpha)
    n = len(mus)
    mu = np.repeat(np.maximum(mus, MU_MIN), paths)
    wi = from_numpy(mi.Vector3f, (np.sqrt(1.0 - mu * mu), 0.0 * mu, mu))
    path = dr.arange(mi.UInt32, n * paths) % paths
    padded = np.concatenate([f0s, np.ones(-len(f0s) % 3)]).reshape(-1, 3)
    out = []
    for three in padded:
        _, weight, bounces = walk.sample(s, wi, _schlick_colour(three),
                                         mi.PCG32(n * paths, path, 2 * seed + 1))
        kept = dr.select(bounces >= 2, weight, 0.0)
        out.append(np.asarray(kept).reshape(3, n, paths).mean(axis=-1).T)
    return np.concatenate(out, axis=1)[:, :len(f0s)]


def pair_cells(mus: np.ndarray, n_mu: int = 192, n_u: int = 96):
    """The quadrature of :func:`pair_kernel` for each cos θ_i of ``mus``:
    cos θ_o at the midpoints of n_mu cells uniform in sqrt(μ_o) (the table's
    and the scale's warp) with their widths, and the azimuth at the midpoints
    of n_u cells of u uniform in the table's u warp, with the azimuth each
    cell spans (over [0, π]; u falls as the azimuth grows). In the table's
    own coordinates each cell holds a smooth piece of the interpolant: near
    the grazing mirror pair of small α the lobe is a spike a degree wide in
    azimuth, which a midpoint rule uniform in azimuth misses (twice the light
    or half of it)."""
    t = (np.arange(n_mu) + 0.5) / n_mu
    mo, dmo = t * t, 2.0 * t / n_mu
    axis = directional.U_AXIS
    a, b = axis._ends()
    edges = axis._inverse_np(np.linspace(a, b, n_u + 1))
    mids = axis._inverse_np(a + (np.arange(n_u) + 0.5) * (b - a) / n_u)
    I, M = (g.ravel() for g in np.meshgrid(np.maximum(mus, MU_MIN), mo, indexing="ij"))
    rep = lambda x, k: np.repeat(x, k)
    phi_edges = directional.azimuth_at(rep(I, n_u + 1), rep(M, n_u + 1),
                                       np.tile(edges, I.size)).reshape(I.size, n_u + 1)
    phi = directional.azimuth_at(rep(I, n_u), rep(M, n_u),
                                 np.tile(mids, I.size)).reshape(I.size, n_u)
    dphi = phi_edges[:, :-1] - phi_edges[:, 1:]
    # along the normal u is 0 at every azimuth (and the lobe does not depend on
    # it): where min(θ_i, θ_o), u's span, is below u_coordinate's 1e-6
    flat = np.minimum(np.arccos(np.minimum(I, 1.0)), np.arccos(np.minimum(M, 1.0))) <= 1e-6
    phi[flat] = (np.arange(n_u) + 0.5) * np.pi / n_u
    dphi[flat] = np.pi / n_u
    return mo, dmo, phi, dphi


def pair_kernel(table, alpha: float, f0: float, mus: np.ndarray, cells=None):
    """K with the directional albedo of ``table``'s lobe at each cos θ_i of
    ``mus`` = K @ (a factor at each cos θ_o of the quadrature), and those
    cos θ_o: ∫ S / (μ_i + μ_o) μ_o dω_o over the cells of :func:`pair_cells`
    (the lobe is even in the azimuth: twice [0, π])."""
    mo, dmo, phi, dphi = cells if cells is not None else pair_cells(mus)
    n_mu, n_u = len(mo), phi.shape[1]
    I = np.repeat(np.maximum(mus, MU_MIN), n_mu * n_u)
    M = np.tile(np.repeat(mo, n_u), len(mus))
    wi, wo = directional.pair_directions(I, M, phi.ravel())
    pair = tuple(from_numpy(mi.Vector3f, w.T.astype(np.float32)) for w in (wi, wo))
    s = np.asarray(directional.read_s(table, pair, float(alpha), float(f0)), dtype=np.float64)
    s = (s * M / (I + M) * 2.0 * dphi.ravel()).reshape(len(mus), n_mu, n_u).sum(axis=-1)
    return s * dmo, mo


def calibrate(spec, values: np.ndarray, paths: int | None = None, log=None,
              iterations: int = 100) -> np.ndarray:
    """c over :data:`mi_brdfs.bsdfs.directional.SCALE_AXES` (μ, α, F0) such
    that the pair table ``values`` read as f_ms c(μ_i) c(μ_o) has the walk's
    albedo of bounces k >= 2 (:func:`walk_multiple_albedo`) at every node:
    per (α, F0), symmetric Sinkhorn steps c <- c sqrt(target / albedo) on the
    interpolated lobe's albedo (:func:`pair_kernel`, c read between its μ
    nodes as the plugin reads it, linearly). Where the target or the
    albedo is below 1e-6 (no light to put right) c stays 1; c is kept in
    [1/4, 4]."""
    scale = directional.ScaleSpec(spec.distribution)
    paths = paths or scale.paths
    mu_axis, alpha_axis, f0_axis = scale.axes
    mus, f0s = mu_axis.nodes(), f0_axis.nodes()
    table = directional.PairTable(values, spec)
    cells = pair_cells(mus)
    out = np.ones((mu_axis.n, alpha_axis.n, f0_axis.n))
    for k, alpha in enumerate(alpha_axis.nodes()):
        target = walk_multiple_albedo(spec.distribution, float(alpha), mus, f0s, paths)
        worst = 0.0
        for j, f0 in enumerate(f0s):
            kernel, mo = pair_kernel(table, alpha, f0, mus, cells)
            x = mu_axis.coordinate_np(mo)           # c at mo: linear between nodes
            lo = np.minimum(x.astype(int), mu_axis.n - 2)
            read = np.zeros((len(mo), mu_axis.n))
            read[np.arange(len(mo)), lo] = 1.0 - (x - lo)
            read[np.arange(len(mo)), lo + 1] = x - lo
            albedo = lambda c, k=kernel @ read: c * (k @ c)
            c, goal = np.ones(mu_axis.n), target[:, j]
            for _ in range(iterations):
                a = albedo(c)
                ok = (goal > 1e-6) & (a > 1e-6)
                c = np.clip(np.where(ok, c * np.sqrt(goal / np.where(ok, a, 1.0)), 1.0), 0.25, 4.0)
            worst = max(worst, float(np.max(np.abs(albedo(c) - goal))))
            out[:, k, j] = c
        if log:
            log(f"  {scale.name}: alpha {alpha:.3g}, c in [{out[:, k].min():.3f}, "
                f"{out[:, k].max():.3f}], albedo within {worst:.1e} of the walk's k >= 2")
    return out


def pair_albedo(spec, values: np.ndarray, scale: np.ndarray | None = None) -> np.ndarray:
    """The directional albedo of the interpolated pair table (and its
    ``scale``), ∫ f_ms cos θ_o dω_o, read as the plugin reads it, at the nodes
    of :data:`mi_brdfs.bsdfs.directional.ALBEDO_AXES` (μ, α, F0), by
    :func:`pair_kernel`'s quadrature."""
    table = directional.PairTable(values, spec, scale)
    mu_axis, alpha_axis, f0_axis = directional.ALBEDO_AXES
    cells = pair_cells(mu_axis.nodes())
    out = np.zeros((mu_axis.n, alpha_axis.n, f0_axis.n))
    for j, alpha in enumerate(alpha_axis.nodes()):
        for k, f0 in enumerate(f0_axis.nodes()):
            out[:, j, k] = pair_kernel(table, alpha, f0, mu_axis.nodes(), cells)[0].sum(axis=1)
    return out


def specs() -> list:
    """Every table every model declares (its ``tables()``), AlbedoSpecs and
    WalkSpecs, each once."""
    found = []
    for cls in PLUGINS:
        for spec in cls.tables():
            if spec.name not in {s.name for s in found}:
                found.append(spec)
    return found


def refined(spec):
    """The spec with every axis refined 2x (its nodes and the cell centres)."""
    axes = tuple(replace(a, n=2 * a.n - 1) for a in spec.axes)
    return replace(spec, axes=axes)


def interpolation_error(spec, table, samples: int, bounded: bool = False) -> tuple[float, float]:
    """(max |E - E~| at cell centres, the same for cos θ >= cos 85°);
    ``bounded``: only where the parameters of unbounded axes are <= 1."""

    fine = refined(spec)
    exact = build(fine, samples)
    centres = tuple(slice(1, None, 2) for _ in fine.axes)
    exact = exact[centres]
    points = [a.nodes()[1::2] for a in fine.axes]
    mesh = [m.ravel() for m in np.meshgrid(*points, indexing="ij")]
    interp = np.asarray(table.grid(*[from_numpy(mi.Float, m) for m in mesh])).reshape(exact.shape)
    dr.eval()
    err = np.abs(exact - np.clip(interp, 0, 1))
    if spec.valid_up_to is not None:        # beyond: extrapolated, not the model's
        k = spec.directions
        keep = points[k] <= spec.valid_up_to
        err = np.take(err, np.flatnonzero(keep), axis=k)
        points[k] = points[k][keep]
    if bounded:
        for k, axis in enumerate(spec.axes):
            if np.isinf(axis.hi):
                keep = points[k] <= 1.0
                err = np.take(err, np.flatnonzero(keep), axis=k)
    up = points[0] >= MU_85
    return float(err.max()), float(err[up].max())


def check_walk(spec, paths: int, log) -> str:
    """(MC noise, interpolation error along the roughness axes and F0) of a
    walk table, on four μ rows (at φ = 0 and 90° for an anisotropic one)."""
    shipped = compensation.shipped(spec)
    rows = [k * (spec.axes[0].n - 1) // 8 for k in (1, 3, 5, 7)]   # 33 nodes: rows 4, 12, 20, 28
    again = groundtruth.table(spec, paths=paths, seed=WALK_SEED + 1, rows=rows)
    d = spec.directions
    rough = spec.axes[d:-1]
    walked = np.ix_(*[a.nodes() <= spec.alpha_max for a in rough])
    noise = max(np.abs(again[i][..., *walked, :] - shipped[i][..., *walked, :]).max()
                for i in rows)
    # cell centres in the roughness axes (between walked nodes) and in F0, against the
    # interpolation (the same seed: the walk's noise, correlated between nodes, mostly cancels)
    fine = refined(spec)
    mids = []
    for a, f in zip(rough, fine.axes[d:-1]):
        x = f.nodes()[1::2]
        mids.append(x[x < a.nodes()[a.nodes() <= spec.alpha_max][-1]])
    f_mid = fine.axes[-1].nodes()[1::2]
    grid = compensation.Table(spec.axes, shipped, d).grid
    mesh = [m.ravel() for m in np.meshgrid(*mids, indexing="ij")]
    worst = 0.0
    for i in rows:
        mu = spec.axes[0].nodes()[i]
        for s2 in ((spec.axes[1].lo, spec.axes[1].hi) if d == 2 else (None,)):   # φ 0, 90°
            alpha = mesh[0] if d == 1 else groundtruth.Alpha(*mesh)
            phi = 0.0 if s2 is None else compensation.azimuth(spec.axes[1], s2)
            walked_w = groundtruth.albedo(spec.distribution, max(mu, MU_MIN), alpha, f_mid, paths,
                                          WALK_SEED, phi=phi)
            point = [np.repeat(m, len(f_mid)) for m in mesh] + [np.tile(f_mid, len(mesh[0]))]
            where = [np.full(point[0].size, mu)] + ([] if s2 is None
                                                    else [np.full(point[0].size, s2)])
            interp = np.asarray(grid(*[from_numpy(mi.Float, x) for x in where + point]))
            worst = max(worst, float(np.abs(interp - walked_w.ravel()).max()))
        log(f"  {spec.name}: checked mu row {i}")
    return (f"{spec.name}: axes {'x'.join(str(a.n) for a in spec.axes)}; Monte-Carlo noise "
            f"{noise:.1e} ({paths} paths vs the shipped {spec.paths}, rows {rows}); "
            f"interpolation error along the roughness and F0 {worst:.1e} (where walked)")


def check_pairs(spec, log, paths: int = 1 << 13) -> str:
    """The Monte-Carlo noise of a directional table: its nodes at α 0.14 and
    0.53 walked again with another seed and a quarter of the paths, the
    largest difference relative to the node's largest value."""
    shipped = compensation.shipped(spec)
    mu_i, mu_o, u, alpha_axis, _ = spec.axes
    mi_, mo_, u_ = (g.ravel() for g in np.meshgrid(np.maximum(mu_i.nodes(), MU_MIN),
                                                   np.maximum(mu_o.nodes(), MU_MIN), u.nodes(),
                                                   indexing="ij"))
    wi, wo = directional.pair_directions(mi_, mo_, directional.azimuth_at(mi_, mo_, u_))
    worst = []
    for k in (8, 14):
        alpha = float(alpha_axis.nodes()[k])
        again = walk_pairs(spec.distribution, alpha, wi, wo, paths, seed=PAIR_SEED + 1)
        again = 0.5 * (again.reshape(shipped.shape[:3] + (-1,))
                       + again.reshape(shipped.shape[:3] + (-1,)).transpose(1, 0, 2, 3))
        node = shipped[:, :, :, k, :]
        worst.append(float(np.abs(again - node).max() / node.max()))
        log(f"  {spec.name}: alpha {alpha:.3g} walked again")
    return (f"{spec.name}: axes {'x'.join(str(a.n) for a in spec.axes)}; Monte-Carlo noise "
            f"{max(worst):.1e} of the largest node ({paths} paths vs the shipped {spec.paths})")


def main(argv: list[str] | None = None) -> int:
    """Rebuild the albedo tables, or (--check) measure their errors."""
    parser = argparse.ArgumentParser(prog="python -m mi_brdfs.tools.tables",
                                     description="Rebuild the albedo tables, or (--check) measure their errors.")
    parser.add_argument("--check", action="store_true", help="measure the shipped tables' errors")
    parser.add_argument("--only", nargs="+", metavar="NAME",
                        help="only these tables (names as printed; the others are kept)")
    parser.add_argument("--samples", type=int,
                        help="quadrature samples per axis (default: each table's, "
                             f"{compensation.SAMPLES} for most)")
    parser.add_argument("--paths", type=int,
                        help="random-walk paths per node (default: each table's, "
                             f"{compensation.WALK_PATHS} for most; --check: a quarter of it)")
    args = parser.parse_args(argv)
    if not dr.is_jit_v(mi.Float):
        mi.set_variant("llvm_ad_rgb")
    every = specs()
    chosen = [s for s in every if not args.only or s.name in args.only]
    unknown = set(args.only or ()) - {s.name for s in chosen}
    if unknown:
        parser.error(f"unknown tables {sorted(unknown)}; valid: "
                     f"{', '.join(s.name for s in every)}")
    log = lambda text: print(text, file=sys.stderr)
    out = {}
    if args.only and os.path.exists(compensation.DATA):
        with np.load(compensation.DATA) as f:
            out = {k: f[k] for k in f.files}
    for spec in chosen:
        start = time.perf_counter()
        walk = isinstance(spec, compensation.WalkSpec)
        if isinstance(spec, directional.PairSpec):
            if args.check:
                print(check_pairs(spec, log) + f" [{time.perf_counter() - start:.0f} s]")
                continue
            out[spec.name] = build_pairs(spec, args.paths, log)
            scale = directional.ScaleSpec(spec.distribution)
            out[scale.name] = calibrate(spec, out[spec.name], log=log)
            albedo = directional.PairAlbedoSpec(spec.distribution)
            out[albedo.name] = pair_albedo(spec, out[spec.name], out[scale.name])
            log(f"{spec.name}: {out[spec.name].size} nodes x {args.paths or spec.paths} paths "
                f"per end, {scale.name} and {albedo.name}, {time.perf_counter() - start:.1f} s")
            continue
        if args.check and walk:
            print(check_walk(spec, max(1000, (args.paths or spec.paths) // 4), log)
                  + f" [{time.perf_counter() - start:.0f} s]")
            continue
        if args.check:
            shipped = compensation.table(spec)
            samples = args.samples or spec.samples
            half = build(spec, samples // 2)
            diff = np.abs(half - shipped.grid.values)
            if spec.valid_up_to is not None:    # beyond: extrapolated, not the model's
                k = spec.directions
                diff = np.take(diff, np.flatnonzero(spec.axes[k].nodes() <= spec.valid_up_to),
                               axis=k)
            quad = float(np.max(diff))
            inter, inter85 = interpolation_error(spec, shipped, max(16, samples // 4))
            unbounded = any(np.isinf(a.hi) for a in spec.axes)
            bounded = (f"; alpha <= 1 up to 85 deg: "
                       f"{interpolation_error(spec, shipped, max(16, samples // 4), True)[1]:.1e}"
                       if unbounded else "")
            print(f"{spec.name}: axes {'x'.join(str(a.n) for a in spec.axes)}; quadrature "
                  f"error {quad:.1e}; interpolation error {inter:.1e} "
                  f"(up to 85 deg: {inter85:.1e}{bounded}) [{time.perf_counter() - start:.0f} s]")
            continue
        if walk:
            out[spec.name] = groundtruth.table(spec, paths=args.paths, log=log)
            what = f"{args.paths or spec.paths} paths"
        else:
            out[spec.name] = build(spec, args.samples)
            what = f"{args.samples or spec.samples}^2 samples"
        log(f"{spec.name}: {out[spec.name].size} nodes x {what}, "
            f"{time.perf_counter() - start:.1f} s")
    if args.check:
        return 0
    os.makedirs(os.path.dirname(compensation.DATA), exist_ok=True)
    tmp = compensation.DATA + ".tmp.npz"
    np.savez_compressed(tmp, **{k: v.astype(np.float32) for k, v in out.items()})
    os.replace(tmp, compensation.DATA)
    print(f"wrote {compensation.DATA}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
