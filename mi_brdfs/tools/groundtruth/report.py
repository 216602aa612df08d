"""What is measured against the random walk: its reference albedos, the
compensated plugins' residuals, BRDF slices and the validation report's
section (``mi-brdfs validate``, section 5)."""
from __future__ import annotations

import html
import math
import os

import numpy as np

import drjit as dr
import mitsuba as mi

from ..._jit import from_numpy
from ..analysis import eval_at_viewer, plane_of_incidence
from .microsurface import DISTRIBUTIONS, Alpha
from .walk import MAX_ORDER, albedo, brdf

REFERENCE_ALPHAS = (0.05, 0.1, 0.2, 0.3, 0.45, 0.6, 0.8, 1.0, 1.5, 3.0)
REFERENCE_F0S = (0.0, 0.1, 0.3, 0.45, 0.6, 0.7, 0.8, 0.9, 0.95, 1.0)
REFERENCE_THETAS = (0, 15, 30, 45, 60, 70, 75, 80, 85)
REFERENCE_SEED = 4242            # not the tables' seed: independent paths
# Anisotropic roughness: every ordered pair (alpha_u, alpha_v) of these, seen along
# (phi 0) and across (phi 90°) the tangent; between the tables' nodes but for 1
ANISOTROPIC_ALPHAS = (0.05, 0.15, 0.3, 0.5, 0.8, 1.0)
ANISOTROPIC_PHIS = (0, 90)
ROUNDING = 1e-6 / math.sqrt(12)  # the standard deviation of the stored values' rounding


def reference(paths: int = 100_000, log=None) -> dict:
    """The walk's albedo at REFERENCE_THETAS x REFERENCE_ALPHAS x REFERENCE_F0S
    (between the tables' nodes), for each distribution."""
    out = {"paths": paths, "seed": REFERENCE_SEED, "theta": list(REFERENCE_THETAS),
           "alpha": list(REFERENCE_ALPHAS), "f0": list(REFERENCE_F0S)}
    for distribution in DISTRIBUTIONS:
        rows = []
        for theta in REFERENCE_THETAS:
            mu = math.cos(math.radians(theta))
            rows.append(albedo(distribution, mu, np.array(REFERENCE_ALPHAS), REFERENCE_F0S,
                               paths, REFERENCE_SEED).round(6).tolist())
            if log:
                log(f"{distribution}: theta {theta}")
        out[distribution] = rows                       # [theta][alpha][f0]
    return out


def reference_anisotropic(paths: int = 100_000, log=None) -> dict:
    """The walk's albedo for anisotropic roughness at REFERENCE_THETAS x
    ANISOTROPIC_PHIS x (alpha_u, alpha_v) in ANISOTROPIC_ALPHAS² x REFERENCE_F0S,
    for each distribution: ``ref[distribution][theta][phi][alpha_u][alpha_v][f0]``."""
    out = {"paths": paths, "seed": REFERENCE_SEED, "theta": list(REFERENCE_THETAS),
           "phi": list(ANISOTROPIC_PHIS), "alpha": list(ANISOTROPIC_ALPHAS),
           "f0": list(REFERENCE_F0S)}
    phi, au, av = np.meshgrid(np.radians(ANISOTROPIC_PHIS), ANISOTROPIC_ALPHAS,
                              ANISOTROPIC_ALPHAS, indexing="ij")
    for distribution in DISTRIBUTIONS:
        rows = []
        for theta in REFERENCE_THETAS:
            w = albedo(distribution, math.cos(math.radians(theta)), Alpha(au.ravel(), av.ravel()),
                       REFERENCE_F0S, paths, REFERENCE_SEED, phi=phi.ravel())
            rows.append(w.reshape(phi.shape + (len(REFERENCE_F0S),)).round(6).tolist())
            if log:
                log(f"{distribution}: theta {theta}")
        out[distribution] = rows
    return out


