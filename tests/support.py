"""Test helpers, in one place: directions, evaluation, the chi-square test, the
white-furnace quadrature, finite differences.

Every helper is independent of the plugins' own sampling (the furnace
quadrature, the direction generators) so that a wrong sampler or pdf cannot
hide an error elsewhere.
"""
from __future__ import annotations

import contextlib
import math
import os
import subprocess
import sys

import numpy as np

import mi_brdfs  # noqa: F401  (LLVM set-up, variant, plugin registration)
import drjit as dr
import mitsuba as mi
from mi_brdfs._jit import from_numpy

# ----------------------------------------------------------------------------
#  A fresh process
# ----------------------------------------------------------------------------

FRESH_START = ("import mitsuba as mi; mi.set_variant('llvm_ad_rgb');"
               "import mi_brdfs; mi_brdfs.register();")


def fresh_python(script: str, *args: str) -> subprocess.CompletedProcess:
    """``script`` (one line, ``;``-separated) run with ``args`` by a new Python
    process on this one's path, after FRESH_START; its output captured as text,
    the test failed if it fails. For what lasts a process's life (the garbage
    collector's freeze, state read once per process)."""
    return subprocess.run([sys.executable, "-c", FRESH_START + script, *args], check=True,
                          capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})


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


def vec(a) -> mi.Vector3f:
    return from_numpy(mi.Vector3f, np.asarray(a, dtype=np.float64).T)


def floats(a) -> mi.Float:
    return from_numpy(mi.Float, a)


def points(x, y) -> mi.Point2f:
    return from_numpy(mi.Point2f, (x, y))


def tensor(a) -> mi.TensorXf:
    """A NumPy array as a Dr.Jit tensor of the same shape (through from_numpy)."""
    a = np.asarray(a)
    return mi.TensorXf(floats(a.ravel()), a.shape)


def surface(wi, uv=None) -> mi.SurfaceInteraction3f:
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = vec(wi)
    si.uv = mi.Point2f(0.5, 0.5) if uv is None else points(uv[:, 0], uv[:, 1])
    return si


def eval_and_pdf(bsdf, wi, wo, uv=None, ctx=None):
    """eval (n, 3) and pdf (n,) of a BSDF on direction pairs (NumPy in and out,
    float64), in the context ``ctx`` (default: every lobe)."""
    ctx = ctx or mi.BSDFContext()
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
    values out of range in a spectrum or a texture are refused with one line. Returns the
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
            refused(p, '<texture type="checkerboard" name="NAME"><float name="color0" '
                    f'value="0.5"/><float name="color1" value="{bad:g}"/></texture>', repr(bad))
    return failures


# ----------------------------------------------------------------------------
#  Direct calls, updates, degenerate inputs (every variant, one lane at a time)
# ----------------------------------------------------------------------------

def interaction(wi) -> mi.SurfaceInteraction3f:
    """A surface interaction for viewer ``wi`` (one 3-vector, or an (n, 3)
    array in JIT variants), at uv (0.5, 0.5); fixed wavelengths in spectral
    variants."""
    wi = np.asarray(wi, dtype=np.float64)
    if wi.ndim == 2:
        si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
        si.wi = vec(wi)
    else:
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(*map(float, wi))
    si.uv = mi.Point2f(0.5, 0.5)
    if mi.is_spectral:
        si.wavelengths = mi.UnpolarizedSpectrum(*[mi.Float(w) for w in (450, 520, 610, 680)])
    return si


def outputs(bsdf, si, wo, sample1, sample2) -> dict[str, np.ndarray]:
    """eval, pdf, eval_pdf and sample (direction, pdf, weight), as float64
    NumPy arrays of shape (values per lane, lanes)."""
    ctx = mi.BSDFContext()
    value, pdf = bsdf.eval_pdf(ctx, si, wo)
    bs, weight = bsdf.sample(ctx, si, sample1, sample2)
    out = {"eval": bsdf.eval(ctx, si, wo), "pdf": bsdf.pdf(ctx, si, wo), "eval_pdf value": value,
           "eval_pdf pdf": pdf, "sample wo": bs.wo, "sample pdf": bs.pdf, "sample weight": weight}
    dr.eval(*out.values())                # one kernel in JIT variants
    lanes = dr.width(si.wi.x)             # (1 in scalar variants)
    return {k: np.array(v, dtype=np.float64).reshape(-1, lanes) for k, v in out.items()}


