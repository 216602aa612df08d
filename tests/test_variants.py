"""Every variant the Mitsuba wheel ships on a CPU (and the cuda ones where a
GPU exists): every plugin loads, evaluates and samples finite, non-negative
values and passes one χ² test of its sampler; scalar_rgb gives llvm_ad_rgb's
values; polarized variants get depolarizers; ``mi-brdfs render -m scalar_rgb``
works. In every variant, every parameter takes every property form Mitsuba's
own plugins take, as they read it (``lambert`` with a <spectrum> is ``diffuse``
with it), and direct calls take what Mitsuba's bindings take (lists, tuples;
attributes). In scalar_rgb no degenerate input raises, and every value
llvm_ad_rgb gives 0 for is 0 (a plane lit from straight below renders black).
One subprocess per variant: a variant switch is global to a process.

Scalar variants have no vectorised χ² in Mitsuba (mi.chi2 needs JIT arrays), so
there a small χ² of the same kind runs sample() and pdf() lane by lane: the
histogram of 12,000 samples on a 6 x 12 (cos θ, φ) grid against pdf()
integrated over each cell, cells with fewer than 5 expected samples pooled.
Its significance is part of the suite-wide Šidák correction (support).
"""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from support import (CHI2_ALPHA, CPU_VARIANTS, GPU_VARIANTS, chi2_test_count,
                     degenerate_configs, degenerate_inputs, variant_chi2_cases)

POLARIZED = ["scalar_spectral_polarized", "llvm_ad_mono_polarized", "llvm_ad_spectral_polarized"]