# The other Fresnel forms of cook_torrance, walked with that Fresnel at every bounce
# (one column per colour channel): Mitsuba's measured conductors as the RGB
# variants hold them, F82-tint, a dielectric and the white conductor (F = 1).
FRESNEL_ALPHAS = (0.1, 0.2, 0.3, 0.5, 0.7, 1.0)
FRESNEL_THETAS = (0, 30, 45, 60, 70, 80, 85)
FRESNEL_MATERIALS = ("Au", "Cu", "Al")
FRESNEL_F82 = ({"fresnel": "f82", "f0": 0.9, "f82_tint": [1.0, 0.9, 0.8]},      # mild dips
               {"fresnel": "f82", "f0": 0.9, "f82_tint": [0.9, 0.6, 0.2]})      # strong ones
FRESNEL_DIELECTRIC = {"fresnel": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}


def fresnel_forms() -> list[dict]:
    """The forms of :func:`fresnel_reference`: each a name, the plugin
    parameters that select it (explicit numbers: ``eta`` and ``kappa`` of a
    ``material`` as ``roughconductor`` reduces them to RGB in the active RGB variant)."""
    from ...bsdfs.cook_torrance import material_textures
    si = dr.zeros(mi.SurfaceInteraction3f)
    forms = []
    for name in FRESNEL_MATERIALS:
        eta, kappa = ([float(x) for x in np.array(t.eval(si)).ravel()]
                      for t in material_textures(name))
        forms.append({"name": name, "params": {"fresnel": "conductor", "eta": eta,
                                               "kappa": kappa}})
    forms += [{"name": name, "params": p} for name, p in zip(("F82 mild", "F82 strong"),
                                                             FRESNEL_F82)]
    forms.append({"name": "dielectric 1.5", "params": FRESNEL_DIELECTRIC})
    forms.append({"name": "white", "params": {"fresnel": "conductor", "eta": 0.0, "kappa": 1.0}})
    return forms


def fresnel_columns(params: dict) -> list:
    """The walk's Fresnel functions (NumPy, one per channel) of a form's parameters."""
    from .microsurface import conductor, dielectric, f82
    rgb = lambda x: x if isinstance(x, list) else [x] * 3
    form = params["fresnel"]
    if form == "conductor":
        if params["eta"] == 0.0 and params["kappa"] == 1.0:
            return [1.0]                                 # the perfect conductor: F = 1
        return [lambda c, e=e, k=k: conductor(e, k, c)
                for e, k in zip(rgb(params["eta"]), rgb(params["kappa"]))]
    if form == "dielectric":
        return [lambda c: dielectric(params["int_ior"] / params["ext_ior"], c)]
    return [lambda c, f=f, t=t: f82(f, t, c)
            for f, t in zip(rgb(params["f0"]), rgb(params["f82_tint"]))]


def fresnel_reference(paths: int = 100_000, log=None) -> dict:
    """The walk's albedo with each of :func:`fresnel_forms` at every bounce, at
    FRESNEL_THETAS x FRESNEL_ALPHAS, for each distribution:
    ``ref["forms"][i]["walk"][distribution][theta][alpha][channel]``."""
    forms = fresnel_forms()
    out = {"paths": paths, "seed": REFERENCE_SEED, "theta": list(FRESNEL_THETAS),
           "alpha": list(FRESNEL_ALPHAS), "forms": forms}
    columns = [fresnel_columns(f["params"]) for f in forms]
    flat = [c for cs in columns for c in cs]                 # one walk serves every column
    for f in forms:
        f["walk"] = {}
    for distribution in DISTRIBUTIONS:
        rows = []
        for theta in FRESNEL_THETAS:
            mu = math.cos(math.radians(theta))
            rows.append(albedo(distribution, mu, np.array(FRESNEL_ALPHAS), flat, paths,
                               REFERENCE_SEED).round(6))
            if log:
                log(f"{distribution}: theta {theta}")
        w = np.array(rows)                                   # [theta][alpha][column]
        start = 0
        for f, cs in zip(forms, columns):
            f["walk"][distribution] = w[:, :, start:start + len(cs)].tolist()
            start += len(cs)
    return out