def lambert_diffuse_difference(folder) -> float:
    """The largest relative difference between ``lambert`` and Mitsuba's
    ``diffuse`` given the same <spectrum> (constant, wavelength:value pairs, a
    file) and the same <rgb>, over eval, pdf and sample at a few inputs."""
    forms = property_forms(folder)
    rng = np.random.default_rng(5)
    worst = 0.0
    for form in ("spectrum", "pairs", "file", "rgb"):
        ours, theirs = (load_form(t, "reflectance", forms[form]) for t in ("lambert", "diffuse"))
        for _ in range(4):
            wi, wo = (unit(np.abs(rng.normal(size=3))) for _ in range(2))
            u = rng.random(3)
            args = (interaction(wi), mi.Vector3f(*map(float, wo)), float(u[0]),
                    mi.Point2f(float(u[1]), float(u[2])))
            a, b = outputs(ours, *args), outputs(theirs, *args)          # (one lane)
            for key in a:
                scale = max(np.abs(b[key]).max(), 1e-30)
                worst = max(worst, float(np.abs(a[key] - b[key]).max() / scale))
    return worst


def direct_call_failures(config: dict) -> list[str]:
    """Direct calls as Mitsuba's bindings take them for its own plugins:
    Python lists and tuples for ``sample2`` and ``wo`` give what the Dr.Jit
    types give; ``has_attribute``/``eval_attribute*`` answer as ``diffuse``
    does: each parameter is an attribute (a texture's value; a plain
    number's through eval_attribute_1), an unknown name is none (0 in JIT
    variants, an exception in scalar ones). Returns the failures."""
    bsdf, diffuse = mi.load_dict(config), mi.load_dict({"type": "diffuse"})
    si = interaction(unit(np.array([0.5, 0.1, 0.7])))
    wo = unit(np.array([-0.3, 0.2, 0.9])).tolist()
    failures = []
    typed = outputs(bsdf, si, mi.Vector3f(*wo), mi.Float(0.5), mi.Point2f(0.3, 0.4))
    for kind in (list, tuple):
        try:
            given = outputs(bsdf, si, kind(wo), 0.5, kind([0.3, 0.4]))
        except Exception as e:
            failures.append(f"{kind.__name__} arguments: {type(e).__name__}: {e}")
            continue
        for key, value in typed.items():
            if not np.array_equal(given[key], value):            # (one lane each)
                failures.append(f"{key} with {kind.__name__} arguments: {given[key]} != {value}")

    def answer(b, method: str, name: str):
        try:
            return np.array(getattr(b, method)(name, si), dtype=np.float64).ravel()
        except RuntimeError:
            return "raises"
    for name, p in bsdf.state.params.items():
        if not bool(np.array(bsdf.has_attribute(name)).ravel()[0]):
            failures.append(f"has_attribute({name!r}) is false")
        one = answer(bsdf, "eval_attribute_1", name)
        if p.kind == "float" and not (isinstance(one, np.ndarray) and np.allclose(
                one, np.array(mi.traverse(bsdf)[name], dtype=np.float64).ravel())):
            failures.append(f"eval_attribute_1({name!r}) = {one}, not its value")
    for method in ("eval_attribute", "eval_attribute_1", "eval_attribute_3"):
        ours, theirs = answer(bsdf, method, "nonsense"), answer(diffuse, method, "nonsense")
        if type(ours) is not type(theirs) or (isinstance(ours, np.ndarray)
                                              and not np.array_equal(ours, theirs)):
            failures.append(f"{method}('nonsense') = {ours}; diffuse: {theirs}")
    if bool(np.array(bsdf.has_attribute("nonsense")).ravel()[0]):
        failures.append("has_attribute('nonsense') is true")
    return failures


