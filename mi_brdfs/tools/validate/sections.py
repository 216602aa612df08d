"""The validation report's sections 1-4: each a function returning its rows
(the ground truth's, section 5, is :func:`mi_brdfs.tools.groundtruth.report_section`)."""
from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

import drjit as dr
import mitsuba as mi

from ..._jit import from_numpy
from ...bsdfs import BY_NAME, cases
from .. import analysis, compare, settings
from ..chi2 import ConvergedChiSquareTest

MODES = ("hdr", "scanline")
ALPHA = 0.01                      # significance level of every statistical test


@dataclass(frozen=True)
class Settings(settings.Settings):
    """How much work each section does."""
    res: int
    passes: int
    spp: int                      # per pass
    furnace_spp: int              # per pixel of the 8x8 furnace renders
    quad: tuple[int, int]         # quadrature strata (cos theta, phi)
    angles: tuple[float, ...]
    chi2_samples: int
    weight_samples: int


# χ² at 1M samples in both: fewer leave the negative controls too little power
# (the 5 % narrower GGX lobe is not rejected at 200,000 samples).
QUICK = Settings(res=48, passes=16, spp=16, furnace_spp=256, quad=(256, 1024),
             angles=(0, 30, 60, 75, 85, 89), chi2_samples=1_000_000, weight_samples=100_000)
FULL = Settings(res=128, passes=32, spp=64, furnace_spp=4096, quad=(1024, 4096),
            angles=(0, 15, 30, 45, 60, 70, 75, 80, 85, 88, 89),
            chi2_samples=1_000_000, weight_samples=1_000_000)


# ----------------------------------------------------------------------------
#  1. Built-in equivalence
# ----------------------------------------------------------------------------

ETA = 1.5
F0_GLASS = ((ETA - 1) / (ETA + 1)) ** 2

EQUIVALENCES = [              # (check id, title, ours, built-in, expectation)
    ("lambert-diffuse", "lambert vs diffuse", {"type": "lambert", "reflectance": 0.7},
     {"type": "diffuse", "reflectance": 0.7},
     "identical up to noise"),
    ("cook_torrance-roughconductor-ggx",
     "cook_torrance (k=0, f0=1, smith, ggx) vs roughconductor (ggx)",
     {"type": "cook_torrance", "k": 0.0, "f0": 1.0, "geometry": "smith", "distribution": "ggx",
      "alpha": 0.3},
     {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3},
     "identical up to noise"),
    ("cook_torrance-roughconductor-beckmann",
     "cook_torrance (k=0, f0=1, smith, beckmann) vs roughconductor (beckmann)",
     {"type": "cook_torrance", "k": 0.0, "f0": 1.0, "geometry": "smith",
      "distribution": "beckmann", "alpha": 0.3},
     {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.3},
     "identical up to the Beckmann G1 fit (Mitsuba's rational fit, within 0.35 % per G1)"),
    ("cook_torrance-roughplastic",
     f"cook_torrance (fresnel dielectric η={ETA:g}, base plastic, smith, ggx) vs roughplastic (ggx)",
     {"type": "cook_torrance", "fresnel": "dielectric", "base": "plastic", "int_ior": ETA,
      "ext_ior": 1.0, "geometry": "smith", "distribution": "ggx", "alpha": 0.3,
      "diffuse_reflectance": 0.5},
     {"type": "roughplastic", "distribution": "ggx", "alpha": 0.3, "diffuse_reflectance": 0.5,
      "int_ior": ETA, "ext_ior": 1.0},
     "identical up to noise (each side integrates the interface's transmittance and internal "
     "reflectance its own way; they agree within 4e-4)"),
    ("cook_torrance-schlick-roughplastic",
     f"cook_torrance (k=0, f0={F0_GLASS:.2f}, smith, ggx: the lecture's Schlick) vs roughplastic "
     "(diffuse 0)",
     {"type": "cook_torrance", "k": 0.0, "f0": F0_GLASS, "geometry": "smith",
      "distribution": "ggx", "alpha": 0.3},
     {"type": "roughplastic", "distribution": "ggx", "alpha": 0.3, "diffuse_reflectance": 0.0,
      "int_ior": ETA, "ext_ior": 1.0},
     "differing by Schlick's approximation only (visible at grazing angles: the rim); "
     "with fresnel=\"dielectric\" the BSDF check below finds nothing else"),
]