def fresnel_config(form: dict, distribution: str, alpha: float,
                   compensation: str = "auto") -> dict:
    """The compensated cook_torrance (k = 0, m_S = 1, Smith G) of one form of
    :func:`fresnel_forms` (its lists as RGB colours), with the lobe
    ``compensation`` (the plugin's option)."""
    params = {k: {"type": "rgb", "value": v} if isinstance(v, list) else v
              for k, v in form["params"].items()}
    return {"type": "cook_torrance", "distribution": distribution, "geometry": "smith",
            "alpha": alpha, "k": 0.0, "specular_reflectance": 1.0,
            "energy_compensation": True, "compensation": compensation, **params}


def residuals_fresnel(ref: dict, n: int = 512) -> list[dict]:
    """Each form of ``ref`` (:func:`fresnel_reference`) and distribution: the
    compensated plugin's albedo against the walk's, per channel, the largest
    relative difference and where (RGB variants)."""
    out = []
    for form in ref["forms"]:
        for distribution in DISTRIBUTIONS:
            worst = (-1.0, None)
            for a, alpha in enumerate(ref["alpha"]):
                config = fresnel_config(form, distribution, alpha)
                for t, theta in enumerate(ref["theta"]):
                    w = np.array(form["walk"][distribution][t][a])
                    e = np.array([compensated_albedo(config, (theta,), n, channel=c)[0]
                                  for c in range(len(w))])
                    r = float(np.max(np.abs(e - w) / w))
                    if r > worst[0]:
                        worst = (r, (alpha, theta, e.round(4).tolist(), w.tolist()))
            out.append({"form": form["name"], "distribution": distribution,
                        "relative": worst[0], "at": worst[1]})
    return out


def reference_agreement(ref: dict, paths: int, seed: int = REFERENCE_SEED + 1,
                        log=None, thetas=None, alphas=None) -> dict:
    """The reference albedos ``ref`` (as :func:`reference` writes them) against
    a walk of their points with ``paths`` paths and another seed, per
    distribution, in standard errors of the difference: the path weights'
    spread s, measured by the new walk, gives s / sqrt(paths) and
    s / sqrt(ref["paths"]). ``thetas``, ``alphas``: only these of ref's points."""
    thetas = ref["theta"] if thetas is None else thetas
    alphas = ref["alpha"] if alphas is None else alphas
    t_rows = [ref["theta"].index(t) for t in thetas]
    a_rows = [ref["alpha"].index(a) for a in alphas]
    out = {}
    for distribution in DISTRIBUTIONS:
        stored = np.array(ref[distribution])[np.ix_(t_rows, a_rows)]   # [theta][alpha][f0]
        new = np.empty_like(stored)
        err = np.empty_like(stored)
        for k, theta in enumerate(thetas):
            new[k], err[k] = albedo(distribution, math.cos(math.radians(theta)),
                                    np.array(alphas), ref["f0"], paths, seed, error=True)
            if log:
                log(f"{distribution}: theta {theta}")
        # both walks' noise, and the stored values' rounding to 1e-6 (uniform: 1e-6 / sqrt 12)
        sigma = np.sqrt(err ** 2 * (1.0 + paths / ref["paths"]) + ROUNDING ** 2)
        diff = np.abs(new - stored)
        z = diff / sigma
        k = np.unravel_index(np.argmax(diff), diff.shape)
        out[distribution] = {"points": int(diff.size), "seed": seed,
                             "largest": float(diff[k]), "largest_z": float(z[k]),
                             "worst_z": float(z.max()), "rms_z": float(np.sqrt(np.mean(z * z))),
                             "z": z}
    return out


def compensated_albedo(config: dict, thetas, n: int = 1024, seed: int = 7,
                       phi: float = 0.0, channel: int = 0) -> np.ndarray:
    """The albedo of a plugin configuration (white m_S: the first channel, or ``channel``) at
    each angle (degrees; the viewer at azimuth ``phi`` degrees from the
    tangent): 2π times the mean of eval over n² jittered strata of the square
    mapped to the hemisphere by Mitsuba's equal-area (concentric) map, which
    resolves a narrow lobe anywhere alike."""
    rng = np.random.default_rng(seed)
    i, j = (a.ravel() for a in np.meshgrid(np.arange(n), np.arange(n), indexing="ij"))
    u = from_numpy(mi.Point2f, ((i + rng.random(i.size)) / n, (j + rng.random(j.size)) / n))
    wo = mi.warp.square_to_uniform_hemisphere(u)
    bsdf = mi.load_dict(config)
    out = []
    for theta in thetas:
        t, p = math.radians(theta), math.radians(phi)
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(*(dr.opaque(mi.Float, c) for c in (
            math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t))))
        value = bsdf.eval(mi.BSDFContext(), si, wo)
        out.append(float(dr.sum(mi.Float64(value[channel]))[0]) * 2.0 * math.pi / (n * n))
    return np.array(out)