def update_failures(config: dict) -> list[str]:
    """Every parameter ``config`` gives as a number, written through
    mi.traverse (plain numbers and uniform textures alike, in every variant)
    to another valid value: after update() the BSDF gives what a fresh load
    with those values gives, at a few inputs. Returns the failures."""
    bsdf = mi.load_dict(config)
    params, changed, failures = mi.traverse(bsdf), {}, []
    for p in bsdf.state.params.values():
        if isinstance(config.get(p.name), float):
            lo = p.lo if p.lo is not None else -1.0
            changed[p.name] = lo + 0.37 * (p.probe_hi() - lo)
            try:
                params[p.name if p.kind == "float" else p.name + ".value"] = changed[p.name]
            except Exception as e:
                failures.append(f"{p.name}: not writable: {type(e).__name__}: {e}")
    params.update()
    fresh = mi.load_dict({**config, **changed})
    rng = np.random.default_rng(3)
    for _ in range(4):
        wi = unit(np.abs(rng.normal(size=3)))
        wo = wi * [-1, -1, 1] + 0.2 * rng.normal(size=3)          # near the highlight
        wo[2] = abs(wo[2])
        args = (interaction(wi), mi.Vector3f(*map(float, unit(wo))), float(rng.random()),
                mi.Point2f(*map(float, rng.random(2))))
        a, b = outputs(bsdf, *args), outputs(fresh, *args)
        for key in a:
            if not np.allclose(a[key], b[key], rtol=1e-5, atol=1e-7):
                failures.append(f"{key} after update: {a[key].ravel()} != {b[key].ravel()}")
    return failures


# Degenerate inputs: viewers at the normal, oblique, on the horizon (along s
# and t), 1e-30 above it, below, and the zero vector; lights opposite the
# viewer (the half vector 0), the zero vector, on the horizon and mirrored;
# samples at the corners and edges of the unit square.
DEGENERATE_VIEWERS = [(0, 0, 1), (0.6, 0, 0.8), (1, 0, 0), (0, 1, 0), (1, 0, 1e-30),
                      (0, 0, -1), (0, 0, 0)]
DEGENERATE_SAMPLES = [(s1, s2) for s1 in (0.0, 1.0)
                      for s2 in ((0, 0), (0, 1), (1, 0), (1, 1), (0.5, 1), (1, 0.5), (0.5, 0))]


def degenerate_inputs() -> list[tuple]:
    """(wi, wo, sample1, sample2): each viewer against each light (-wi, 0, the
    horizon along s and t, the mirror direction), and the first three viewers
    against -wi with every sample of :data:`DEGENERATE_SAMPLES`."""
    inputs = []
    for i, wi in enumerate(DEGENERATE_VIEWERS):
        x, y, z = wi
        lights = [(-x, -y, -z), (0, 0, 0), (1, 0, 0), (0, -1, 0), (-x, -y, z)]
        inputs += [(wi, wo) + DEGENERATE_SAMPLES[(5 * i + k) % len(DEGENERATE_SAMPLES)]
                   for k, wo in enumerate(lights)]
        if i < 3:
            inputs += [(wi, lights[0], s1, s2) for s1, s2 in DEGENERATE_SAMPLES]
    return inputs


def degenerate_configs() -> list[dict]:
    """Every plugin in both modes, every microfacet distribution and geometry,
    both microfacet samplers, anisotropic roughness, energy compensation, and
    the models' options."""
    from mi_brdfs.bsdfs import BY_NAME
    from mi_brdfs.bsdfs.microfacet import DISTRIBUTIONS, GEOMETRIES
    ct = {"type": "cook_torrance", "k": 0.2}
    return ([{"type": name, "mode": mode} for name in BY_NAME for mode in ("hdr", "scanline")]
            + [{**ct, "distribution": d, "geometry": g, "sample_visible": v}
               for d in DISTRIBUTIONS for g in GEOMETRIES for v in (True, False)
               if v or (d != "blinn" and g == "smith")]
            + [{"type": name, "energy_compensation": True}
               for name, cls in BY_NAME.items() if cls.compensable]
            + [{**ct, "distribution": d, "alpha_u": 0.05, "alpha_v": 0.3, "sample_visible": v}
               for d in ("beckmann", "ggx") for v in (True, False)]
            + [{"type": "ward", "alpha_u": 0.05, "alpha_v": 0.3, "formula": "angles"},
               {"type": "toon", "specular_model": "blinn", "smoothness": 0.2},
               {"type": "oren_nayar", "method": "table"}])