def sphere_scene(bsdf: dict, res: int) -> dict:
    """The equivalence scene: :func:`.analysis.sphere_scene` with a grey
    environment beside its point light, rendered by the path tracer (direct
    and one indirect bounce)."""
    return analysis.sphere_scene(bsdf, res, integrator={"type": "path", "max_depth": 2},
                                 env=0.5)


def independent_renders(scene_dict: dict, count: int, spp: int, seed0: int = 0) -> np.ndarray:
    """(count, H, W, 3): ``count`` renders with seeds seed0, seed0 + 1, ...
    (kept apart, for the per-pixel test; not averaged as render passes are)."""
    scene = mi.load_dict(scene_dict)
    return np.stack([np.array(mi.render(scene, spp=spp, seed=seed0 + i))[..., :3]
                     for i in range(count)]).astype(np.float64)


def welch_test(a: np.ndarray, b: np.ndarray) -> dict:
    """Per-pixel Welch t-test of the pass means (channel mean), Bonferroni over pixels."""
    from scipy import stats                 # optional: the reports extra

    a, b = a.mean(axis=-1), b.mean(axis=-1)          # (passes, H, W)
    n = a.shape[0]
    ma, mb = a.mean(0), b.mean(0)
    va, vb = a.var(0, ddof=1) / n, b.var(0, ddof=1) / n
    se2 = va + vb
    both_zero = se2 <= 0
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(both_zero, 0.0, (ma - mb) / np.sqrt(np.where(both_zero, 1, se2)))
        df = np.where(both_zero, 1.0,
                      se2**2 / (va**2 / (n - 1) + vb**2 / (n - 1) + 1e-300))
    p = np.where(both_zero & (ma != mb), 0.0, 2 * stats.t.sf(np.abs(t), df))
    pixels = p.size
    significant = int(np.count_nonzero(p < ALPHA / pixels))
    mask = (ma > 1e-3) | (mb > 1e-3)
    rel = float(np.mean(np.abs(ma - mb)[mask] / np.maximum(ma, mb)[mask])) if mask.any() else 0.0
    return {"pixels": pixels, "significant_pixels": significant, "min_p": float(p.min()),
            "bonferroni_alpha": ALPHA / pixels, "identical": significant == 0,
            "mean_relative_difference": rel}


def equivalence_section(size: Settings, out: str) -> list[dict]:
    results = []
    for i, (check_id, title, ours, builtin, expected) in enumerate(EQUIVALENCES):
        a = independent_renders(sphere_scene(ours, size.res), size.passes, size.spp, seed0=0)
        b = independent_renders(sphere_scene(builtin, size.res), size.passes, size.spp,
                                seed0=1000)
        test = welch_test(a, b)
        ref_img, test_img = b.mean(0), a.mean(0)          # built-in, ours
        m = compare.metrics(ref_img, test_img, with_flip=False)
        m["flip"], flip_map = compare.flip(ref_img, test_img, "hdr")     # linear renders
        m["flip_mode"] = "hdr"
        files = compare.pictures(out, f"eq{i}", ref_img, test_img, "clamp", flip_map,
                                 ref_name=f"eq{i}_builtin.png")
        results.append({"id": check_id, "title": title, "expected": expected, "test": test,
                        "metrics": {k: v for k, v in m.items() if k != "channels"},
                        "files": files})
    return results


def fresnel_dielectric(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """The unpolarized Fresnel reflectance of a dielectric of relative index
    ``eta`` (> 1) for light arriving from outside at cos θ_i (Fresnel's
    equations; transcribed here, independent of Mitsuba and the plugins)."""
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - (1.0 - cos_i**2) / eta**2))
    r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (r_s**2 + r_p**2)


def fresnel_schlick(cos_i: np.ndarray, f0: float) -> np.ndarray:
    """Schlick's approximation F0 + (1 − F0)(1 − cos θ)^5."""
    return f0 + (1.0 - f0) * (1.0 - cos_i) ** 5


FRESNEL_ALPHAS = (0.1, 0.3, 0.7)  # GGX roughness of the exact-Fresnel check
FRESNEL_PAIRS = 100_000           # random (wi, wo) pairs on the upper hemisphere
FLOAT_PRECISION = 1e-5            # largest |difference| allowed, relative to the largest value