def residuals(ref: dict, distribution: str, geometry: str, alpha_max: float = 1.0) -> dict:
    """The compensated cook_torrance (k = 0, m_S = 1) against the walk of
    ``ref`` for every angle, alpha <= alpha_max and F0: the largest relative
    and absolute differences (relative: where the walk reflects >= 1 %), and
    where."""
    smith = "ggx" if distribution == "ggx" else "beckmann"
    thetas = ref["theta"]
    walk_values = np.array(ref[smith])                          # [theta][alpha][f0]
    worst = {"relative": 0.0, "absolute": 0.0, "at": None}
    for a, alpha in enumerate(ref["alpha"]):
        if alpha > alpha_max:
            continue
        for j, f0 in enumerate(ref["f0"]):
            config = {"type": "cook_torrance", "distribution": distribution,
                      "geometry": geometry, "alpha": alpha, "k": 0.0, "f0": f0,
                      "specular_reflectance": 1.0, "energy_compensation": True}
            e = compensated_albedo(config, thetas)
            w = walk_values[:, a, j]
            diff = np.abs(e - w)
            rel = np.where(w >= 0.01, diff / np.maximum(w, 1e-12), 0.0)
            k = int(np.argmax(rel))
            if rel[k] > worst["relative"]:
                worst.update(relative=float(rel[k]), at=(alpha, f0, thetas[k], float(e[k]),
                                                         float(w[k])))
            worst["absolute"] = max(worst["absolute"], float(diff.max()))
    return worst


def residuals_anisotropic(ref: dict, distribution: str, geometry: str, n: int = 512) -> dict:
    """The compensated anisotropic cook_torrance (k = 0, m_S = 1) against the
    walk of ``ref`` (:func:`reference_anisotropic`) at every angle, azimuth,
    (alpha_u, alpha_v) and F0: the largest relative and absolute differences
    (relative: where the walk reflects >= 1 %), and where, per azimuth
    (``by_phi``), and where it reflects >= 3 % (``relative_3``); and the
    largest relative difference of single scattering
    alone. ``n``² strata per albedo (:func:`compensated_albedo`)."""
    thetas, walk_values = ref["theta"], np.array(ref[distribution])   # [θ][φ][α_u][α_v][F0]
    worst = {"relative": 0.0, "absolute": 0.0, "at": None, "single": 0.0,
             "by_phi": {phi: 0.0 for phi in ref["phi"]}, "relative_3": 0.0}
    for u, alpha_u in enumerate(ref["alpha"]):
        for v, alpha_v in enumerate(ref["alpha"]):
            for j, f0 in enumerate(ref["f0"]):
                config = {"type": "cook_torrance", "distribution": distribution,
                          "geometry": geometry, "alpha_u": alpha_u, "alpha_v": alpha_v,
                          "k": 0.0, "f0": f0, "specular_reflectance": 1.0}
                for k, phi in enumerate(ref["phi"]):
                    w = walk_values[:, k, u, v, j]
                    e = compensated_albedo({**config, "energy_compensation": True}, thetas,
                                           n=n, phi=phi)
                    diff = np.abs(e - w)
                    rel = np.where(w >= 0.01, diff / np.maximum(w, 1e-12), 0.0)
                    m = int(np.argmax(rel))
                    worst["by_phi"][phi] = max(worst["by_phi"][phi], float(rel[m]))
                    worst["relative_3"] = max(worst["relative_3"],
                                              float(np.max(np.where(w >= 0.03, rel, 0.0))))
                    if rel[m] > worst["relative"]:
                        worst.update(relative=float(rel[m]), at=(
                            alpha_u, alpha_v, f0, thetas[m], phi, float(e[m]), float(w[m])))
                    worst["absolute"] = max(worst["absolute"], float(diff.max()))
                    if f0 in (0.0, 0.6, 1.0):    # single scattering alone, for scale
                        single = compensated_albedo(config, thetas, n=n, phi=phi)
                        worst["single"] = max(worst["single"], float(np.max(np.where(
                            w >= 0.01, np.abs(single - w) / np.maximum(w, 1e-12), 0.0))))
    return worst