def degenerate_lanes(bsdf) -> dict[str, list]:
    """:func:`outputs` at every :func:`degenerate_inputs`, lane by lane (one
    call each in scalar variants, one vectorised call in JIT ones): {output:
    [values of each lane]}, and "errors": the exceptions raised, as text."""
    inputs = degenerate_inputs()
    wi, wo, s1, s2 = (np.array([i[k] for i in inputs], dtype=np.float64) for k in range(4))
    if dr.is_jit_v(mi.Float):
        values = outputs(bsdf, interaction(wi), vec(wo), floats(s1), points(s2[:, 0], s2[:, 1]))
        return {"errors": [], **{k: v.T.tolist() for k, v in values.items()}}
    out: dict[str, list] = {"errors": []}
    for k in range(len(inputs)):
        try:
            values = outputs(bsdf, interaction(wi[k]), mi.Vector3f(*map(float, wo[k])),
                             float(s1[k]), mi.Point2f(*map(float, s2[k])))
        except Exception as e:
            out["errors"].append(f"{inputs[k]}: {type(e).__name__}: {e}")
            continue
        for key, value in values.items():
            out.setdefault(key, []).append(value[:, 0].tolist())
    return out


# ----------------------------------------------------------------------------
#  Chi-square (Mitsuba's test, as its own BSDF tests use it)
# ----------------------------------------------------------------------------

CHI2_SAMPLES = 1_000_000
CHI2_ALPHA = 0.01      # the probability that the whole suite rejects a correct sampler
# The variants whose χ² runs in tests/test_variants.py (cuda ones only with a GPU).
CPU_VARIANTS = ["scalar_rgb", "scalar_spectral", "llvm_ad_rgb", "llvm_ad_mono", "llvm_ad_spectral"]
GPU_VARIANTS = ["cuda_ad_rgb", "cuda_ad_spectral"] if dr.has_backend(dr.JitBackend.CUDA) else []


def variant_chi2_cases() -> list[tuple[dict, float]]:
    """One χ² configuration per plugin for the variants test: its cases'
    first, at its second incident angle."""
    from mi_brdfs.bsdfs.cases import ALL as CASES
    out = []
    for cls in mi_brdfs.PLUGINS:
        case = CASES[cls.name].chi2[0]
        out.append((case.config, case.thetas[min(1, len(case.thetas) - 1)]))
    return out


def chi2_test_count() -> int:
    """Every χ² test of the suite, for one Šidák correction: the battery's
    cases' runs and negative controls, the blends' and the variants'. (An entry that
    cannot be built runs none: its own tests fail.)"""
    from mi_brdfs.bsdfs import cases
    entries = []
    for cls in mi_brdfs.PLUGINS:
        try:
            entries.append(cases.of(cls.name))
        except Exception:
            pass
    battery = sum(len(c.thetas) for e in entries for c in e.chi2)
    negative = sum(1 for e in entries if e.negative)
    blends = len(mi_brdfs.PLUGINS)       # one blendbsdf χ² per plugin (blend_chi2_configs)
    return battery + negative + blends + len(CPU_VARIANTS + GPU_VARIANTS) * len(mi_brdfs.PLUGINS)


class BrokenCases:
    """Stands for the test cases of a plugin whose cases cannot be
    built: conftest's pytest_pyfunc_call fails each such case with the error."""

    def __init__(self, name: str, error: Exception):
        self.name, self.error = name, error

    def __repr__(self) -> str:
        return f"BrokenCases({self.name!r})"


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
#  Every plugin at one configuration: adapters, dispatch, renders
# ----------------------------------------------------------------------------

BLEND_WEIGHT = 0.2        # the weight of the second BSDF (Mitsuba's blendbsdf tests use 0.2)


