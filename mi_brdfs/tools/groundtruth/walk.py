"""The random walk on a Smith microsurface: the light that leaves, and its BRDF.

Heitz, Hanika, d'Eon & Dachsbacher 2016, "Multiple-Scattering Microfacet BSDFs
with the Smith Model" (ACM TOG 35(4)), section 4 and its appendices, for a
conductor: the Smith microsurface is a volume whose facets scatter light
until it leaves through the top. This module follows the paper's model; the
coordinates and the loop are our own.

**Depth.** The paper gives the microsurface a height distribution with cdf
C1(h) and masking G1(w, h) = C1(h)^Λ(w) at height h (w going up); the result
does not depend on that distribution. We measure depth by τ = -ln C1(h)
(τ = 0 at the top, above every facet). Then G1(w, τ) = exp(-Λ(w) τ): along a
direction w the microsurface is a homogeneous medium in τ whose extinction
per unit of τ is |Λ(w)| (Λ(w) going up, 1 + Λ(-w) going down: the projected
area of the facets that face the ray over |cos θ|). A free flight with
E ~ Exp(1) moves the path to

    τ' = τ - E / Λ(w)

(up for Λ > 0, down for Λ < 0; along the horizon |Λ| is infinite: the ray
meets a facet where it is); going up, τ' <= 0 means the path has left.

**Phase function.** At a facet the ray arriving along w sees it from
wb = -w: the normal m is drawn from the normals visible from wb,
D_wb(m) = max(0, wb·m) D(m) / A(wb), the ray is mirrored about it, and the
path's weight is multiplied by Schlick's Fresnel F(wb·m) for every F0 asked
(one path serves every F0), or by any other Fresnel form given as a function of
the cosine (:func:`.microsurface.conductor`, :func:`.microsurface.dielectric`,
:func:`.microsurface.f82`; one column per colour channel). For F0 = 1 every weight stays 1: the walk loses
no light, the white furnace of the model.

**BRDF.** Next-event estimation: at each facet the phase function toward the
light wo, F(wb·h) D_wb(h) / (4 wb·h) with h = (wb + wo)/|wb + wo|, times the probability G1(wo, τ) of leaving along wo
from there; the expectation of the sum over bounces is f·cos θ_o. The first
bounce alone is the height-correlated single scattering (Heitz 2014):
F D / (4 cos θ_i (1 + Λ(wi) + Λ(wo))).

Roughness is one α or an :class:`.Alpha` pair (α_x along s, α_y along t),
per direction; the microsurface functions take both through one code path
(:mod:`.microsurface`).

Vectorised in NumPy float64 over paths. Path j of every direction of a call
draws the same random numbers (common random numbers: a table's nodes, walked
together, are smooth along its axes); paths are walked in chunks of
``CHUNK``, each with its own generator, so path j's numbers do not depend on
how many directions a call walks. Paths still inside after ``MAX_ORDER``
bounces are dropped (none at F0 = 1 up to α = 3 in the tests).
"""
from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np

from ...bsdfs.compensation import azimuth
from ...bsdfs.microfacet import ALPHA_MIN
from .microsurface import (Alpha, check, d_visible, dot, fresnel, lam, normalize, pair,
                           sample_visible)

MAX_ORDER = 1000          # bounces after which a path still inside is dropped
CHUNK = 4096              # paths per chunk (each chunk its own generator)
MU_MIN = 1e-4             # the cos θ at which a table's μ = 0 node is computed (W and E)
WALK_SEED = 20160701      # of the walk of the shipped tables


class Walked(NamedTuple):
    """What :func:`walk` returns, per direction and F0 (shape (N, len(f0s))),
    with the standard errors of the means (the paths' spread / sqrt(paths))."""
    albedo: np.ndarray               # the mean weight with which the paths leave
    albedo_error: np.ndarray
    value: np.ndarray | None         # f·cos θ_o toward wo by next-event estimation
    value_error: np.ndarray | None   # (None: no wo)