def fresnel_section(seed: int = 5, ours_eta: float = ETA) -> list[dict]:
    """cook_torrance with ``fresnel="dielectric"`` (η ``ours_eta``) and with the
    lecture's Schlick F against roughplastic's specular lobe (diffuse 0, η =
    ETA), at BSDF level: eval at random direction pairs."""
    rng = np.random.default_rng(seed)

    def hemisphere(n):
        u, v = rng.random(n), rng.random(n)
        s = np.sqrt(1.0 - u * u)
        return np.stack([s * np.cos(2 * np.pi * v), s * np.sin(2 * np.pi * v), u], axis=1)
    wi, wo = hemisphere(FRESNEL_PAIRS), hemisphere(FRESNEL_PAIRS)
    h = (wi + wo) / np.linalg.norm(wi + wo, axis=1, keepdims=True)
    cos_d = np.sum(wi * h, axis=1)
    ratio = fresnel_dielectric(cos_d, ETA) / fresnel_schlick(cos_d, F0_GLASS)

    def eval_pairs(config):
        si = dr.zeros(mi.SurfaceInteraction3f, FRESNEL_PAIRS)
        si.wi = from_numpy(mi.Vector3f, wi.T)
        value = mi.load_dict(config).eval(mi.BSDFContext(), si,
                                          from_numpy(mi.Vector3f, wo.T))
        return np.array(value, dtype=np.float64)[0]

    rows = []
    for alpha in FRESNEL_ALPHAS:
        lobe = {"type": "cook_torrance", "k": 0.0, "geometry": "smith", "distribution": "ggx",
                "alpha": alpha}
        exact = eval_pairs({**lobe, "fresnel": "dielectric", "int_ior": ours_eta, "ext_ior": 1.0})
        schlick = eval_pairs({**lobe, "f0": F0_GLASS})
        builtin = eval_pairs({"type": "roughplastic", "distribution": "ggx", "alpha": alpha,
                            "diffuse_reflectance": 0.0, "int_ior": ETA, "ext_ior": 1.0})
        scale = float(builtin.max())
        rows.append({"id": f"cook_torrance-roughplastic-fresnel-{alpha:g}",
                     "title": f"cook_torrance (k=0, fresnel dielectric η={ours_eta:g}, smith, ggx, "
                              f"α={alpha:g}) vs roughplastic (diffuse 0, η={ETA:g})",
                     "pairs": FRESNEL_PAIRS, "alpha": alpha,
                     "exact": float(np.max(np.abs(exact - builtin)) / scale),
                     "schlick": float(np.max(np.abs(schlick - builtin)) / scale),
                     "ratio_range": [float(ratio.min()), float(ratio.max())]})
    return rows


# ----------------------------------------------------------------------------
#  2. White furnace
# ----------------------------------------------------------------------------

def rendered_albedo(config: dict, angles, size: Settings) -> np.ndarray:
    """E(theta_i) by rendering: a large plane with the BSDF inside a uniform white
    environment, seen by an orthographic camera at theta_i (every pixel sees
    the surface at exactly that angle), with direct lighting only."""
    T = mi.ScalarTransform4f
    out = []
    for a in angles:
        t = math.radians(a)
        scene = mi.load_dict({
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 2, "hide_emitters": True},
            "sensor": {"type": "orthographic",
                       "to_world": T().look_at(origin=[100 * math.sin(t), 0, 100 * math.cos(t)],
                                               target=[0, 0, 0], up=[0, 1, 0]) @ T().scale(0.25),
                       "film": {"type": "hdrfilm", "width": 8, "height": 8,
                                "rfilter": {"type": "box"}},
                       "sampler": {"type": "independent"}},
            "plane": {"type": "rectangle", "bsdf": config, "to_world": T().scale(1000.0)},
            # A black floor just below: light from below the surface (which the
            # toon model's dark side would see) is not part of the albedo.
            "floor": {"type": "rectangle", "bsdf": {"type": "diffuse", "reflectance": 0.0},
                      "to_world": T().translate([0, 0, -1e-2]) @ T().scale(1000.0)},
            "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
        })
        image = np.array(mi.render(scene, spp=size.furnace_spp))[..., :3]
        out.append(float(image.mean(axis=(0, 1)).max()))
    return np.array(out)


COMPENSATED = "hdr, compensated"  # the furnace's third curve: hdr with energy_compensation
PRESERVED_UP_TO = 85.0            # where promised: albedo 1 ± PRESERVED_TOL up to this θ_i
PRESERVED_TOL = 0.01


