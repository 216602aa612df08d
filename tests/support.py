"""Test helpers, in one place: directions, evaluation, the chi-square test, the
white-furnace quadrature, finite differences.

Every helper is independent of the plugins' own sampling (the furnace
quadrature, the direction generators) so that a wrong sampler or pdf cannot
hide an error elsewhere.
"""
from __future__ import annotations

import contextlib
import math

import numpy as np

import mi_brdfs  # noqa: F401  (LLVM set-up, variant, plugin registration)
import drjit as dr
import mitsuba as mi

# ----------------------------------------------------------------------------
#  Directions and evaluation
# ----------------------------------------------------------------------------


def rgb(c) -> dict:
    return {"type": "rgb", "value": list(map(float, c))}


def f32(a) -> np.ndarray:
    """Directions exactly as the plugin sees them: their float32 values, in float64."""
    return np.asarray(a, dtype=np.float32).astype(np.float64)


def unit(a) -> np.ndarray:
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


def random_hemisphere(rng, n, min_cos=0.0) -> np.ndarray:
    """n unit vectors with z > min_cos, as an (n, 3) NumPy array."""
    v = rng.normal(size=(4 * n + 64, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[:, 2] = np.abs(v[:, 2])
    v = v[v[:, 2] > min_cos]
    return v[:n]


def direction(theta_deg: float, phi_deg: float = 0.0) -> np.ndarray:
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def mirror_pairs(rng, n, width=0.3, min_cos=0.02):
    """(wi, wo): viewers above the surface; half the lights near the viewer's
    mirror direction (within ~width), half anywhere above; float32-exact."""
    wi = random_hemisphere(rng, n, min_cos)
    wo = random_hemisphere(rng, n, min_cos)
    m = n // 2
    wo[:m] = wi[:m] * [-1, -1, 1] + width * rng.normal(size=(m, 3))
    wo[:m] /= np.linalg.norm(wo[:m], axis=1, keepdims=True)
    wo[:m, 2] = np.maximum(np.abs(wo[:m, 2]), min_cos)
    return f32(unit(wi)), f32(unit(wo))


def jit(x):
    """A Dr.Jit array in Dr.Jit's own (aligned) memory. Arrays made from NumPy
    may keep NumPy's buffer, whose alignment varies from run to run and is part
    of a kernel's hash: the same test would then compile its kernels again."""
    return dr.copy(x)


def vec(a) -> mi.Vector3f:
    a = np.asarray(a, dtype=np.float64)
    return jit(mi.Vector3f(a[:, 0], a[:, 1], a[:, 2]))


def floats(a) -> mi.Float:
    return jit(mi.Float(np.asarray(a, dtype=np.float64)))


def points(x, y) -> mi.Point2f:
    return jit(mi.Point2f(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)))


def surface(wi, uv=None) -> mi.SurfaceInteraction3f:
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = vec(wi)
    si.uv = mi.Point2f(0.5, 0.5) if uv is None else points(uv[:, 0], uv[:, 1])
    return si


def evaluate(bsdf, wi, wo, uv=None):
    """eval (n, 3) and pdf (n,) of a BSDF on direction pairs (NumPy in and out, float64)."""
    ctx = mi.BSDFContext()
    si = surface(wi, uv)
    value = np.array(bsdf.eval(ctx, si, vec(wo)), dtype=np.float64)
    pdf = np.array(bsdf.pdf(ctx, si, vec(wo)), dtype=np.float64)
    return (value.T if value.ndim == 2 else value[:, None]), pdf


def error_line(error: BaseException) -> str:
    """The last line of an error's message: the one a user reads."""
    return str(error).strip().splitlines()[-1]


def assert_refused(config: dict, name: str, shown: str, valid: str) -> None:
    """Loading ``config`` fails with one line naming the plugin, the parameter
    ``name``, its value as ``shown`` and ``valid`` (the valid range or choice)."""
    import pytest
    with pytest.raises(Exception) as info:
        mi.load_dict(config)
    last = error_line(info.value)
    assert f"{config['type']}: parameter '{name}' = {shown} is invalid" in last, last
    assert valid in last, last


def finite(x) -> bool:
    return bool(np.all(np.isfinite(np.array(x))))


def config_id(config: dict) -> str:
    """A readable test id for a plugin configuration."""
    parts = [config["type"]]
    for k, v in config.items():
        if k == "type":
            continue
        parts.append(f"{k}={v['type'] if isinstance(v, dict) else v}")
    return "-".join(parts)


# ----------------------------------------------------------------------------
#  Property forms: every way a Mitsuba scene gives a parameter
# ----------------------------------------------------------------------------

PAIRS = "400:0.2, 550:0.6, 700:0.4"          # a <spectrum> of wavelength:value pairs
BITMAP = [[[0.1, 0.5, 0.9], [0.3, 0.3, 0.3]], [[0.8, 0.2, 0.4], [0.6, 0.7, 0.1]]]
UVS = [(0.5, 0.5), (0.1, 0.2), (0.9, 0.3), (0.3, 0.8)]      # where textures are compared


def property_forms(folder) -> dict[str, str]:
    """{form: an XML element of parameter NAME}, in every form Mitsuba's own
    plugins accept for a colour or a scalar, with values in [0.1, 0.9] (within
    every parameter's range). The spectrum file and the bitmap are written
    into ``folder``; ``ref`` refers to the texture of :func:`load_form`."""
    from pathlib import Path
    folder = Path(folder)
    spd, exr = folder / "forms.spd", folder / "forms.exr"
    spd.write_text("".join(f"{w} {v}\n" for w, v in (p.split(":") for p in PAIRS.split(", "))))
    mi.Bitmap(np.array(BITMAP, dtype=np.float32)).write(str(exr))
    return {
        "float": '<float name="NAME" value="0.3"/>',
        "integer": '<integer name="NAME" value="1"/>',
        "rgb": '<rgb name="NAME" value="0.2, 0.5, 0.8"/>',
        "spectrum": '<spectrum name="NAME" value="0.4"/>',
        "pairs": f'<spectrum name="NAME" value="{PAIRS}"/>',
        "file": f'<spectrum name="NAME" filename="{spd}"/>',
        "bitmap": f'<texture type="bitmap" name="NAME"><string name="filename" value="{exr}"/>'
                  '</texture>',
        "ref": '<ref name="NAME" id="shared"/>',
    }


def load_form(plugin: str, name: str, element: str):
    """``plugin`` with its parameter ``name`` given as ``element`` (from
    :func:`property_forms`), loaded from XML: a ``ref`` inside a scene that
    declares the texture it refers to (a checkerboard) and a shape using it."""
    element = element.replace("NAME", name)
    bsdf = f'<bsdf type="{plugin}">{element}</bsdf>'
    if "<ref" not in element:
        return mi.load_string(bsdf.replace("<bsdf ", '<bsdf version="3.0.0" ', 1))
    scene = mi.load_string(
        '<scene version="3.0.0"><texture type="checkerboard" id="shared">'
        '<float name="color0" value="0.2"/><float name="color1" value="0.7"/></texture>'
        f'<shape type="rectangle">{bsdf}</shape></scene>')
    return scene.shapes()[0].bsdf()


def texture_values(bsdf, name: str, method: str) -> np.ndarray:
    """``bsdf.<method>(name, si)`` (eval_attribute or eval_attribute_1) at
    :data:`UVS`, as (len(UVS), channels) float64; fixed wavelengths in spectral
    variants. Lane by lane in scalar variants."""
    def si_at(uv):
        si = dr.zeros(mi.SurfaceInteraction3f, len(uv[0])) if dr.is_jit_v(mi.Float) \
            else dr.zeros(mi.SurfaceInteraction3f)
        si.uv = mi.Point2f(*uv)
        if mi.is_spectral:
            si.wavelengths = mi.UnpolarizedSpectrum(*[mi.Float(w) for w in (450, 520, 610, 680)])
        return si
    if dr.is_jit_v(mi.Float):
        u, v = (np.array(c, dtype=np.float64) for c in zip(*UVS))
        value = getattr(bsdf, method)(name, si_at((u, v)))
        out = np.array(value, dtype=np.float64).reshape(1 if method.endswith("_1") else len(value), -1)
        return np.broadcast_to(out, (out.shape[0], len(UVS))).T    # (a constant has width 1)
    return np.array([np.array(getattr(bsdf, method)(name, si_at(uv)), dtype=np.float64).ravel()
                     for uv in UVS])


def property_form_failures(plugin: str, folder) -> list[str]:
    """Every parameter of ``plugin`` in every form of :func:`property_forms`:
    a colour or scalar holds what Mitsuba's ``diffuse`` holds for the same
    element (its texture compared at :data:`UVS`); a plain number takes
    <float> and <integer>; whatever is refused (a texture or spectrum for a
    plain number; in spectral variants a wavelength-dependent spectrum or a
    3-channel bitmap for a scalar, which have no single value there) is
    refused with the one-line error. Wrong types (<string>, <boolean>) and
    out-of-range spectrum values are refused with one line. Returns the
    failures, one line each (empty: all as expected)."""
    from mi_brdfs.bsdfs import BY_NAME
    forms, failures = property_forms(folder), []

    def refused(p, element, shown: str | None = None) -> None:
        try:
            load_form(plugin, p.name, element)
        except Exception as e:
            last = error_line(e)
            head = f"{plugin}: parameter '{p.name}' = " + (shown or "")
            if head not in last or "is invalid; valid:" not in last:
                failures.append(f"{p.name} {element}: not the one-line error: {last}")
            return
        failures.append(f"{p.name} {element}: accepted, should be refused")

    for p in BY_NAME[plugin].PARAMS:
        method = "eval_attribute_1" if p.kind == "scalar" else "eval_attribute"
        for form, element in forms.items():
            if p.kind == "float" and form not in ("float", "integer") or (
                    mi.is_spectral and p.kind == "scalar" and form in ("pairs", "file", "bitmap")):
                refused(p, element)
                continue
            try:
                bsdf = load_form(plugin, p.name, element)
            except Exception as e:
                failures.append(f"{p.name} {form}: refused: {error_line(e)}")
                continue
            if p.kind == "float":
                value = float(np.array(mi.traverse(bsdf)[p.name]).ravel()[0])
                expected = 1.0 if form == "integer" else 0.3
                if abs(value - expected) > 1e-7:
                    failures.append(f"{p.name} {form}: holds {value}, not {expected}")
                continue
            ours = texture_values(bsdf, p.name, method)
            theirs = texture_values(load_form("diffuse", "reflectance", element), "reflectance",
                                    method)
            if ours.shape != theirs.shape or not np.allclose(ours, theirs, rtol=1e-6, atol=0):
                failures.append(f"{p.name} {form}: {np.round(ours[0], 5).tolist()} where "
                                f"diffuse holds {np.round(theirs[0], 5).tolist()}")
        # wrong types, and a spectrum holding a value out of range
        refused(p, '<string name="NAME" value="abc"/>', "'abc'")
        refused(p, '<boolean name="NAME" value="true"/>', "True")
        if p.kind != "float":
            bad = p.lo - 0.5 if p.lo is not None else p.hi + 0.5
            refused(p, f'<spectrum name="NAME" value="400:0.5, 700:{bad:g}"/>', repr(bad))
    return failures


# ----------------------------------------------------------------------------
#  Chi-square (Mitsuba's test, as its own BSDF tests use it)
# ----------------------------------------------------------------------------

CHI2_SAMPLES = 1_000_000
CHI2_ALPHA = 0.01      # the probability that the whole suite rejects a correct sampler
# The variants whose χ² runs in tests/test_variants.py (cuda ones only with a GPU).
CPU_VARIANTS = ["scalar_rgb", "scalar_spectral", "llvm_ad_rgb", "llvm_ad_mono", "llvm_ad_spectral"]
GPU_VARIANTS = ["cuda_ad_rgb", "cuda_ad_spectral"] if dr.has_backend(dr.JitBackend.CUDA) else []


def variant_chi2_cases() -> list[tuple[dict, float]]:
    """One χ² configuration per plugin for the variants test: its catalog's
    first, at its second incident angle."""
    from mi_brdfs.tools.catalog import ENTRIES
    out = []
    for cls in mi_brdfs.PLUGINS:
        case = ENTRIES[cls.name].chi2[0]
        out.append((case.config, case.thetas[min(1, len(case.thetas) - 1)]))
    return out


def chi2_test_count() -> int:
    """Every χ² test of the suite, for one Šidák correction: the battery's
    catalog runs and negative controls, and the variants'."""
    from mi_brdfs.tools.catalog import ENTRIES
    battery = sum(len(c.thetas) for e in ENTRIES.values() for c in e.chi2)
    negative = sum(1 for e in ENTRIES.values() if e.negative)
    return battery + negative + len(CPU_VARIANTS + GPU_VARIANTS) * len(mi_brdfs.PLUGINS)


def chi2_test(sample_config: dict, pdf_config: dict, theta_deg: float, phi_deg: float = 0.0,
              *, res: int = 201, ires: int = 16,
              samples: int = CHI2_SAMPLES) -> mi.chi2.ChiSquareTest:
    """The histogram of sample() of ``sample_config`` against pdf() of
    ``pdf_config`` integrated over each cell, on a (2 res) x res grid of
    (phi, cos theta), for a viewer at (theta_deg, phi_deg)."""
    wi = mi.ScalarVector3f(*direction(theta_deg, phi_deg))
    sample_func, _ = mi.chi2.BSDFAdapter(sample_config["type"], sample_config, wi=wi)
    _, pdf_func = mi.chi2.BSDFAdapter(pdf_config["type"], pdf_config, wi=wi)
    return mi.chi2.ChiSquareTest(domain=mi.chi2.SphericalDomain(), pdf_func=pdf_func,
                                 sample_func=sample_func, sample_dim=3,
                                 sample_count=samples, res=res, ires=ires)


# ----------------------------------------------------------------------------
#  White furnace: directional albedo by an independent quadrature
# ----------------------------------------------------------------------------

_hemispheres: dict[int, mi.Vector3f] = {}


def hemisphere_points(n: int) -> mi.Vector3f:
    """n² jittered stratified points of the unit square mapped to the upper
    hemisphere by Mitsuba's equal-area ``square_to_uniform_hemisphere`` (density
    1/(2π), low distortion: narrow lobes anywhere are resolved alike). A fixed
    seed; cached per n."""
    if n not in _hemispheres:
        rng = np.random.default_rng(314159 + n)
        i, j = (a.ravel() for a in np.meshgrid(np.arange(n), np.arange(n), indexing="ij"))
        u = points((i + rng.random(i.size)) / n, (j + rng.random(j.size)) / n)
        _hemispheres[n] = mi.warp.square_to_uniform_hemisphere(u)
        dr.eval(_hemispheres[n])
    return _hemispheres[n]


def albedo(bsdf, theta_deg: float, phi_deg: float = 0.0, n: int = 1024) -> np.ndarray:
    """Per-channel directional albedo E(w_i) = ∫ eval(w_i, w_o) dw_o (eval
    carries cos θ_o) at incidence (theta, phi): 2π mean(eval) over
    :func:`hemisphere_points` (never the plugin's sampler)."""
    wo = hemisphere_points(n)
    d = direction(theta_deg, phi_deg)
    si = dr.zeros(mi.SurfaceInteraction3f)
    # Opaque: one compiled kernel for every incident angle.
    si.wi = mi.Vector3f(*(dr.opaque(mi.Float, float(c)) for c in d))
    si.uv = mi.Point2f(0.5, 0.5)
    value = bsdf.eval(mi.BSDFContext(), si, wo)
    return np.array([float(dr.sum(mi.Float64(value[c]))[0]) for c in range(len(value))]) \
        * 2.0 * np.pi / dr.width(wo)


def lobe_quadrature(width: float, n_gl: int = 24, n_phi: int = 2048):
    """Nodes (a, phi) and weights (sin a da dphi) over the sphere in polar
    coordinates about a lobe's axis: a in Gauss-Legendre panels graded to the
    lobe's width (widths doubling from width/20 to pi/2, then two panels to pi),
    phi by the midpoint rule over [0, pi] (for lobes even in phi). Exact for
    a power-cosine lobe however narrow it is."""
    edges, a = [0.0], 0.05 * width
    while a < math.pi / 2:
        edges.append(a)
        a *= 2.0
    edges += [math.pi / 2, 0.75 * math.pi, math.pi]
    x, w = np.polynomial.legendre.leggauss(n_gl)
    alpha = np.concatenate([lo + (hi - lo) * (x + 1) / 2 for lo, hi in zip(edges, edges[1:])])
    w_alpha = np.concatenate([(hi - lo) / 2 * w for lo, hi in zip(edges, edges[1:])])
    phi = (np.arange(n_phi) + 0.5) * math.pi / n_phi
    A, P = np.meshgrid(alpha, phi, indexing="ij")
    W = (w_alpha * np.sin(alpha))[:, None] * (2.0 * math.pi / n_phi)
    return A.ravel(), P.ravel(), np.broadcast_to(W, A.shape).ravel()


def mirror_lobe_albedo(bsdf, theta_deg: float, width: float, **quadrature) -> np.ndarray:
    """Per-channel directional albedo by :func:`lobe_quadrature` about the
    viewer's mirror direction (where Phong's and Blinn's lobes are centred)."""
    A, P, W = lobe_quadrature(width, **quadrature)
    t = math.radians(theta_deg)
    r = np.array([-math.sin(t), 0.0, math.cos(t)])      # mirror direction of w_i
    t1 = np.array([math.cos(t), 0.0, math.sin(t)])      # a frame about r
    t2 = np.array([0.0, 1.0, 0.0])
    wo = (np.sin(A) * np.cos(P))[:, None] * t1 + (np.sin(A) * np.sin(P))[:, None] * t2 \
        + np.cos(A)[:, None] * r
    wi = np.tile([math.sin(t), 0.0, math.cos(t)], (len(W), 1))
    return evaluate(bsdf, wi, wo)[0].T @ W


def uniform_hemisphere_grid(nu: int, nv: int, seed: int) -> np.ndarray:
    """nu x nv jittered strata uniform in (cos θ, φ): directions of density 1/(2π)."""
    rng = np.random.default_rng(seed)
    u = ((np.arange(nu)[:, None] + rng.random((nu, nv))) / nu).ravel()
    v = ((np.arange(nv)[None, :] + rng.random((nu, nv))) / nv).ravel()
    s = np.sqrt(np.maximum(0.0, 1 - u * u))
    return np.stack([s * np.cos(2 * np.pi * v), s * np.sin(2 * np.pi * v), u], axis=1)


def sample_narrow_lobe(bsdf, theta_deg: float, n: int, seed: int):
    """n samples of a BSDF for a viewer at theta_deg: (wi, wo, pdf), float64
    arrays of the float32 values the plugin used."""
    rng = np.random.default_rng(seed)
    wi = f32(np.tile(direction(theta_deg), (n, 1)))
    bs, _ = bsdf.sample(mi.BSDFContext(), surface(wi), floats(rng.random(n)),
                        points(rng.random(n), rng.random(n)))
    return wi, f32(np.array(bs.wo).T), np.array(bs.pdf, dtype=np.float64)


# ----------------------------------------------------------------------------
#  Gradients
# ----------------------------------------------------------------------------


def finite_difference(make, x: float, h: float, side: str = "central") -> float:
    """(f(x + h) - f(x - h)) / 2h, or one-sided ("forward", "backward") at a bound;
    ``make(x)`` returns the value f(x)."""
    if side == "forward":
        return (make(x + h) - make(x)) / h
    if side == "backward":
        return (make(x) - make(x - h)) / h
    return (make(x + h) - make(x - h)) / (2 * h)


# ----------------------------------------------------------------------------
#  Variants
# ----------------------------------------------------------------------------


@contextlib.contextmanager
def active_variant(name: str):
    """Run the block in Mitsuba variant ``name`` with every plugin registered
    for it, then return to the previous variant and Dr.Jit's default flags
    (as Mitsuba's own variant fixtures do, without flushing the kernel cache)."""
    previous = mi.variant()
    mi.set_variant(name)
    mi_brdfs.register()
    try:
        yield name
    finally:
        dr.set_flag(dr.JitFlag.Default, True)
        mi.set_variant(previous)