# ----------------------------------------------------------------------------
#  The validation report's section (mi-brdfs validate)
# ----------------------------------------------------------------------------

REPORT_THETAS = (0, 15, 30, 45, 60, 70, 75, 80, 85)
REPORT_CASES = ((0.3, 0.3), (0.3, 1.0), (1.0, 0.3), (1.0, 1.0))     # (alpha, F0)
# The largest relative difference (where the walk reflects >= 1 %) each D x G may
# show against the walk of its nearest Smith microsurface, alpha <= 1, F0 in [0, 1],
# 0-85°: 3 % for Smith G (the goal); Blinn's and the V-cavity's own single
# scattering differ more (measured with python -m mi_brdfs.tools.groundtruth
# --reference tests/bsdfs/walk_reference.json --residuals: 1.4 %, 2.0 %, 8.8 %,
# 318 %, 160 %, 127 %; the V-cavity's worst at F0 = 0, 85°, where its single
# scattering alone reflects more than the walk).
RESIDUAL_BOUND = {("ggx", "smith"): 0.03, ("beckmann", "smith"): 0.03,
                  ("blinn", "smith"): 0.10, ("ggx", "cook_torrance"): 3.2,
                  ("beckmann", "cook_torrance"): 1.7, ("blinn", "cook_torrance"): 1.3}


