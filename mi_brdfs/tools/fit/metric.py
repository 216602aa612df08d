"""The BRDF-space metrics the fit reports (``brdf_error``), the objective it
minimises, and the direction pairs both are estimated on.

``cosine`` (the default): the L² distance of the two BRDFs under the
projected solid angle of both directions, relative to the target's own norm::

    E²(f) = ∫∫ ‖f_t(ω_i, ω_o) - f(ω_i, ω_o)‖² cos θ_i cos θ_o dω_i dω_o
    brdf_error = E(f) / E(0)

with ‖·‖² the sum over the RGB channels, ω_i the viewer, ω_o the light
(Mitsuba's ``si.wi`` and ``wo``). E(0) is the error of a black BSDF, so 0
means identical and 1 is as far as black. The projected solid angle is how a
convex object shows a BRDF: the pixels that see a surface at θ_i scale with
cos θ_i, the light it receives from ω_o with cos θ_o. Every pair counts, up
to the horizon.

``ngan``: Ngan, Durand & Matusik 2005 ("Experimental Analysis of BRDF
Models", EGSR), section 4: the root-mean-square difference of the
cosine-weighted BRDF values ρ(ω_i, ω_o) cos θ_light (``eval``'s value), each
sample weighted by its solid angle, over the pairs with both angles at most
80° (they left out the measurements beyond 80°)::

    E²_ngan(f) = Σ w (f_t cos θ_o - f cos θ_o)² / Σ w,   θ_i, θ_o <= 80°

reported relative to a black BSDF's, as ``cosine``.

**The objective** (:data:`OBJECTIVES`, :func:`compress`): the same pairs,
each ``eval`` value compressed — by default its cube root, c(x) =
(x + 10⁻⁴)^(1/3) - 10^(-4/3) — and weighted by ``Pairs.shown``: for
``cosine`` the pair's weight times cos θ_i (the pixels that see the viewer;
``eval`` already holds cos θ_o), for ``ngan`` its own weight::

    E_c²(f) = Σ shown ‖c(eval_t) - c(eval)‖²,   objective = E_c(f) / E_c(0)

A sum of squares of ``eval`` itself is ruled by the peaks (they grow towards
the horizon: 45 % of the cosine metric's weight lies within 10° of it, median
over the trade materials, 5 % of the cube root's; ``python -m
mi_brdfs.tools.fit.study``), and a fit to it gives up a dim colour first.

**The direction pairs** (fixed by a seed: every fit of a run sees the same
set): viewers ω_i stratified over the hemisphere, uniformly in (cos θ, φ)
(``viewers`` = (n_z, n_φ) strata, one jittered point each: the lowest stratum
in cos θ reaches the horizon, so grazing viewers are always in the set). For
each viewer, the lights ω_o come from a mixture: ``uniform`` = (n_z, n_φ)
stratified points over the hemisphere (grazing lights included likewise),
and ``lobe`` points around the viewer's mirror direction for each roughness
in ``LOBE_ALPHAS`` (half vectors from the GGX distribution D(h) cos θ_h,
stratified, reflected): sharp lobes get samples where they are. The
integrals are estimated with the balance heuristic over that mixture (Veach
1997): each pair weighs 1 / (n_v p(ω_i)) · 1 / Σ_k n_k p_k(ω_o | ω_i), which
is unbiased whatever the target. Lights within ``COS_MIN`` of the horizon are
left out (their weight in either metric is below 1e-4 of a pair's).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import drjit as dr

METRICS = ("cosine", "ngan")
OBJECTIVES = ("cbrt", "log", "linear")   # what the optimiser minimises (see compress)
CBRT_FLOOR = 1e-4                   # c(x) = (x + 1e-4)^(1/3) - 1e-4^(1/3): finite slope at 0
LOG_FLOOR = 1e-2                    # c(x) = log(1 + x / 0.01)
LOBE_ALPHAS = (0.02, 0.1, 0.4)      # GGX roughness of the mirror-guided light samples
NGAN_MAX_DEG = 80.0                 # Ngan et al.'s largest angle
COS_MIN = 1e-4                      # lights closer to the horizon are left out
SEED = 20050629                     # of the jitter (EGSR 2005's first day)


@dataclass(frozen=True)
class Pairs:
    """Direction pairs and each pair's weights (NumPy, float64)."""
    wi: np.ndarray          # (N, 3) viewers, local frame
    wo: np.ndarray          # (N, 3) lights
    weight: np.ndarray      # (N,) multiplies Σ_c (eval_t - eval)² in E²
    shown: np.ndarray       # (N,) multiplies Σ_c (c(eval_t) - c(eval))² in the objective


def stratified(nz: int, nphi: int, rng) -> np.ndarray:
    """(nz·nphi, 2) jittered points of the unit square, one per stratum."""
    iz, ip = np.meshgrid(np.arange(nz), np.arange(nphi), indexing="ij")
    u = (iz.ravel() + rng.random(iz.size)) / nz
    v = (ip.ravel() + rng.random(ip.size)) / nphi
    return np.stack([u, v], axis=1)


def uniform_hemisphere(u: np.ndarray) -> np.ndarray:
    """Uniform directions on the hemisphere: cos θ = u_0, φ = 2π u_1 (density 1/(2π))."""
    z = u[:, 0]
    s = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = 2.0 * math.pi * u[:, 1]
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)