def furnace_curves(config: dict) -> list[tuple[str, dict]]:
    """(label, configuration) of each furnace curve: both modes, and hdr with
    energy compensation where the model has it."""
    curves = [(mode, {**config, "mode": mode}) for mode in MODES]
    if BY_NAME[config["type"]].compensable:
        curves.append((COMPENSATED, {**config, "mode": "hdr", "energy_compensation": True}))
    return curves


def furnace_section(size: Settings, out: str, models: dict) -> list[dict]:
    from matplotlib.figure import Figure    # the reports extra; no pyplot: no global backend

    rows = []
    for name, configs in models.items():
        for label, base in configs:
            fig = Figure(figsize=(5.2, 3.4), dpi=100)
            ax = fig.subplots()
            plot = f"furnace_{name}_{len(rows)}.png"
            for (mode, config), colour in zip(furnace_curves(base), ("C0", "C3", "C2")):
                quad = analysis.directional_albedo(mi.load_dict(config), size.angles, size.quad)
                rend = rendered_albedo(config, size.angles, size)
                ax.plot(size.angles, quad, "-o", color=colour, ms=3, label=f"{mode}: quadrature")
                ax.plot(size.angles, rend, "x", color=colour, label=f"{mode}: render")
                worst = int(np.argmax(quad))
                band = quad[np.array(size.angles) <= PRESERVED_UP_TO]
                rows.append({
                    "model": name, "config": label, "mode": mode,
                    "compensated": mode == COMPENSATED,
                    "promised": cases.promises_one(name, config),     # albedo = 1
                    "angles": list(size.angles), "quadrature": quad.tolist(),
                    "render": rend.tolist(), "max": float(quad.max()),
                    "max_at": size.angles[worst], "mean": float(quad.mean()),
                    "min": float(quad.min()),
                    "deviation": float(np.max(np.abs(band - 1.0))),   # from 1, up to 85°
                    "render_vs_quadrature": float(np.nanmax(np.abs(rend - quad))),
                    "exceeds_1": bool(quad.max() > 1.005),
                    "loses_energy": bool(quad.max() < 0.99),
                    "plot": plot,
                })
            ax.axhline(1.0, color="k", lw=0.6)
            ax.set_xlabel(r"incident angle $\theta_i$ (degrees)")     # typeset by mathtext
            ax.set_ylabel("directional albedo")
            ax.set_title(f"{name}: {label}", fontsize=9)
            ax.legend(fontsize=6)
            fig.tight_layout()
            fig.savefig(os.path.join(out, plot))
    return rows


# ----------------------------------------------------------------------------
#  3. Sampling
# ----------------------------------------------------------------------------

def viewer(theta: float, phi: float = 0.0):
    """The local direction to a viewer at (theta, phi), in degrees."""
    t, p = math.radians(theta), math.radians(phi)
    return mi.ScalarVector3f(math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t))


def chi2_test(sampled: dict, pdf: dict, theta: float, phi: float, res: int,
              samples: int) -> ConvergedChiSquareTest:
    """The χ² test of ``sampled``'s sampler against ``pdf``'s density, for a
    viewer at (theta, phi), the density integrated until it converges."""
    sample_func, _ = mi.chi2.BSDFAdapter(sampled["type"], sampled, wi=viewer(theta, phi))
    _, pdf_func = mi.chi2.BSDFAdapter(pdf["type"], pdf, wi=viewer(theta, phi))
    return ConvergedChiSquareTest(domain=mi.chi2.SphericalDomain(), pdf_func=pdf_func,
                                  sample_func=sample_func, sample_dim=3,
                                  sample_count=samples, res=res)


def chi2_count(models: dict, negatives: dict) -> int:
    """Every χ² test of the report, for the Šidák correction."""
    return sum(len(c.thetas) for tests in models.values() for _, c in tests) + len(negatives)