def report_section(out: str, quick: bool = False, log=None) -> list[dict]:
    """Every compensated cook_torrance D x G against the random walk of its
    nearest Smith microsurface: albedo against angle (compensated and single
    scattering, white m_S, k = 0, at REPORT_CASES) and BRDF slices in the
    plane of incidence (α 0.6, F0 0.6). Writes one figure per D x G and one
    of slices; returns a row per D x G with its largest differences."""
    from matplotlib.figure import Figure    # the reports extra; no pyplot: no global backend
    paths = 4000 if quick else 40_000
    thetas = REPORT_THETAS[::2] if quick else REPORT_THETAS
    mus = np.cos(np.radians(thetas))
    rows = []
    for distribution in ("ggx", "beckmann", "blinn"):
        smith = "ggx" if distribution == "ggx" else "beckmann"
        walked = {a: albedo(smith, mus, a, sorted({f for _, f in REPORT_CASES}), paths, seed=3)
                  for a in sorted({a for a, _ in REPORT_CASES})}
        for geometry in ("smith", "cook_torrance"):
            fig = Figure(figsize=(5.2, 3.4), dpi=100)
            ax = fig.subplots()
            worst_rel = worst_abs = 0.0
            for k, (alpha, f0) in enumerate(REPORT_CASES):
                config = {"type": "cook_torrance", "distribution": distribution,
                          "geometry": geometry, "alpha": alpha, "k": 0.0, "f0": f0,
                          "specular_reflectance": 1.0}
                comp = compensated_albedo({**config, "energy_compensation": True}, thetas)
                single = compensated_albedo(config, thetas)
                w = walked[alpha][:, sorted({f for _, f in REPORT_CASES}).index(f0)]
                diff = np.abs(comp - w)
                worst_rel = max(worst_rel, float(np.max(np.where(w >= 0.01, diff / w, 0.0))))
                worst_abs = max(worst_abs, float(diff.max()))
                label = f"α {alpha:g}, F0 {f0:g}"
                ax.plot(thetas, w, "-", color=f"C{k}", lw=2.5, alpha=0.4, label=f"walk, {label}")
                ax.plot(thetas, comp, "o", color=f"C{k}", ms=3, label=f"compensated, {label}")
                ax.plot(thetas, single, ":", color=f"C{k}", lw=1)
            ax.set_xlabel(r"incident angle $\theta_i$ (degrees)")
            ax.set_ylabel("directional albedo")
            ax.set_title(f"cook_torrance {distribution}/{geometry} vs the walk on {smith}\n"
                         "(dotted: single scattering)", fontsize=8)
            ax.legend(fontsize=5.5, ncol=2)
            fig.tight_layout()
            plot = f"groundtruth_{distribution}_{geometry}.png"
            fig.savefig(os.path.join(out, plot))
            rows.append({"distribution": distribution, "geometry": geometry, "walk": smith,
                         "relative": worst_rel, "absolute": worst_abs,
                         "bound": RESIDUAL_BOUND[(distribution, geometry)],
                         "paths": paths, "plot": plot})
            if log:
                log(f"ground truth: {distribution}/{geometry}")
    # BRDF slices (f·cos θ_o in the plane of incidence): every D x G against the
    # walk of its nearest Smith microsurface (one walk per Smith distribution)
    fig = Figure(figsize=(11.0, 6.4), dpi=100)
    axes = fig.subplots(2, 3)
    slice_thetas, n = (30, 70), 61
    walked = {}
    for smith in DISTRIBUTIONS:
        for theta in slice_thetas:
            t = math.radians(theta)
            theta_o = np.radians(np.linspace(-89.5, 89.5, n))
            wo = np.stack([np.sin(theta_o), np.zeros(n), np.cos(theta_o)], axis=1)
            wi = np.repeat(np.array([[-math.sin(t), 0.0, math.cos(t)]]), n, axis=0)
            walked[smith, theta] = brdf(smith, wi, wo, 0.6, 0.6, paths=paths // 4, seed=9)
    for ax, (distribution, geometry) in zip(axes.ravel(), [
            (d, g) for g in ("smith", "cook_torrance") for d in ("ggx", "beckmann", "blinn")]):
        smith = "ggx" if distribution == "ggx" else "beckmann"
        config = {"type": "cook_torrance", "distribution": distribution, "geometry": geometry,
                  "alpha": 0.6, "k": 0.0, "f0": 0.6, "specular_reflectance": 1.0}
        for k, theta in enumerate(slice_thetas):
            theta_o, comp = plane_of_incidence(
                mi.load_dict({**config, "energy_compensation": True}), theta, n)
            _, single = plane_of_incidence(mi.load_dict(config), theta, n)
            deg = np.degrees(theta_o)
            ax.plot(deg, walked[smith, theta], "-", color=f"C{k}", lw=2.5, alpha=0.4,
                    label=rf"walk ({smith}), $\theta_i$ {theta}°")
            ax.plot(deg, comp, "--", color=f"C{k}", label=rf"compensated, $\theta_i$ {theta}°")
            ax.plot(deg, single, ":", color=f"C{k}", lw=1, label=rf"single, $\theta_i$ {theta}°")
        ax.set_title(f"{distribution}/{geometry}, α 0.6, F0 0.6", fontsize=9)
        ax.set_xlabel(r"$\theta_o$ in the plane of incidence (°; > 0: mirror side)", fontsize=8)
        ax.set_ylabel(r"$f\,\cos\theta_o$ (1/sr)", fontsize=8)
        ax.legend(fontsize=5.5)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "groundtruth_slices.png"))
    residual_map(os.path.join(out, RESIDUAL_MAP), paths, quick)
    return rows


RESIDUAL_MAP = "groundtruth_residuals.png"
MAP_ALPHAS = (0.05, 0.1, 0.2, 0.3, 0.45, 0.6, 0.8, 1.0)
MAP_F0S = (0.3, 1.0)