def ggx_d(cos_h: np.ndarray, alpha: float) -> np.ndarray:
    """The GGX (Trowbridge-Reitz) distribution D(h) for cos θ_h."""
    a2 = alpha * alpha
    c2 = np.clip(cos_h, 0.0, 1.0) ** 2
    return np.where(cos_h > 0, a2 / (math.pi * (c2 * (a2 - 1.0) + 1.0) ** 2), 0.0)


def ggx_half_vectors(u: np.ndarray, alpha: float) -> np.ndarray:
    """Half vectors with density D(h) cos θ_h: tan²θ = α² u_0 / (1 - u_0), φ = 2π u_1."""
    t2 = alpha * alpha * u[:, 0] / np.maximum(1.0 - u[:, 0], 1e-12)
    cos_t = 1.0 / np.sqrt(1.0 + t2)
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
    phi = 2.0 * math.pi * u[:, 1]
    return np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t], axis=1)


def lobe_pdf(wi: np.ndarray, wo: np.ndarray, alpha: float) -> np.ndarray:
    """Density of ω_o = reflect(ω_i, h), h ~ D(h) cos θ_h: D cos θ_h / (4 ω_o·h)."""
    h = wi + wo
    norm = np.linalg.norm(h, axis=1, keepdims=True)
    h = h / np.maximum(norm, 1e-30)
    o_dot_h = np.sum(wo * h, axis=1)
    valid = (norm[:, 0] > 1e-12) & (o_dot_h > 0)
    return np.where(valid, ggx_d(h[:, 2], alpha) * h[:, 2] / (4.0 * np.maximum(o_dot_h, 1e-30)),
                    0.0)


def pairs(metric: str, viewers: tuple[int, int], uniform: tuple[int, int], lobe: int,
          seed: int = SEED) -> Pairs:
    """The direction pairs of ``metric`` (see the module docstring): for each
    of the viewers, ``uniform`` stratified lights and ``lobe`` mirror-guided
    lights per roughness in LOBE_ALPHAS."""
    if metric not in METRICS:
        raise ValueError(f"unknown metric {metric!r}; valid: {', '.join(METRICS)}")
    rng = np.random.default_rng(seed)
    view = uniform_hemisphere(stratified(*viewers, rng))
    n_v, n_u = len(view), uniform[0] * uniform[1]
    side = max(1, int(round(math.sqrt(lobe))))
    n_l = side * side if lobe > 0 else 0
    wi_all, wo_all, w_all, shown_all = [], [], [], []
    for wi in view:
        lights = [uniform_hemisphere(stratified(*uniform, rng))]
        for alpha in (LOBE_ALPHAS if n_l else ()):
            h = ggx_half_vectors(stratified(side, side, rng), alpha)
            lights.append(2.0 * (h @ wi)[:, None] * h - wi)        # reflect ω_i about h
        wo = np.concatenate(lights)
        wo = wo[wo[:, 2] > COS_MIN]
        wi_rep = np.broadcast_to(wi, wo.shape)
        # Balance heuristic: 1 / Σ_k n_k p_k(ω_o).
        mixture = n_u / (2.0 * math.pi) + sum(n_l * lobe_pdf(wi_rep, wo, a)
                                              for a in (LOBE_ALPHAS if n_l else ()))
        w = (2.0 * math.pi / n_v) / mixture                      # 1/(n_v p(ω_i)) · 1/mixture
        cos_i, cos_o = wi[2], wo[:, 2]
        if metric == "cosine":
            shown = w * cos_i                 # eval itself, over the pixels that see θ_i
            w = w * cos_i / cos_o             # (eval)² = f² cos²θ_o -> f² cos θ_i cos θ_o
        else:
            limit = math.cos(math.radians(NGAN_MAX_DEG))
            w = w * ((cos_i >= limit) & (cos_o >= limit))
            shown = w
        keep = w > 0
        wi_all.append(wi_rep[keep])
        wo_all.append(wo[keep])
        w_all.append(w[keep])
        shown_all.append(shown[keep])
    return Pairs(*(np.concatenate(a) for a in (wi_all, wo_all, w_all, shown_all)))


def compress(x, objective: str):
    """The objective's compression of eval values (NumPy or Dr.Jit, per channel):
    ``cbrt`` the cube root (the lightness response: CIE L* grows as Y^(1/3);
    Fores, Ferwerda & Gu 2012 found a cube-root metric the closest to what
    observers judge among the RMS metrics of BRDF fitting), ``log`` a
    logarithm, ``linear`` none (the metric itself). A floor keeps the slope at
    0 finite: a model value of 0 still gets a gradient."""
    if objective not in OBJECTIVES:
        raise ValueError(f"unknown objective {objective!r}; valid: {', '.join(OBJECTIVES)}")
    if objective == "linear":
        return x
    if isinstance(x, np.ndarray):
        x = np.maximum(x, 0.0)
        if objective == "cbrt":
            return np.cbrt(x + CBRT_FLOOR) - CBRT_FLOOR ** (1.0 / 3.0)
        return np.log1p(x / LOG_FLOOR)
    x = dr.fmax(x, 0.0)
    if objective == "cbrt":
        return dr.cbrt(x + CBRT_FLOOR) - CBRT_FLOOR ** (1.0 / 3.0)
    return dr.log(1.0 + x / LOG_FLOOR)