def sampling_section(size: Settings, models: dict, count: int | None = None) -> list[dict]:
    """χ² and sample weights of every test of ``models`` ({model: [(label,
    cases.Chi2)]}), at the case's resolution and viewer azimuth.
    ``count``: the number of χ² tests the significance is corrected for."""
    count = count or chi2_count(models, {})
    rows = []
    for name, tests in models.items():
        for label, case in tests:
            bsdf = mi.load_dict(case.config)
            for theta in case.thetas:
                chi2 = chi2_test(case.config, case.config, theta, case.phi, case.res,
                                 size.chi2_samples)
                passed = bool(chi2.run(significance_level=ALPHA, test_count=count, quiet=True))
                # Sample weights at this incident angle.
                n = size.weight_samples
                rng = np.random.default_rng(11)
                si = dr.zeros(mi.SurfaceInteraction3f, n)
                si.wi = mi.Vector3f(viewer(theta, case.phi))
                _, weight = bsdf.sample(mi.BSDFContext(), si, from_numpy(mi.Float, rng.random(n)),
                                        from_numpy(mi.Point2f, rng.random((2, n))))
                w = np.array(weight).mean(axis=0)
                rows.append({"model": name, "config": label, "theta": theta, "phi": case.phi,
                             "passed": passed, "p_value": float(chi2.p_value),
                             "ires": chi2.ires_reached, "unconverged": chi2.unconverged,
                             "weight_mean": float(w.mean()), "weight_variance": float(w.var())})
    return rows


def negative_section(size: Settings, negatives: dict, count: int) -> list[dict]:
    """The χ² test of each negative control (:func:`.cases.negative_controls`): the
    sampler of one configuration against the pdf of a slightly different
    one. Each must be rejected."""
    rows = []
    for name, (sampled, pdf, theta, phi) in negatives.items():
        chi2 = chi2_test(sampled, pdf, theta, phi, 201, size.chi2_samples)
        rejected = not chi2.run(significance_level=ALPHA, test_count=count, quiet=True)
        differs = ", ".join(f"{k} {sampled.get(k)} sampled, {pdf.get(k)} in the pdf"
                            for k in sorted(set(sampled) | set(pdf))
                            if sampled.get(k) != pdf.get(k))
        rows.append({"model": name, "config": differs, "theta": theta, "phi": phi,
                     "rejected": rejected, "p_value": float(chi2.p_value),
                     "ires": chi2.ires_reached})
    return rows


# ----------------------------------------------------------------------------
#  4. Lobes
# ----------------------------------------------------------------------------

# What a lobe plot's radius is: eval's value, f·cos θ_o; a BRDF in hdr mode
# (per steradian), the lecture's shading value in scan-line mode (no 1/π).
LOBE_RADIUS = {"hdr": r"radius: $f\,\cos\theta_o$ (1/sr)",
               "scanline": r"radius: $f\,\cos\theta_o$ (the lecture's value, no unit)"}
LOBE_SCALE = "one radial scale in both plots"


def lobe_figure(name: str, base: dict, angles=(0, 30, 60, 80)):
    """The lobe plot of one configuration: ``eval`` in the plane of incidence,
    scan-line mode beside hdr mode, each titled with what its radius is and
    its unit, each with its legend, both on one radial scale (the reader
    compares their sizes)."""
    from matplotlib.figure import Figure    # the reports extra; no pyplot: no global backend

    fig = Figure(figsize=(8.4, 3.4), dpi=100)
    axes = fig.subplots(1, 2, subplot_kw={"projection": "polar"})
    for ax, mode in zip(axes, MODES):
        # the radius named under the title (a polar axis has no y label)
        analysis.polar_lobes(ax, mi.load_dict({**base, "mode": mode}), angles,
                             f"{mode} mode\n{LOBE_RADIUS[mode]}")
    top = max(ax.get_rmax() for ax in axes)
    for ax in axes:
        ax.set_rmax(top)
        ax.set_title(ax.get_title(), fontsize=10, y=0.86)     # near the half disc
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, 0.17), ncol=len(angles),
                  title="viewer", title_fontsize=7, handlelength=1.2, columnspacing=0.8)
    fig.suptitle(f"{name}: {LOBE_SCALE}", fontsize=10, y=0.99, va="top")
    fig.subplots_adjust(left=0.02, right=0.98, bottom=0.0, top=0.9, wspace=0.15)
    return fig


def lobe_section(out: str, models: dict, angles=(0, 30, 60, 80)) -> list[dict]:
    rows = []
    for name, base in models.items():
        file = f"lobe_{name}.png"
        lobe_figure(name, base, angles).savefig(os.path.join(out, file), bbox_inches="tight",
                                                pad_inches=0.1)
        rows.append({"model": name, "plot": file})
    return rows