SCRIPT = r'''
import json, math, sys
import numpy as np
import mi_brdfs, mitsuba as mi, drjit as dr
from scipy import stats

variant, alpha, test_count = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
cases, folder = json.loads(sys.argv[4]), sys.argv[6]
sys.path.insert(0, sys.argv[5])                 # the tests' support module
from support import (degenerate_configs, degenerate_lanes, direct_call_failures,
                     lambert_diffuse_difference, property_form_failures, update_failures)
from mi_brdfs.bsdfs.cases import ALL as CASES
rng = np.random.default_rng(7)
N = 64
v = rng.normal(size=(N, 3)); v /= np.linalg.norm(v, axis=1, keepdims=True); v[:, 2] = np.abs(v[:, 2])
w = rng.normal(size=(N, 3)); w /= np.linalg.norm(w, axis=1, keepdims=True); w[:, 2] = np.abs(w[:, 2])
U = rng.random((N, 3))


def lanes(bsdf):
    """eval, pdf, sample (wo, pdf, weight) at N fixed inputs, lane by lane."""
    out = {"eval": [], "pdf": [], "wo": [], "spdf": [], "weight": []}
    ctx = mi.BSDFContext()
    for k in range(N):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(*map(float, v[k]))
        si.uv = mi.Point2f(0.5, 0.5)
        if mi.is_spectral:
            si.wavelengths = mi.UnpolarizedSpectrum(550.0)
        wo = mi.Vector3f(*map(float, w[k]))
        value, pdf = bsdf.eval_pdf(ctx, si, wo)
        bs, weight = bsdf.sample(ctx, si, float(U[k, 0]), mi.Point2f(float(U[k, 1]), float(U[k, 2])))
        if mi.is_polarized:        # a depolarizer: only the first row's first entry
            m = np.array(value, dtype=np.float64).reshape(4, 4, -1)
            assert np.all(m.reshape(16, -1)[1:] == 0), "not a depolarizer"
            value, weight = m[0, 0], np.array(weight, dtype=np.float64).reshape(4, 4, -1)[0, 0]
        out["eval"].append(np.array(value, dtype=np.float64).ravel()[:3].tolist())
        out["pdf"].append(float(np.array(pdf).ravel()[0]))
        out["wo"].append(np.array(bs.wo, dtype=np.float64).ravel().tolist())
        out["spdf"].append(float(np.array(bs.pdf).ravel()[0]))
        out["weight"].append(np.array(weight, dtype=np.float64).ravel()[:3].tolist())
    return out


def scalar_chi2(bsdf, theta, n=12000, nt=6, nphi=12, sub=6):
    """The same test as Mitsuba's, lane by lane: a histogram of sample()
    against pdf() integrated over each (cos θ, φ) cell; p-value of χ²."""
    t = math.radians(theta)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(math.sin(t), 0.0, math.cos(t))
    if mi.is_spectral:
        si.wavelengths = mi.UnpolarizedSpectrum(550.0)
    ctx, r = mi.BSDFContext(), np.random.default_rng(11)
    counts = np.zeros((nt, nphi))
    for _ in range(n):
        bs, _ = bsdf.sample(ctx, si, float(r.random()), mi.Point2f(float(r.random()), float(r.random())))
        if float(np.array(bs.pdf).ravel()[0]) > 0:
            x, y, z = (float(c) for c in np.array(bs.wo).ravel())
            i = min(int(z * nt), nt - 1)
            j = min(int((math.atan2(y, x) % (2 * math.pi)) / (2 * math.pi) * nphi), nphi - 1)
            counts[i, j] += 1
    expected = np.zeros((nt, nphi))
    for i in range(nt):
        for j in range(nphi):
            total = 0.0
            for a in range(sub):
                for b in range(sub):
                    c = (i + (a + 0.5) / sub) / nt
                    p = (j + (b + 0.5) / sub) / nphi * 2 * math.pi
                    s = math.sqrt(max(0.0, 1 - c * c))
                    total += float(np.array(bsdf.pdf(ctx, si, mi.Vector3f(s * math.cos(p), s * math.sin(p), c))).ravel()[0])
            expected[i, j] = total / sub**2 * (1 / nt) * (2 * math.pi / nphi) * n
    obs, exp = counts.ravel(), expected.ravel()
    small = exp < 5
    obs = np.append(obs[~small], obs[small].sum() + (n - counts.sum()))
    exp = np.append(exp[~small], exp[small].sum() + max(n - expected.sum(), 0.0))
    keep = exp > 0
    chi2 = float(np.sum((obs[keep] - exp[keep]) ** 2 / exp[keep]))
    return float(stats.chi2.sf(chi2, keep.sum() - 1))


def jit_chi2(config, theta):
    t = math.radians(theta)
    sample_func, pdf_func = mi.chi2.BSDFAdapter(config["type"], config,
                                                wi=mi.ScalarVector3f(math.sin(t), 0.0, math.cos(t)))
    chi2 = mi.chi2.ChiSquareTest(domain=mi.chi2.SphericalDomain(), pdf_func=pdf_func,
                                 sample_func=sample_func, sample_dim=3,
                                 sample_count=200_000, res=51, ires=16)
    return bool(chi2.run(significance_level=alpha, test_count=test_count, quiet=True))


results = {}
mi.set_variant(variant)
mi_brdfs.register()
for config, theta in cases:
    bsdf = mi.load_dict(config)
    r = {"lanes": lanes(bsdf)}
    if not mi.is_polarized:
        if dr.is_jit_v(mi.Float):
            r["chi2"] = jit_chi2(config, theta)
        else:
            p = scalar_chi2(bsdf, theta)
            r["chi2"] = p > 1 - (1 - alpha) ** (1 / test_count)     # Šidák, as Mitsuba's
            r["p"] = p
    if variant != "llvm_ad_rgb":       # (the battery's variant runs them itself)
        r["forms"] = property_form_failures(config["type"], folder)
        r["calls"] = direct_call_failures(config)
    r["update"] = update_failures(CASES[config["type"]].interior[0])
    results[config["type"]] = r
checks = {}
if variant != "llvm_ad_rgb":
    checks["lambert vs diffuse"] = lambert_diffuse_difference(folder)
if variant == "scalar_rgb":
    checks["degenerate"] = [degenerate_lanes(mi.load_dict(c)) for c in degenerate_configs()]
    # a plane seen straight on (orthographic: every viewer exactly at the
    # normal), lit from straight behind: wo = -wi, the half vector 0
    scene = mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 2},
        "sensor": {"type": "orthographic", "film": {"type": "hdrfilm", "width": 2, "height": 2}},
        "plane": {"type": "rectangle", "bsdf": {"type": "cook_torrance", "distribution": "ggx"},
                  "to_world": mi.ScalarTransform4f().translate([0, 0, 1]).scale([1, -1, -1])},
        "light": {"type": "directional", "direction": [0, 0, -1]}})
    checks["lit from below"] = np.array(mi.render(scene), dtype=np.float64).ravel().tolist()
if variant == "scalar_rgb":            # the same values as llvm_ad_rgb
    mi.set_variant("llvm_ad_rgb")
    mi_brdfs.register()
    for config, _ in cases:
        results[config["type"]]["llvm"] = lanes(mi.load_dict(config))
    checks["degenerate llvm"] = [degenerate_lanes(mi.load_dict(c)) for c in degenerate_configs()]
print("RESULTS " + json.dumps({"plugins": results, "checks": checks}))
'''