def walk(distribution: str, wi, alpha, f0s, seed: int, paths: int, wo=None,
         orders: tuple[int, int] = (1, MAX_ORDER)) -> Walked:
    """``paths`` walks from each viewer direction ``wi`` (N, 3), with roughness
    ``alpha`` (one α or an :class:`.Alpha`, each broadcast to (N,)). Counts the
    paths that leave after a number of bounces in ``orders`` (first, last;
    inclusive), and, if ``wo`` (N, 3) is given, the next-event estimates of
    those bounces toward it."""
    check(distribution)
    wi = np.asarray(wi, dtype=np.float64)
    n = len(wi)
    ax, ay = (np.broadcast_to(a, (n,)) for a in pair(alpha))
    f0s = columns(f0s)
    wo = None if wo is None else np.asarray(wo, dtype=np.float64)
    sums = np.zeros((2, 2, n, len(f0s)))     # [albedo, value][Σ x, Σ x²] over paths
    for start in range(0, paths, CHUNK):
        m = min(CHUNK, paths - start)
        rng = np.random.default_rng((seed, start // CHUNK))
        per_path = _walk_chunk(distribution, wi, ax, ay, f0s, rng, m, wo, orders)
        for k, x in enumerate(x for x in per_path if x is not None):
            x = x.reshape(n, m, len(f0s))
            sums[k] += x.sum(axis=1), (x * x).sum(axis=1)
    mean = sums[:, 0] / paths
    error = np.sqrt(np.maximum(sums[:, 1] / paths - mean * mean, 0.0) / max(paths - 1, 1))
    if wo is None:
        return Walked(mean[0], error[0], None, None)
    return Walked(mean[0], error[0], mean[1], error[1])


def columns(f0s):
    """The Fresnel forms of a walk's columns: a float array of Schlick F0s, or
    a list whose items are F0s or functions F(cos) (NumPy) of another form."""
    if any(callable(f) for f in np.atleast_1d(np.asarray(f0s, dtype=object))):
        return list(f0s)
    return np.atleast_1d(np.asarray(f0s, dtype=np.float64))


def reflectance(f0s, c):
    """F at the cosines c (n,) for each column of ``f0s`` (:func:`columns`): (n, columns)."""
    if isinstance(f0s, np.ndarray):
        return fresnel(f0s, c[:, None])
    return np.stack([f(c) if callable(f) else fresnel(f, c) for f in f0s], axis=-1)


def _walk_chunk(distribution, wi, ax, ay, f0s, rng, m, wo, orders):
    """m paths from each direction; returns per path (direction-major) the
    weight it leaves with and the sum of its next-event estimates, per F0."""
    first, last = orders
    cell = np.arange(len(wi) * m)              # each path's own index
    node, path = cell // m, cell % m           # its direction; its random numbers
    w = -wi[node]                              # the direction the path travels
    tau = np.zeros(len(cell))                  # its depth τ = -ln C1(h)
    weight = np.ones((len(cell), len(f0s)))    # the product of its Fresnel factors, per F0
    alpha = Alpha(ax[node], ay[node])
    leaves = np.zeros_like(weight)             # what the path leaves with (in orders)
    seen = None if wo is None else np.zeros_like(weight)   # its next-event estimates
    for bounces in range(last + 1):            # facets met so far
        u = rng.random((3, m))[:, path]
        # ---- free flight: the next facet, or out through the top
        extinction = lam(distribution, w, alpha)       # 0 straight up: nothing in the way
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            tau = np.where(extinction == 0, -np.inf, tau + np.log1p(-u[0]) / extinction)
        out = (w[:, 2] > 0) & (tau <= 0)
        if bounces >= first:
            leaves[cell[out]] = weight[out]
        stay = ~out
        cell, node, path, w, tau, weight, u = cell[stay], node[stay], path[stay], w[stay], \
            tau[stay], weight[stay], u[:, stay]
        alpha = Alpha(alpha.x[stay], alpha.y[stay])
        if bounces == last or len(cell) == 0:
            break
        wb = -w                                # the facet is seen from here
        # ---- next-event estimation toward wo from this facet (bounce number bounces + 1)
        if wo is not None and bounces + 1 >= first:
            light = wo[node]
            h = normalize(wb + light)
            c = dot(wb, h)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                phase = d_visible(distribution, wb, h, alpha) / (4.0 * c)
                leave = np.exp(-tau * lam(distribution, light, alpha))    # G1(wo, τ)
                estimate = weight * (phase * leave)[:, None] * reflectance(f0s, c)
            seen[cell] += np.where(light[:, 2:] > 0, np.nan_to_num(estimate), 0.0)
        # ---- scattering: a visible normal, the mirror direction, Fresnel
        m_normal = sample_visible(distribution, wb, alpha, u[1], u[2])
        c = dot(wb, m_normal)
        w = 2.0 * c[:, None] * m_normal - wb
        weight = weight * reflectance(f0s, c)
        if not np.isfinite(w).all():
            raise FloatingPointError("random walk: a direction is not finite")
    return leaves, seen


def directions(mu, phi=0.0):
    """Unit directions at cos θ = mu and azimuth phi (radians), broadcast: (..., 3)."""
    mu, phi = np.broadcast_arrays(np.asarray(mu, dtype=np.float64),
                                  np.asarray(phi, dtype=np.float64))
    s = np.sqrt(np.maximum(1.0 - mu * mu, 0.0))
    return np.stack([s * np.cos(phi), s * np.sin(phi), mu], axis=-1)


def albedo(distribution: str, mu, alpha, f0s=(1.0,), paths: int = 100_000, seed: int = 1,
           orders: tuple[int, int] = (1, MAX_ORDER), phi=0.0,
           error: bool = False) -> np.ndarray:
    """Directional albedo W of the walk seen from cos θ = ``mu`` at azimuth
    ``phi`` (radians from the tangent s), shape (len, len(f0s)) after
    broadcasting ``mu``, ``phi`` and the roughness together (one walk per
    point). Anisotropic roughness: ``alpha=Alpha(alpha_x, alpha_y)``.
    ``error``: also return the standard errors, (W, its error)."""
    ax, ay = pair(alpha)
    mu, phi, ax, ay = (a.ravel() for a in np.broadcast_arrays(
        np.asarray(mu, dtype=np.float64), np.asarray(phi, dtype=np.float64), ax, ay))
    walked = walk(distribution, directions(mu, phi), Alpha(ax, ay), f0s, seed, paths,
                  orders=orders)
    return (walked.albedo, walked.albedo_error) if error else walked.albedo


def brdf(distribution: str, wi, wo, alpha, f0=1.0, paths: int = 100_000, seed: int = 1,
         orders: tuple[int, int] = (1, MAX_ORDER), error: bool = False) -> np.ndarray:
    """f·cos θ_o of the walk (Mitsuba's eval convention) at each pair (wi, wo)
    ((N, 3) each, or one of them (3,)), by next-event estimation; shape (N,).
    ``alpha``: one α or an :class:`.Alpha`, per pair or for all. ``error``:
    also return the standard errors, (f·cos θ_o, its error)."""
    wi, wo = np.broadcast_arrays(np.atleast_2d(np.asarray(wi, dtype=np.float64)),
                                 np.atleast_2d(np.asarray(wo, dtype=np.float64)))
    walked = walk(distribution, wi, alpha, [f0], seed, paths, wo=wo, orders=orders)
    below = wo[:, 2] <= 0
    value, err = (np.where(below, 0.0, x[:, 0]) for x in (walked.value, walked.value_error))
    return (value, err) if error else value


def table(spec, paths: int | None = None, seed: int | None = None, rows=None,
          log=None) -> np.ndarray:
    """W at the nodes of a :class:`mi_brdfs.bsdfs.compensation.WalkSpec`
    (μ, [φ or sin²φ,] α or (α_u, α_v), F0): one call per μ node, every node up to
    ``spec.alpha_max`` on common random numbers (the roughness nodes beyond
    hold the last walked one's W, per axis). μ = 0 is walked at ``MU_MIN``,
    α = 0 at ``ALPHA_MIN`` (as the plugins clamp them). An anisotropic table
    is walked where α_u < α_v, or α_u = α_v and φ <= 45°, and filled by the
    quarter turn W(μ, φ, α_u, α_v) = W(μ, 90° - φ, α_v, α_u).
    ``rows``: only these μ nodes (the others are NaN)."""
    mu_axis, f0_axis, inner = spec.axes[0], spec.axes[-1], spec.axes[1:-1]
    mus = np.maximum(mu_axis.nodes(), MU_MIN)
    walked = [np.flatnonzero(a.nodes() <= spec.alpha_max) if a.name.startswith("alpha")
              else np.arange(a.n) for a in inner]        # the walked nodes of each axis
    index = np.meshgrid(*walked, indexing="ij")        # (φ,) α or (α_u, α_v)
    keep = np.ones(index[0].shape, dtype=bool)
    if spec.directions == 2:                            # the quarter turn's canonical half
        s, u, v = index
        x = inner[0].nodes()
        if not (np.allclose(x, x[0] + x[-1] - x[::-1])
                and replace(inner[2], name=inner[1].name) == inner[1]):
            raise ValueError(f"{spec.name}: the quarter turn needs a symmetric azimuth axis "
                             "and equal roughness axes")
        keep = (u < v) | ((u == v) & (2 * s <= inner[0].n - 1))
    nodes = [np.maximum(a.nodes(), ALPHA_MIN) if a.name.startswith("alpha") else a.nodes()
             for a in inner]
    point = [x[i[keep]] for x, i in zip(nodes, index)]
    out = np.full(tuple(a.n for a in spec.axes), np.nan)
    for i in (range(len(mus)) if rows is None else rows):
        if spec.directions == 2:
            phi = azimuth(inner[0], point[0])
            w = albedo(spec.distribution, mus[i], Alpha(point[1], point[2]), f0_axis.nodes(),
                       paths or spec.paths, WALK_SEED if seed is None else seed, phi=phi)
        else:
            w = albedo(spec.distribution, mus[i], point[0], f0_axis.nodes(),
                       paths or spec.paths, WALK_SEED if seed is None else seed)
        block = np.full(index[0].shape + (f0_axis.n,), np.nan)
        block[keep] = w
        if spec.directions == 2:                        # the other half by the quarter turn
            block = np.where(np.isnan(block), block[::-1].swapaxes(1, 2), block)
        # the nodes beyond alpha_max hold the last walked one's W
        held = np.ix_(*[np.minimum(np.arange(a.n), len(k) - 1) for a, k in zip(inner, walked)])
        out[i] = block[held]
        if log:
            log(f"{spec.name}: mu node {i + 1}/{len(mus)}")
    return out