def plugin_configs() -> dict[str, dict]:
    """{name: configuration} for every registered plugin, in the registry's
    order: the first interior configuration of its cases without
    energy compensation (hdr; each parameter given as a number, away from its
    bounds and from the model's kinks)."""
    from mi_brdfs.bsdfs.cases import ALL as CASES
    return {cls.name: dict(next(c for c in CASES[cls.name].interior     # (a copy: Mitsuba
                                if not c.get("energy_compensation")))   # loads a dict once)
            for cls in mi_brdfs.PLUGINS}


def moved(config: dict) -> dict:
    """``config`` with every parameter it gives as a number moved 40 % of the
    way towards the lower end of its range: another configuration of the same
    plugin (another side of a surface, another scene), still valid and interior."""
    from mi_brdfs.bsdfs import BY_NAME
    out = dict(config)
    for p in BY_NAME[config["type"]].PARAMS:
        if isinstance(config.get(p.name), float):
            out[p.name] = p.lo + 0.6 * (config[p.name] - p.lo)
    return out


def numbers(config: dict) -> dict[str, float]:
    """The parameters ``config`` gives as numbers: {name: value}."""
    return {k: v for k, v in config.items() if isinstance(v, float)}


def neighbour(name: str) -> str:
    """The plugin after ``name`` in the registry (the last one's is the first):
    a partner of another kind for adapters that hold two BSDFs."""
    names = [cls.name for cls in mi_brdfs.PLUGINS]
    return names[(names.index(name) + 1) % len(names)]


def twosided(front: dict, back: dict | None = None) -> dict:
    """Mitsuba's ``twosided`` around ``front`` (on both sides, mirrored) or
    with ``back`` on the back side."""
    return {"type": "twosided", "front": front, **({"back": back} if back else {})}


def blend(first: dict, second: dict, weight=BLEND_WEIGHT) -> dict:
    """Mitsuba's ``blendbsdf``: (1 - weight) · first + weight · second."""
    return {"type": "blendbsdf", "weight": weight, "bsdf_0": first, "bsdf_1": second}


def blend_chi2_configs() -> dict[str, dict]:
    """{plugin: blendbsdf config}: every plugin (:func:`plugin_configs`)
    blended with weight :data:`BLEND_WEIGHT` into Mitsuba's ``roughdielectric``
    (α 0.5), whose sampler the blend mixes with the plugin's; the χ² of each
    runs at :data:`BLEND_CHI2_THETA` (tests/bsdfs/test_adapters.py)."""
    return {name: blend(config, {"type": "roughdielectric", "alpha": 0.5})
            for name, config in plugin_configs().items()}


BLEND_CHI2_THETA = 50.0      # the viewer of the blends' χ² tests, degrees


def mirrored(v: np.ndarray) -> np.ndarray:
    """Directions reflected through the surface (z negated)."""
    return v * [1.0, 1.0, -1.0]


def sampled(bsdf, wi, rng, ctx=None) -> dict[str, np.ndarray]:
    """sample() at viewers ``wi`` (NumPy, (n, 3)) with uniform random numbers
    from ``rng``, and eval_pdf, eval and pdf at the sampled directions, in the
    context ``ctx``: {"wo" (n, 3), "pdf" (n,), "weight" (n, 3), "value"
    (n, 3), "value_pdf" (n,), "eval" (n, 3), "pdf_at" (n,), "u" the numbers}
    as float64."""
    ctx = ctx or mi.BSDFContext()
    n = len(wi)
    u = rng.random((n, 3))
    si = surface(wi)
    bs, weight = bsdf.sample(ctx, si, floats(u[:, 0]), points(u[:, 1], u[:, 2]))
    value, value_pdf = bsdf.eval_pdf(ctx, si, bs.wo)
    out = {"wo": bs.wo, "pdf": bs.pdf, "weight": weight, "value": value, "value_pdf": value_pdf,
           "eval": bsdf.eval(ctx, si, bs.wo), "pdf_at": bsdf.pdf(ctx, si, bs.wo)}
    dr.eval(*out.values())
    out = {k: np.array(v, dtype=np.float64) for k, v in out.items()}
    out = {k: v.T if v.ndim == 2 else v for k, v in out.items()}
    return {**out, "u": u}


