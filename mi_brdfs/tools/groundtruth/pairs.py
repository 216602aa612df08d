"""The walk's BRDF at pairs of directions, and cook_torrance's directional
lobe against it: the reference of ``tests/bsdfs/test_directional.py``
(``python -m mi_brdfs.tools.groundtruth --directional -o FILE``) and its
residual table (``--reference FILE --residuals``).

**The pairs.** θ_i <= θ_o in :data:`PAIR_THETAS` (degrees; 60, 80 and 87 lie
between the table's cos θ nodes), ω_i at azimuth 0 and ω_o at Δφ
(:data:`PAIR_AZIMUTHS`: 0 the retro-reflection side, 180 the mirror side).
Grazing pairs (either angle >= 75°) at every Δφ, the others at 0, 90 and
180; a pair with θ_i = 0 at Δφ = 0 only (the azimuth is then meaningless).
The walk from ω_i (the less grazing end) toward ω_o: its bounces k >= 2 by
next-event estimation (:func:`.walk.walk`, ``orders=(2, MAX_ORDER)``, with
their standard error), one walk for every F0 of :data:`PAIR_F0S`; the first
bounce in closed form (:func:`.microsurface.single_scattering`).

**The hemisphere's L1.** ∫∫ |f - f_walk| cos θ_i cos θ_o dω_i dω_o over
∫∫ f_walk cos θ_i cos θ_o, per distribution, α and F0, for the directional
and the separable lobe. The NumPy walk is too slow for a quadrature over
every pair; the numerator takes the Dr.Jit walk (``cook_torrance`` with
``multiple_scattering="walk"``, :mod:`mi_brdfs.bsdfs.walk`, which
``tests/bsdfs/test_walk_rung.py`` holds to the NumPy walk): jittered strata
of (cos θ_i, cos θ_o, Δφ), each with ``L1_LANES`` walk evaluations. The
denominator is 2π ∫ cos θ W(θ) dcos θ with W the NumPy walk's albedo
(Gauss-Legendre in cos θ). The walk's noise lifts an L1 (|d + ε| >= |d| on
average); ``noise`` is that lift where d = 0, measured from the two halves
of each stratum's lanes (half their mean |difference|), and ``error`` the
standard error of the quadrature (the strata's spread).
"""
from __future__ import annotations

import math

import numpy as np

import drjit as dr
import mitsuba as mi

from ..._jit import from_numpy
from .microsurface import DISTRIBUTIONS, d, dot, fresnel, lam, normalize, single_scattering
from .walk import MAX_ORDER, albedo, directions, walk

PAIR_THETAS = (0, 30, 60, 75, 80, 85, 87)
PAIR_AZIMUTHS = (0, 90, 150, 170, 175, 178, 180)
PAIR_AZIMUTHS_FEW = (0, 90, 180)           # of the pairs that are not grazing
PAIR_ALPHAS = (0.05, 0.1, 0.3, 0.6, 1.0, 2.0)
PAIR_F0S = (1.0, 0.5, 0.2)
GRAZING = 75                               # degrees: a pair is grazing if either angle is
PAIR_SEED = 3636                           # not the tables' seed: independent paths
L1_STRATA = (12, 12, 24)                   # (cos θ_i, cos θ_o, Δφ in [0, π])
L1_LANES = 4096                            # walk evaluations per stratum
L1_BATCH = 1 << 21                         # lanes per Dr.Jit call
L1_MUS = 24                                # Gauss-Legendre nodes of the albedo's integral
NONE, SOME = 1e-4, 1e-2                    # the walk's k >= 2 "none" and "some" (of its largest)
DIRECTIONAL_PATHS = 400_000                # paths per pair: where the walk has "some" at a
                                           # grazing pair its standard error is below 0.16 of it
COMPENSATIONS = ("directional", "separable")


def pair_grid() -> list[tuple[int, int, int]]:
    """(θ_i, θ_o, Δφ) in degrees, θ_i <= θ_o (see the module doc)."""
    out = []
    for k, ti in enumerate(PAIR_THETAS):
        for to in PAIR_THETAS[k:]:
            grazing = max(ti, to) >= GRAZING
            dphis = (0,) if ti == 0 else PAIR_AZIMUTHS if grazing else PAIR_AZIMUTHS_FEW
            out += [(ti, to, p) for p in dphis]
    return out