def residual_map(path: str, paths: int, quick: bool = False) -> np.ndarray:
    """The figure ``path``: compensated cook_torrance's albedo (white m_S,
    k = 0) minus the walk's on its own Smith microsurface, over the incident
    angle and α, for GGX and Beckmann with Smith's G at F0 0.3 and 1; the
    differences, [distribution][F0][α][θ]."""
    from matplotlib.figure import Figure
    thetas = REPORT_THETAS[::2] if quick else REPORT_THETAS
    alphas = MAP_ALPHAS[1::3] if quick else MAP_ALPHAS
    mus = np.cos(np.radians(thetas))
    diff = np.empty((2, len(MAP_F0S), len(alphas), len(thetas)))
    for d, distribution in enumerate(("ggx", "beckmann")):
        for a, alpha in enumerate(alphas):
            walked = albedo(distribution, mus, alpha, MAP_F0S, paths, seed=5)   # [θ][F0]
            for j, f0 in enumerate(MAP_F0S):
                config = {"type": "cook_torrance", "distribution": distribution,
                          "geometry": "smith", "alpha": alpha, "k": 0.0, "f0": f0,
                          "specular_reflectance": 1.0, "energy_compensation": True}
                diff[d, j, a] = compensated_albedo(config, thetas, n=512) - walked[:, j]
    top = max(float(np.abs(diff).max()), 1e-3)
    fig = Figure(figsize=(9.0, 6.0), dpi=100)
    axes = fig.subplots(2, len(MAP_F0S), sharex=True, sharey=True)
    for d, distribution in enumerate(("GGX", "Beckmann")):
        for j, f0 in enumerate(MAP_F0S):
            ax = axes[d, j]
            image = ax.imshow(diff[d, j], cmap="RdBu_r", vmin=-top, vmax=top, origin="lower",
                              aspect="auto")
            for (a, t), value in np.ndenumerate(diff[d, j]):
                ax.text(t, a, f"{1e3 * value:.1f}", ha="center", va="center", fontsize=6)
            ax.set_xticks(range(len(thetas)), [f"{t:g}" for t in thetas])
            ax.set_yticks(range(len(alphas)), [f"{x:g}" for x in alphas])
            ax.set_title(f"{distribution} × Smith, F0 {f0:g}", fontsize=9)
            if d == 1:
                ax.set_xlabel(r"incident angle $\theta_i$ (degrees)")
            if j == 0:
                ax.set_ylabel(r"roughness $\alpha$")
    bar = fig.colorbar(image, ax=axes, shrink=0.9)
    bar.set_label("compensated albedo − walk's albedo (fraction of the incident energy; "
                  "cells: ×10⁻³)", fontsize=8)
    fig.suptitle(f"Compensated cook_torrance against the random walk ({paths} paths per "
                 "point), white $m_S$, k = 0", fontsize=9)
    fig.savefig(path, bbox_inches="tight")
    return diff


def report_html(rows: list[dict]) -> str:
    """The section's HTML (its heading, the table of residuals, the figures)."""
    esc = html.escape
    parts = ["<p>The random walk on the Smith microsurface (Heitz et al. 2016; "
             "the module <code>mi_brdfs.tools.groundtruth</code>), with Schlick's Fresnel at "
             "every bounce, is the truth of multiple scattering; compensated "
             "<code>cook_torrance</code> (white m_S, k = 0) against it. Blinn's D and "
             "the V-cavity G are compared with the walk of the nearest Smith "
             "microsurface (Beckmann at the same α; the same D).</p><table><tr><th>D/G</th>"
             "<th>walk</th><th>largest relative difference (walk ≥ 0.01)</th>"
             "<th>largest absolute</th><th>bound</th><th>paths</th></tr>"]
    for r in rows:
        cls = "good" if r["relative"] <= r["bound"] else "bad"
        parts.append(f"<tr><td>{esc(r['distribution'])}/{esc(r['geometry'])}</td>"
                     f"<td>{esc(r['walk'])}</td><td class='{cls}'>{100 * r['relative']:.1f} %"
                     f"</td><td>{r['absolute']:.4f}</td><td>{100 * r['bound']:g} %</td>"
                     f"<td>{r['paths']}</td></tr>")
    parts.append("</table><div class='figs'>" + "".join(
        f"<img src='{esc(r['plot'])}' alt='ground truth'>" for r in rows)
        + "<img src='groundtruth_slices.png' alt='BRDF slices'>"
        f"<img src='{RESIDUAL_MAP}' alt='residual map: compensated albedo minus the walk, "
        "over angle and roughness'></div><p>The residual map: the compensated albedo minus "
        "the walk's at every angle and α ≤ 1 (GGX and Beckmann with Smith's G). BRDF slices: "
        "f·cos θ_o in the plane of incidence, the walk's by next-event estimation; the "
        "compensation lobe is separable, the walk's multiple scattering is not, and the "
        "separable G1·G1 shapes the single scattering (as Mitsuba's roughconductor).</p>")
    return "".join(parts)