def assert_weight_is_value_over_pdf(s: dict[str, np.ndarray], what: str = "") -> None:
    """A :func:`sampled` record is consistent: eval_pdf is (eval, pdf); where
    the sample holds (pdf > 0) weight · pdf = eval and pdf() is the sample's
    pdf; a failed sample weighs 0. Tolerances of the battery."""
    np.testing.assert_allclose(s["value"], s["eval"], rtol=1e-6, atol=1e-8, err_msg=what)
    np.testing.assert_allclose(s["value_pdf"], s["pdf_at"], rtol=1e-6, atol=1e-8, err_msg=what)
    ok = s["pdf"] > 0
    assert ok.mean() > 0.3, f"{what}: {ok.mean():.0%} of the samples hold"
    np.testing.assert_allclose(s["weight"][ok] * s["pdf"][ok, None], s["value"][ok],
                               rtol=1e-4, atol=1e-6, err_msg=what)
    np.testing.assert_allclose(s["pdf_at"][ok], s["pdf"][ok], rtol=1e-4, err_msg=what)
    assert not s["weight"][~ok].any(), what


TILE_PIXELS = 6           # pixels along each side of a tile of tiles_scene


def tiles_scene(bsdfs: dict[str, dict], integrator: dict, spp: int = 4,
                env: float = 0.0, backs=()) -> dict:
    """A row of unit square tiles in the plane z = 0, one per BSDF (keyed by
    name: the tile's shape is that name), seen from straight above (a camera
    whose view spans the row: the plane maps linearly onto the image) so that
    tile i fills the columns [i, i + 1) × :data:`TILE_PIXELS`. Above each
    tile, at height 0.5, a point light: a tile sees its own light from its
    normal to 55° and the other tiles' lights towards grazing. With ``env``,
    a constant environment too; the tiles named in ``backs`` are turned over
    (their back faces the camera and the lights). (Not Mitsuba's orthographic
    camera: 3.9.1's does not record in a frozen function.)"""
    T = mi.ScalarTransform4f
    k = len(bsdfs)
    height = max(4.0, k / 2)          # (a field of view of at most 90°)
    scene = {"type": "scene", "integrator": integrator,
             "sensor": {"type": "perspective", "fov_axis": "x",
                        "fov": 2 * math.degrees(math.atan(k / 2 / height)),
                        "to_world": T().look_at(origin=[0, 0, height], target=[0, 0, 0],
                                                up=[0, 1, 0]),
                        "film": {"type": "hdrfilm", "width": k * TILE_PIXELS,
                                 "height": TILE_PIXELS, "rfilter": {"type": "box"}},
                        "sampler": {"type": "independent", "sample_count": spp}}}
    for i, (name, bsdf) in enumerate(bsdfs.items()):
        x = i - (k - 1) / 2
        scene[name] = {"type": "rectangle", "bsdf": bsdf,
                       "to_world": T().translate([x, 0.0, 0.0]) @ T().scale(0.5)
                       @ T().rotate([1, 0, 0], 180 if name in backs else 0)}
        scene[f"{name}_light"] = {"type": "point", "position": [x, 0.0, 0.5],
                                  "intensity": {"type": "rgb", "value": 0.5}}
    if env:
        scene["env"] = {"type": "constant", "radiance": {"type": "rgb", "value": env}}
    return scene


def tile(image, i: int):
    """The pixels of tile i of a :func:`tiles_scene` image (a tensor or array)."""
    return image[:, i * TILE_PIXELS:(i + 1) * TILE_PIXELS]


@contextlib.contextmanager
def jit_flags(flags: dict):
    """Run the block with these Dr.Jit flags ({dr.JitFlag: bool}), then restore them."""
    before = {flag: dr.flag(flag) for flag in flags}
    for flag, value in flags.items():
        dr.set_flag(flag, value)
    try:
        yield
    finally:
        for flag, value in before.items():
            dr.set_flag(flag, value)


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
    return eval_and_pdf(bsdf, wi, wo)[0].T @ W


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