def pair_vectors(pairs) -> tuple[np.ndarray, np.ndarray]:
    """ω_i (azimuth 0) and ω_o (azimuth Δφ) of (θ_i, θ_o, Δφ) rows, (N, 3) each."""
    p = np.radians(np.asarray(pairs, dtype=np.float64))
    return directions(np.cos(p[:, 0])), directions(np.cos(p[:, 1]), p[:, 2])


def config(distribution: str, alpha: float, f0, compensation: str = "directional") -> dict:
    """cook_torrance with Smith's G, k = 0, m_S = 1 and energy compensation;
    ``f0`` a number or an RGB list."""
    f0 = {"type": "rgb", "value": list(f0)} if isinstance(f0, (list, tuple)) else f0
    return {"type": "cook_torrance", "distribution": distribution, "geometry": "smith",
            "alpha": alpha, "k": 0.0, "f0": f0, "specular_reflectance": 1.0,
            "energy_compensation": True, "compensation": compensation}


def _round(x: np.ndarray) -> list:
    return [[float(f"{v:.7g}") for v in row] for row in x]


def hemisphere_l1(distribution: str, alpha: float, paths: int, seed: int = PAIR_SEED,
                  strata=L1_STRATA, lanes: int = L1_LANES, log=None) -> dict:
    """The hemisphere's L1 of each of :data:`COMPENSATIONS` against the walk
    (see the module doc), per F0 of :data:`PAIR_F0S` (the three colour
    channels of one walk): {compensation: [...], "noise": [...], "error":
    {compensation: [...]}, "albedo_integral": [...]}. ``paths`` per albedo node."""
    # the denominator: 2π ∫ μ W(μ) dμ by Gauss-Legendre
    x, w = np.polynomial.legendre.leggauss(L1_MUS)
    mus, weights = 0.5 * (x + 1.0), 0.5 * w
    walked = albedo(distribution, mus, alpha, PAIR_F0S, paths, seed)        # [μ][F0]
    integral = (weights * mus) @ walked                                      # ∫ μ W dμ
    # the numerator: jittered strata of (μ_i, μ_o, Δφ)
    ni, no, nphi = strata
    rng = np.random.default_rng((seed, int(alpha * 1000), DISTRIBUTIONS.index(distribution)))
    cell = np.arange(ni * no * nphi)
    mu_i = (cell // (no * nphi) + rng.random(cell.size)) / ni
    mu_o = (cell // nphi % no + rng.random(cell.size)) / no
    dphi = (cell % nphi + rng.random(cell.size)) / nphi * math.pi
    wi, wo = directions(mu_i), directions(mu_o, dphi)
    plugins = {c: mi.load_dict(config(distribution, alpha, PAIR_F0S, c)) for c in COMPENSATIONS}
    walker = mi.load_dict({k: v for k, v in config(distribution, alpha, PAIR_F0S).items()
                           if k not in ("energy_compensation", "compensation")}
                          | {"multiple_scattering": "walk"})
    ctx = mi.BSDFContext()
    half = np.zeros((2, cell.size, len(PAIR_F0S)))
    values = {c: np.zeros((cell.size, len(PAIR_F0S))) for c in COMPENSATIONS}
    per_call = max(L1_BATCH // lanes, 1)
    for start in range(0, cell.size, per_call):
        part = slice(start, min(start + per_call, cell.size))
        n = part.stop - part.start
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = from_numpy(mi.Vector3f, wi[part].T)
        v = from_numpy(mi.Vector3f, wo[part].T)
        for c, bsdf in plugins.items():
            values[c][part] = np.array(bsdf.eval(ctx, si, v)).T
        si = dr.zeros(mi.SurfaceInteraction3f, n * lanes)
        si.wi = from_numpy(mi.Vector3f, np.repeat(wi[part], lanes, 0).T)
        si.uv = from_numpy(mi.Point2f, rng.random((2, n * lanes)))
        f = np.array(walker.eval(ctx, si, from_numpy(mi.Vector3f, np.repeat(wo[part], lanes, 0).T)))
        f = f.T.reshape(n, 2, lanes // 2, len(PAIR_F0S)).mean(axis=2)      # [stratum][half][F0]
        half[:, part] = f.transpose(1, 0, 2)
    f_walk = half.mean(axis=0)
    # 2π ∫dμ_i μ_i ∫dμ_o ∫_0^2π dΔφ |Δ eval| over 2π ∫ μ W dμ: 2π mean(|Δ| μ_i) / ∫ μ W
    scale = 2.0 * math.pi * mu_i[:, None] / integral
    out = {"albedo_integral": integral.tolist(), "error": {}}
    for c in COMPENSATIONS:
        terms = np.abs(values[c] - f_walk) * scale
        out[c] = terms.mean(axis=0).tolist()
        out["error"][c] = (terms.std(axis=0) / math.sqrt(cell.size)).tolist()
    out["noise"] = (0.5 * np.abs(half[0] - half[1]) * scale).mean(axis=0).tolist()
    if log:
        log(f"{distribution}, alpha {alpha}: L1 " + ", ".join(
            f"{c} {100 * out[c][0]:.2f} %" for c in COMPENSATIONS)
            + f" (F0 1; noise {100 * out['noise'][0]:.2f} %)")
    return out


def directional_reference(paths: int = DIRECTIONAL_PATHS, log=None,
                          l1_paths: int = 50_000) -> dict:
    """The walk at :func:`pair_grid` for every distribution, α and F0, and the
    hemisphere's L1 of both lobes (module doc):
    ``ref[distribution]["single" | "multiple" | "error"][alpha][pair][f0]``
    (f·cos θ_o of the closed-form first bounce, of the bounces k >= 2 and their
    standard error), ``ref["l1"][distribution][alpha]`` (:func:`hemisphere_l1`)."""
    pairs = pair_grid()
    wi, wo = pair_vectors(pairs)
    out = {"paths": paths, "seed": PAIR_SEED, "pairs": [list(p) for p in pairs],
           "alpha": list(PAIR_ALPHAS), "f0": list(PAIR_F0S),
           "l1_strata": list(L1_STRATA), "l1_lanes": L1_LANES, "l1_paths": l1_paths}
    f0s = np.array(PAIR_F0S)
    for distribution in DISTRIBUTIONS:
        rows = {"single": [], "multiple": [], "error": []}
        for alpha in PAIR_ALPHAS:
            walked = walk(distribution, wi, alpha, f0s, PAIR_SEED, paths, wo=wo,
                          orders=(2, MAX_ORDER))
            single = np.stack([single_scattering(distribution, wi, wo, alpha, f) for f in f0s], 1)
            rows["single"].append(_round(single))
            rows["multiple"].append(_round(walked.value))
            rows["error"].append(_round(walked.value_error))
            if log:
                log(f"{distribution}: alpha {alpha} walked at {len(pairs)} pairs")
        out[distribution] = rows
    out["l1"] = {distribution: [hemisphere_l1(distribution, alpha, l1_paths, log=log)
                                for alpha in PAIR_ALPHAS] for distribution in DISTRIBUTIONS}
    return out


# ----------------------------------------------------------------------------
#  The residual table
# ----------------------------------------------------------------------------

def separable_single(distribution: str, wi, wo, alpha, f0):
    """f·cos θ_o of the uncompensated lobe, G1(ω_i) G1(ω_o) (roughconductor's)."""
    h = normalize(wi + wo)
    with np.errstate(divide="ignore", invalid="ignore"):
        g = 1.0 / ((1.0 + lam(distribution, wi, alpha)) * (1.0 + lam(distribution, wo, alpha)))
        value = fresnel(f0, dot(wi, h)) * d(distribution, h, alpha) * g / (4.0 * wi[..., 2])
    return np.nan_to_num(value)


def plugin_multiple(distribution: str, alpha: float, compensation: str, wi, wo) -> np.ndarray:
    """The plugin's eval less its single scattering (the height-correlated one
    for the directional lobe, G1·G1 for the separable), per F0 of
    :data:`PAIR_F0S`: (N, F0)."""
    bsdf = mi.load_dict(config(distribution, alpha, PAIR_F0S, compensation))
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = from_numpy(mi.Vector3f, wi.T)
    value = np.array(bsdf.eval(mi.BSDFContext(), si, from_numpy(mi.Vector3f, wo.T))).T
    single = single_scattering if compensation == "directional" else separable_single
    return value - np.stack([single(distribution, wi, wo, alpha, f) for f in PAIR_F0S], 1)


def grazing_rule(ref: dict, distribution: str, a: int, compensation: str) -> dict:
    """At the grazing pairs of ``ref`` (both orders of each), in f = value /
    cos θ_o per F0: the largest of the plugin's k >= 2 where the walk has none
    (< NONE of its largest), over the walk's largest ("none", the test's
    bound: SOME), and the least ratio plugin / walk where the walk has some
    (>= SOME of its largest; the walk less 3 of its standard errors; "some",
    the test's bound: 0.5), and the largest there (the walk plus 3 standard
    errors; "most", the test's bound: 2)."""
    pairs = np.array(ref["pairs"], dtype=np.float64)
    grazing = pairs[:, :2].max(axis=1) >= GRAZING
    wi, wo = pair_vectors(pairs[grazing])
    walk_value = np.array(ref[distribution]["multiple"][a])[grazing] / wo[:, 2:]   # f
    error = np.array(ref[distribution]["error"][a])[grazing] / wo[:, 2:]
    low, high = walk_value - 3.0 * error, walk_value + 3.0 * error
    alpha = ref["alpha"][a]
    top = walk_value.max(axis=0)
    none = some = most = None
    for x, y in ((wi, wo), (wo, wi)):                  # f is reciprocal: both orders
        f = plugin_multiple(distribution, alpha, compensation, x, y) / y[:, 2:]
        n = np.where(walk_value < NONE * top, np.abs(f), 0.0).max(axis=0) / top
        has = walk_value >= SOME * top
        ratio = np.where(has, f / np.maximum(low, 1e-300), np.inf)
        above = np.where(has, f / np.maximum(high, 1e-300), 0.0).max(axis=0)
        most = above if most is None else np.maximum(most, above)
        none = n if none is None else np.maximum(none, n)
        some = ratio.min(axis=0) if some is None else np.minimum(some, ratio.min(axis=0))
    return {"none": none.tolist(), "some": some.tolist(), "most": most.tolist()}


def print_directional_residuals(ref: dict) -> None:
    """The residual table of a reference written by :func:`directional_reference`."""
    print(f"cook_torrance (Smith G, k 0, m_S 1, energy_compensation) against the walk, F0 in "
          f"{ref['f0']}, the worst over them. L1: over the hemisphere of pairs, "
          "∫∫|f - f_walk| cos θ_i cos θ_o / ∫∫ f_walk cos θ_i cos θ_o (Dr.Jit walk, "
          f"{ref['l1_strata']} strata x {ref['l1_lanes']} lanes; noise: its lift by the walk's "
          "noise). Grazing pairs (either angle >= 75 deg): 'none' the plugin's k >= 2 where "
          f"the walk's is < {NONE:g} of its largest, over that largest (bound {SOME:g}); "
          f"'some' the least plugin / (walk - 3 standard errors) where the walk's is >= "
          f"{SOME:g} of its largest (bound 0.5), 'most' the largest plugin / (walk + 3 standard "
          "errors) there (bound 2)")
    print("D         alpha | directional: L1      none  some   most | separable: L1       none  "
          "some   most | L1 noise")
    for distribution in DISTRIBUTIONS:
        for a, alpha in enumerate(ref["alpha"]):
            l1 = ref["l1"][distribution][a]
            cells = []
            for c in COMPENSATIONS:
                g = grazing_rule(ref, distribution, a, c)
                cells.append(f"{100 * max(l1[c]):6.2f} % {max(g['none']):8.2g} "
                             f"{min(g['some']):5.2f} {max(g['most']):6.3g}")
            print(f"{distribution:9} {alpha:5g} |    {cells[0]} |  {cells[1]} | "
                  f"{100 * max(l1['noise']):.2f} %")