def run_variant(variant: str, folder) -> tuple[dict, dict]:
    """({plugin: its results}, {check: result}) of the script in ``variant``."""
    cases = variant_chi2_cases()
    run = subprocess.run([sys.executable, "-c", SCRIPT, variant, str(CHI2_ALPHA),
                          str(chi2_test_count()), json.dumps(cases),
                          str(Path(__file__).parent), str(folder)],
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    line = next(line for line in run.stdout.splitlines() if line.startswith("RESULTS "))
    results = json.loads(line[len("RESULTS "):])
    return results["plugins"], results["checks"]


def check_scenes_and_calls(variant: str, results: dict, checks: dict) -> None:
    """Every parameter written through traverse; every property form, direct
    calls, and lambert = diffuse for the same <spectrum> and <rgb> to float
    precision (in llvm_ad_rgb: the battery and test_lambert check those)."""
    for name, r in results.items():
        assert not r["update"], f"{name} in {variant}:\n" + "\n".join(r["update"])
    if variant == "llvm_ad_rgb":
        return
    for name, r in results.items():
        assert not r["forms"], f"{name} in {variant}:\n" + "\n".join(r["forms"])
        assert not r["calls"], f"{name} in {variant}:\n" + "\n".join(r["calls"])
    assert checks["lambert vs diffuse"] < 1e-6, checks["lambert vs diffuse"]


def check_degenerate(checks: dict) -> None:
    """scalar_rgb at degenerate inputs: nothing raises, every value is finite
    and non-negative (directions aside), and 0 wherever llvm_ad_rgb gives 0."""
    for config, scalar, llvm in zip(degenerate_configs(), checks["degenerate"],
                                    checks["degenerate llvm"]):
        assert not scalar["errors"], f"{config}: " + "\n".join(scalar["errors"][:5])
        for key, values in scalar.items():
            if key == "errors":
                continue
            s, j = np.array(values), np.array(llvm[key])
            assert np.isfinite(s).all() and (key == "sample wo" or (s >= 0).all()), (config, key)
            if key == "sample wo":      # a failed sample (wo = 0) fails in both; a
                # component that is 0 in one and 1e-24 in the other is float32 noise
                lanes = np.flatnonzero((j == 0).all(axis=1) & (s != 0).any(axis=1))
            else:
                lanes = np.flatnonzero(((j == 0) & (s != 0)).any(axis=1))
            assert not lanes.size, (f"{config} {key}: 0 in llvm_ad_rgb, not in scalar_rgb at "
                                    f"{[degenerate_inputs()[k] for k in lanes[:3]]}")
    image = np.array(checks["lit from below"])
    assert np.isfinite(image).all() and (image == 0).all()


def check_lanes(lanes: dict) -> None:
    for key in ("eval", "pdf", "spdf", "weight"):
        a = np.array(lanes[key], dtype=np.float64)
        assert np.isfinite(a).all() and (a >= 0).all(), key
    assert np.isfinite(np.array(lanes["wo"])).all()
    # random pairs: a narrow lobe has pdf 0 (to float32) for many of them
    assert (np.array(lanes["pdf"]) > 0).any() and (np.array(lanes["spdf"]) > 0).mean() > 0.3


@pytest.mark.slow
@pytest.mark.parametrize("variant", CPU_VARIANTS + GPU_VARIANTS)
def test_every_plugin_in_every_variant(variant, tmp_path):
    results, checks = run_variant(variant, tmp_path)
    assert set(results) == {c[0]["type"] for c in variant_chi2_cases()}
    check_scenes_and_calls(variant, results, checks)
    if variant == "scalar_rgb":
        check_degenerate(checks)
    for name, r in results.items():
        check_lanes(r["lanes"])
        assert r["chi2"], f"{name}: χ² rejected its sampler in {variant} (p = {r.get('p')})"
    if variant == "scalar_rgb":
        for name, r in results.items():
            for key in ("eval", "pdf", "wo", "spdf", "weight"):
                np.testing.assert_allclose(np.array(r["lanes"][key]), np.array(r["llvm"][key]),
                                           rtol=1e-4, atol=1e-6, err_msg=f"{name} {key}")


@pytest.mark.parametrize("variant", POLARIZED)
def test_polarized_variants_get_depolarizers(variant, tmp_path):
    """eval and the sample weight are Mueller matrices with one non-zero entry,
    the unpolarized value (the script asserts it lane by lane); every property
    form and direct call as in the other variants."""
    results, checks = run_variant(variant, tmp_path)
    for name, r in results.items():
        check_lanes(r["lanes"])
    check_scenes_and_calls(variant, results, checks)


def test_render_in_scalar_rgb(tmp_path):
    """The command line renders a bundled scene in the scalar variant."""
    out = tmp_path / "course.exr"
    run = subprocess.run([sys.executable, "-m", "mi_brdfs", "render", "course", "-m", "scalar_rgb",
                          "-D", "res=8", "--spp", "1", "-o", str(out), "-q"],
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-2000:]
    import mitsuba as mi
    image = np.array(mi.Bitmap(str(out)))
    assert image.shape[:2] == (8, 8) and np.isfinite(image).all() and image.max() > 0


def bitmap_reflectance(value: float) -> dict:
    """A 4 x 4 RGB bitmap texture of one grey value (a new mi.Bitmap each time:
    in spectral variants the texture upsamples the bitmap it is given in place)."""
    import mitsuba as mi
    return {"type": "bitmap", "bitmap": mi.Bitmap(np.full((4, 4, 3), value, dtype=np.float32))}


@pytest.mark.parametrize("variant", ["llvm_ad_spectral", "scalar_spectral"])
def test_spectral_bitmap_above_one(variant, capfd):
    """In spectral variants a bitmap's values above 1 are clamped to 1 when the
    texture is built, as for Mitsuba's diffuse: lambert reads it as diffuse
    does, and says so once, naming itself and the parameter; a bitmap below 1
    gets no word."""
    import drjit as dr
    import mitsuba as mi
    from support import active_variant
    with active_variant(variant):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi, si.uv = mi.Vector3f(0, 0, 1), mi.Point2f(0.5, 0.5)
        si.wavelengths = mi.UnpolarizedSpectrum(550.0)
        capfd.readouterr()
        values = {}
        for value in (3.0, 0.5):
            for plugin in ("diffuse", "lambert"):
                bsdf = mi.load_dict({"type": plugin, "reflectance": bitmap_reflectance(value)})
                values[plugin, value] = np.array(bsdf.eval(mi.BSDFContext(), si,
                                                           mi.Vector3f(0.0, 0.6, 0.8)))
                said = "".join(capfd.readouterr())        # (Mitsuba logs to stdout)
                if plugin == "lambert":
                    warned = "lambert: parameter 'reflectance': 16 pixel(s)" in said
                    assert warned == (value > 1), said
                    assert said.count("spectral upsampling clamps") == (value > 1), said
        for value in (3.0, 0.5):
            np.testing.assert_allclose(values["lambert", value], values["diffuse", value],
                                       rtol=1e-6)
        np.testing.assert_allclose(values["lambert", 3.0], 0.8 / np.pi, rtol=1e-5)


def test_plain_numbers_read_as_floats_in_scalar_variants():
    """In scalar variants every plain-number parameter of every plugin reads as
    a Python float through mi.traverse, as a built-in's does (dielectric's eta),
    and can be written and updated: the new value is what the plugin uses, and
    a bad one is refused at update() as at load time."""
    import mitsuba as mi
    from mi_brdfs.bsdfs import PLUGINS
    from mi_brdfs.bsdfs.params import ParameterError
    from support import active_variant
    with active_variant("scalar_rgb"):
        assert type(mi.traverse(mi.load_dict({"type": "dielectric"}))["eta"]) is float
        plain = [(cls.name, p) for cls in PLUGINS for p in cls.PARAMS if p.kind == "float"]
        assert plain                                     # (k, f0, smoothness)
        for name, p in plain:
            bsdf = mi.load_dict({"type": name, p.name: p.default})     # (optional ones: given)
            params = mi.traverse(bsdf)
            assert type(params[p.name]) is float, (name, p.name, type(params[p.name]))
            value = 0.5 * (p.lo + p.probe_hi())
            params[p.name] = value
            params.update()
            assert params[p.name] == pytest.approx(value)
            assert getattr(bsdf, "m_" + p.name) == pytest.approx(value)
            params[p.name] = p.hi + 1.0 if p.hi is not None else p.lo - 1.0
            with pytest.raises(ParameterError, match=f"{name}: parameter '{p.name}'"):
                params.update()