def slice_difference(distribution: str, geometry: str, alpha: float, theta: float, f0: float,
                     paths: int = 20_000, n: int = 41) -> tuple[float, float]:
    """Relative L1 difference over the plane of incidence between the BRDF of
    the walk (on the nearest Smith microsurface) and compensated /
    single-scattering cook_torrance (white m_S, k = 0): (compensated, single)."""
    config = {"type": "cook_torrance", "distribution": distribution, "geometry": geometry,
              "alpha": alpha, "k": 0.0, "f0": f0, "specular_reflectance": 1.0}
    theta_o, comp = plane_of_incidence(mi.load_dict({**config, "energy_compensation": True}),
                                       theta, n)
    _, single = plane_of_incidence(mi.load_dict(config), theta, n)
    t = math.radians(theta)
    wi = np.repeat(np.array([[-math.sin(t), 0.0, math.cos(t)]]), n, axis=0)
    wo = np.stack([np.sin(theta_o), np.zeros(n), np.cos(theta_o)], axis=1)
    walked = brdf("ggx" if distribution == "ggx" else "beckmann", wi, wo, alpha, f0,
                  paths=paths, seed=2)
    return (float(np.abs(comp - walked).sum() / walked.sum()),
            float(np.abs(single - walked).sum() / walked.sum()))



GRAZING_PAIRS = (        # (name, θ_i, θ_o, φ_o - φ_i in degrees): both directions grazing
    ("retro-reflection", 60, 60, 0), ("retro-reflection", 70, 70, 0),
    ("retro-reflection", 80, 80, 0), ("retro-reflection", 85, 85, 0),
    ("side-on", 80, 80, 90),
    ("mirror", 70, 70, 180), ("mirror", 80, 80, 180), ("mirror", 85, 85, 180))


def grazing_difference(distribution: str = "beckmann", alpha: float = 0.3, f0: float = 1.0,
                       paths: int = 200_000) -> list[dict]:
    """Where the separable compensation lobe (``compensation="separable"``)
    puts the light of grazing directions, against the walk: at each of
    :data:`GRAZING_PAIRS`, the BRDF f (eval / cos θ_o) that compensation adds
    to cook_torrance with Smith's G (k = 0, white m_S) and the walk's multiple
    scattering there (bounces >= 2, next-event estimation, with its standard
    error). The lobe, separable in θ_i and θ_o, adds the same at every
    azimuth; the walk's is concentrated near the mirror direction."""
    def direction(theta, phi):
        t, p = math.radians(theta), math.radians(phi)
        return [math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)]
    wi = np.array([direction(ti, 0) for _, ti, _, _ in GRAZING_PAIRS])
    wo = np.array([direction(to, dphi) for _, _, to, dphi in GRAZING_PAIRS])
    config = {"type": "cook_torrance", "distribution": distribution, "geometry": "smith",
              "alpha": alpha, "k": 0.0, "f0": f0, "specular_reflectance": 1.0}
    # the separable lobe (the directional one, the default here, is measured by .pairs)
    plugins = [mi.load_dict({**config, "energy_compensation": True,
                             "compensation": "separable"}), mi.load_dict(config)]
    comp, single = ([eval_at_viewer(bsdf, ti, wo[k:k + 1], phi_i_deg=0.0)[0, 0]
                     for k, (_, ti, _, _) in enumerate(GRAZING_PAIRS)] for bsdf in plugins)
    added = (np.array(comp) - np.array(single)) / wo[:, 2]
    walked, error = brdf(distribution, wi, wo, alpha, f0, paths=paths, seed=5,
                         orders=(2, MAX_ORDER), error=True)
    return [{"pair": name, "theta_i": ti, "theta_o": to, "dphi": dphi, "added": float(a),
             "walk": float(w / wo[k, 2]), "walk_error": float(e / wo[k, 2])}
            for k, ((name, ti, to, dphi), a, w, e)
            in enumerate(zip(GRAZING_PAIRS, added, walked, error))]
