"""mi-brdfs explore, in this process: the materials it accepts and writes,
the views it computes (against NumPy and physics), its kernel reuse, its
worker's newest-request rule and its fit. The server and the page:
test_explore_server.py and test_explore_browser.py."""
from __future__ import annotations

import gc
import math
import threading
import time

import numpy as np
import pytest

pytest.importorskip("aiohttp")

import drjit as dr                       # noqa: E402
import mitsuba as mi                     # noqa: E402
from support import random_hemisphere, surface, vec   # noqa: E402

import mi_brdfs                          # noqa: E402
from mi_brdfs.tools.explore import material as M       # noqa: E402
from mi_brdfs.tools.explore.backend import MaterialError   # noqa: E402
from mi_brdfs.tools.explore.session import ALBEDO_ANGLES, Explorer, hemispherical   # noqa: E402
from mi_brdfs.tools.explore.worker import Worker       # noqa: E402

BUILTINS = ("diffuse", "roughconductor", "roughplastic", "principled")


@pytest.fixture(scope="module")
def ex():
    explorer = Explorer()
    yield explorer
    # No BSDF of the explorer may outlive the module: a live BSDF outside a
    # scene stops frozen renders of later tests (see render/frozen.py).
    del explorer
    gc.collect()


# ----------------------------------------------------------------------------
#  Models and materials
# ----------------------------------------------------------------------------

def test_models_are_every_plugin_and_the_builtins(ex):
    names = [m["name"] for m in ex.public_models()]
    assert names == [cls.name for cls in mi_brdfs.PLUGINS] + list(BUILTINS)
    ct = ex.models["cook_torrance"]
    alpha = next(p for p in ct["params"] if p["name"] == "alpha")
    assert (alpha["kind"], alpha["default"], alpha["lo"], alpha["hi"], alpha["control"]) == \
        ("scalar", 0.3, 0.0, None, True)
    distribution = next(o for o in ct["options"] if o["name"] == "distribution")
    assert distribution["choices"] == ["blinn", "beckmann", "ggx"]
    # Ward's anisotropic roughness is not exposed with the defaults: no control
    ward = {p["name"]: p["control"] for p in ex.models["ward"]["params"]}
    assert ward["alpha"] and not ward["alpha_u"] and not ward["alpha_v"]


def test_the_parameters_an_option_exposes_have_controls_with_that_choice(ex):
    when = {p["name"]: (p["control"], p.get("when")) for p in ex.models["cook_torrance"]["params"]}
    assert when["eta"] == when["kappa"] == (False, {"fresnel": ["conductor"]})
    assert when["int_ior"] == when["ext_ior"] == (False, {"fresnel": ["dielectric"]})
    assert when["f82_tint"] == (False, {"fresnel": ["f82"]})
    assert when["alpha"] == (True, None)
    # no other course model has a parameter that only an option exposes
    others = [(m["name"], p["name"]) for m in ex.public_models() if m["name"] != "cook_torrance"
              for p in m["params"] if "when" in p]
    assert others == []


def test_a_new_eta_goes_through_traverse_and_equals_roughconductor(ex):
    """The conductor's index is a parameter of the configuration: a new value
    reuses the loaded BSDF (no load per slider step) and takes effect, as
    Mitsuba's roughconductor with the same index shows."""
    base = {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith",
            "fresnel": "conductor", "k": 0.0, "alpha": 0.25, "kappa": [3.0, 2.5, 2.0]}
    _, first = ex.prepare({**base, "eta": [0.2, 0.4, 1.1]})
    _, second = ex.prepare({**base, "eta": [1.5, 0.9, 0.3]})
    assert second is first
    rng = np.random.default_rng(5)
    wi, wo = random_hemisphere(rng, 64, 0.05), random_hemisphere(rng, 64, 0.05)
    si = surface(wi)
    ours = np.array(second.bsdf.eval(mi.BSDFContext(), si, vec(wo)))
    theirs = np.array(mi.load_dict({
        "type": "roughconductor", "distribution": "ggx", "alpha": 0.25,
        "eta": {"type": "rgb", "value": [1.5, 0.9, 0.3]},
        "k": {"type": "rgb", "value": [3.0, 2.5, 2.0]}}).eval(mi.BSDFContext(), si, vec(wo)))
    assert np.abs(theirs).max() > 0.1
    assert np.allclose(ours, theirs, rtol=1e-4, atol=1e-5)


def test_a_material_is_completed_with_the_defaults(ex):
    m = M.complete(ex.models, {"type": "cook_torrance", "alpha": 1, "diffuse_reflectance": 0.2})
    assert list(m)[:2] == ["type", "mode"] and m["mode"] == "hdr"
    assert m["alpha"] == 1.0 and isinstance(m["alpha"], float)
    assert m["diffuse_reflectance"] == [0.2, 0.2, 0.2] and m["k"] == 0.5
    assert m["distribution"] == "beckmann" and m["energy_compensation"] is False


@pytest.mark.parametrize("raw, message", [
    ([1, 2], "a material is a JSON object, not [1, 2]"),
    ({"type": "nonesuch"}, 'model "nonesuch" is unknown; valid: lambert, oren_nayar'),
    ({"type": "phong", "shininess": 3}, "phong has no option or parameter 'shininess'; valid: "
                                        "mode, sampling, energy_compensation, diffuse_reflectance"),
    ({"type": "phong", "mode": "flat"}, "phong: option 'mode' = \"flat\" is invalid; valid: "
                                        "one of hdr, scanline"),
    ({"type": "cook_torrance", "geometry": "x"}, "cook_torrance: option 'geometry' = \"x\" is "
                                                 "invalid; valid: one of cook_torrance, smith"),
    ({"type": "cook_torrance", "k": "half"}, "cook_torrance: parameter 'k' = \"half\" is invalid; "
                                             "valid: a finite number"),
    ({"type": "lambert", "reflectance": [1, 2]}, "lambert: parameter 'reflectance' = [1, 2] is "
                                                 "invalid; valid: a finite number or a list of three"),
    ({"type": "lambert", "reflectance": math.inf}, "lambert: parameter 'reflectance' = inf is "
                                                   "invalid; valid: a finite number"),
    ({"type": "oren_nayar", "table_resolution": 1}, "oren_nayar: option 'table_resolution' = 1 "
                                                    "is invalid; valid: an integer in"),
    ({"type": "roughconductor", "alpha": -0.5}, "roughconductor: parameter 'alpha' = -0.5 is "
                                                "invalid; valid: [0, inf]"),
    ({"type": "diffuse", "reflectance": [0.5, 1.5, 0]}, "diffuse: parameter 'reflectance' = 1.5 "
                                                        "is invalid; valid: [0, 1]"),
])
def test_a_bad_material_is_one_line_naming_what_is_wrong(ex, raw, message):
    with pytest.raises(M.RequestError) as error:
        M.complete(ex.models, raw)
    assert str(error.value).startswith(message) and "\n" not in str(error.value)


@pytest.mark.parametrize("raw, message", [
    ({"type": "cook_torrance", "alpha": -1}, "cook_torrance: parameter 'alpha' = -1.0 is invalid; "
                                             "valid: [0, 3.402823e+38]"),
    ({"type": "phong", "exponent": 1e9}, "phong: parameter 'exponent' = 1000000000.0 is invalid; "
                                         "valid: [0, 1e+08]"),
    ({"type": "ward", "alpha_u": 0.1}, "ward: parameter 'alpha' = "),
    ({"type": "phong", "mode": "scanline", "energy_compensation": True},
     "phong: parameter 'energy_compensation' = True is invalid; valid: false with mode=\"scanline\""),
])
def test_the_plugins_own_checks_give_the_loaders_message(ex, raw, message):
    """Range checks of the course plugins are the loader's, at a new
    configuration and at a new value of a loaded one alike."""
    ex.plots({"type": raw["type"]}, 30.0)                 # the configuration is loaded
    with pytest.raises(MaterialError) as error:
        ex.plots(raw, 30.0)
    assert str(error.value).startswith(message) and "\n" not in str(error.value)
    ex.plots({"type": raw["type"]}, 30.0)                 # and it still works


VARIED = {
    "lambert": {"reflectance": [0.7, 0.3, 0.1]},
    "oren_nayar": {"sigma": 0.6, "method": "table", "table_resolution": 32},
    "toon": {"smoothness": 0.3, "specular_model": "blinn", "diffuse_shade": [0.1, 0.2, 0.3]},
    "phong": {"mode": "scanline", "exponent": 37.5},
    "blinn": {"energy_compensation": True, "specular_reflectance": [0.9, 0.8, 0.2]},
    "ward": {"alpha": 0.21, "formula": "angles"},
    "cook_torrance": {"distribution": "ggx", "geometry": "smith", "k": 0.25, "f0": [0.7, 0.6, 0.5],
                      "alpha": 0.15, "energy_compensation": True, "sample_visible": False},
    "diffuse": {"reflectance": [0.2, 0.4, 0.6]},
    "roughconductor": {"material": "Cu", "alpha": 0.2, "distribution": "ggx",
                       "specular_reflectance": [1.0, 0.9, 0.8]},
    "roughplastic": {"alpha": 0.3, "diffuse_reflectance": [0.8, 0.1, 0.1]},
    "principled": {"metallic": 0.7, "roughness": 0.35, "clearcoat": 0.5, "specular": 0.3,
                   "base_color": [0.9, 0.5, 0.1]},
}


def evaluations(bsdf) -> np.ndarray:
    """eval at fixed random direction pairs (the same for every call)."""
    rng = np.random.default_rng(29)
    wi, wo = random_hemisphere(rng, 256, 0.05), random_hemisphere(rng, 256, 0.05)
    return np.array(bsdf.eval(mi.BSDFContext(), surface(wi), vec(wo)))


@pytest.mark.parametrize("name", list(VARIED))
def test_copy_xml_and_python_load_as_written_and_mean_the_material(ex, name):
    """Both strings load, and as the same BSDF as the material's own
    dictionary: eval agrees at random direction pairs."""
    material = M.complete(ex.models, {"type": name, **VARIED[name]})
    strings = ex.strings(material)
    expected = evaluations(mi.load_dict(M.load_dict(ex.models, material)))
    from_xml = mi.load_string(strings["xml"])
    scope: dict = {}
    exec(strings["python"], scope)                       # as a user pastes it
    assert np.abs(expected).max() > 0
    for loaded in (from_xml, scope["bsdf"]):
        np.testing.assert_allclose(evaluations(loaded), expected, rtol=1e-6, atol=1e-7)
    for key, value in VARIED[name].items():              # every chosen value is written
        text = ", ".join(map(repr, value)) if isinstance(value, list) else (
            str(value).lower() if isinstance(value, bool) else str(value))
        assert f'name="{key}" value="{text}"' in strings["xml"], key


def test_copied_numbers_are_the_shortest_that_read_back_as_the_float32(ex):
    """A value that went through float32 (0.30000001192092896) or a slider's
    arithmetic is written as a user would type it, in the XML and the Python."""
    material = M.complete(ex.models, {"type": "cook_torrance", "alpha": 0.30000001192092896,
                                      "diffuse_reflectance": [0.9999999999972802, 1 / 3, 0.05]})
    strings = ex.strings(material)
    assert '<float name="alpha" value="0.3"/>' in strings["xml"]
    assert '<rgb name="diffuse_reflectance" value="1.0, 0.33333334, 0.05"/>' in strings["xml"]
    assert '"alpha": 0.3,' in strings["python"]
    assert '"value": [1.0, 0.33333334, 0.05]' in strings["python"]


def test_a_move_waits_for_the_first_answer_to_a_request_sent_after_it():
    """The page's latency of a move (ms): to the first answer drawn of a
    request sent after the move, not to an earlier request's answer."""
    from mi_brdfs.tools.explore.latency import after_moves
    answers = [(5.0, 50.0), (52.0, 130.0), (131.0, 170.0)]       # (sent, shown)
    assert after_moves([0.0, 30.0, 60.0, 200.0], answers) == [50.0, 100.0, 110.0]


# ----------------------------------------------------------------------------
#  The views, against NumPy and physics
# ----------------------------------------------------------------------------

def test_lambert_views_are_the_lecture_formula(ex):
    """Lambert's lobe in the plane of incidence is ρ/π cos θ_o per channel,
    its albedo ρ at every angle, its white furnace 1 (NumPy, not the plugin)."""
    rho = np.array([0.8, 0.4, 0.1])
    out = ex.plots({"type": "lambert", "reflectance": rho.tolist()}, 40.0)
    theta = np.radians(out["lobe"]["theta"])
    expected = rho[:, None] / np.pi * np.clip(np.cos(theta), 0, None)[None, :]
    np.testing.assert_allclose(out["lobe"]["rgb"], expected, atol=2e-4)
    own, white = out["albedo"]["curves"]
    np.testing.assert_allclose(own["E"], rho.max(), rtol=2e-3)       # the largest channel
    np.testing.assert_allclose(white["E"], 1.0, rtol=2e-3)
    assert out["furnace"]["mean"] == pytest.approx(1.0, abs=3e-3)
    x, y, z = (np.array(out["lobe3d"][k]) for k in "xyz")           # f cos θ as radius
    theta_o = np.linspace(0.0, np.pi / 2, x.shape[0])                 # rows: θ_o to the horizon
    np.testing.assert_allclose(np.sqrt(x**2 + y**2 + z**2),
                               np.repeat(rho.mean() / np.pi * np.cos(theta_o)[:, None],
                                         x.shape[1], axis=1), atol=3e-4)


def test_a_sharp_phong_lobe_reflects_cos_theta(ex):
    """hdr Phong's lobe (γ+2)/2π cos^γ(α) times cos θ_o integrates to cos θ_i
    over the sphere (the cos θ_o = cos θ_r cos α + sin θ_r sin α cos β of the
    lobe's frame leaves cos θ_r · 2π/(γ+2)): at γ = 1000 its lobe stays above
    the horizon up to 70°, and the albedo curve must be cos θ_i there."""
    out = ex.plots({"type": "phong", "exponent": 1000.0, "diffuse_reflectance": 0.0,
                    "specular_reflectance": 1.0}, 0.0)
    e = np.array(out["albedo"]["curves"][0]["E"])
    angles = np.array(ALBEDO_ANGLES)
    below = angles <= 70
    np.testing.assert_allclose(e[below], np.cos(np.radians(angles[below])), rtol=5e-3)


def test_hemispherical_albedo_of_known_curves():
    """2∫E(μ)μ dμ: 1 for E = 1, 2/3 for E = cos θ (independent closed forms)."""
    angles = np.radians(ALBEDO_ANGLES)
    assert hemispherical(np.ones(len(angles)))["mean"] == pytest.approx(1.0, abs=1e-12)
    assert hemispherical(np.cos(angles))["mean"] == pytest.approx(2 / 3, abs=2e-3)


def test_compensated_cook_torrance_against_the_random_walk(ex):
    """A compensated GGX white surface reflects what the walk on the
    microsurface reflects (within 3 %: the README's 1.4 % plus the walk's
    noise at 8000 paths), an uncompensated one less, with a colour F0 too; a
    white F0 = 1, k = 0 surface reflects 1 by the walk (every path leaves)."""
    material = {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith",
                "alpha": 0.6, "f0": 0.5, "k": 0.3}
    out = ex.plots(material, 0.0)
    curves = {c["label"]: np.array(c["E"]) for c in out["albedo"]["curves"]}
    walk = np.array(ex.walk(material)["E"])
    np.testing.assert_allclose(curves["white, energy compensated"], walk, rtol=0.03)
    assert (curves["white, not compensated"] < walk - 0.005).all()
    white = ex.walk({**material, "f0": 1.0, "k": 0.0})["E"]
    np.testing.assert_allclose(white, 1.0, atol=1e-9)
    # a colour f0: the largest channel of each (the explorer's curves show that one)
    colour = {**material, "f0": [0.1, 0.5, 0.9]}
    curves = {c["label"]: np.array(c["E"]) for c in ex.plots(colour, 0.0)["albedo"]["curves"]}
    walk = np.array(ex.walk(colour)["E"])
    np.testing.assert_allclose(curves["white, energy compensated"], walk, rtol=0.03)
    assert (curves["white, not compensated"] < walk - 0.005).all()
    assert ex.walk({**material, "distribution": "blinn"})["E"] is None
    assert ex.walk({"type": "phong"})["E"] is None


def kernels_compiled(work) -> int:
    """How many kernels ``work()`` compiled (not found in Dr.Jit's caches)."""
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()                                   # clears it
    work()
    history = dr.kernel_history()
    dr.set_flag(dr.JitFlag.KernelHistory, False)
    return sum(1 for k in history if k.get("type") == dr.KernelType.JIT
               and not k.get("cache_hit", False))


def test_a_parameter_change_reuses_the_compiled_kernels(ex):
    """New values go in as opaque values: the plots and the preview of a
    loaded configuration compile nothing new, and yet show the new value."""
    base = {"type": "cook_torrance", "distribution": "beckmann", "alpha": 0.3, "k": 0.4,
            "mode": "scanline"}
    first = ex.plots(base, 20.0)
    list(ex.frames(base, 128, 8))
    changed = {**base, "alpha": 0.12, "k": 0.1, "f0": 0.3, "diffuse_reflectance": [0.2, 0.3, 0.9]}
    box = {}
    assert kernels_compiled(lambda: box.update(plots=ex.plots(changed, 20.0),
                                               frames=list(ex.frames(changed, 128, 8)))) == 0
    assert np.max(box["plots"]["lobe"]["rgb"]) > 2 * np.max(first["lobe"]["rgb"])


def test_progressive_frames_refine_to_the_spp_asked(ex):
    frames = list(ex.frames({"type": "phong", "exponent": 50}, 128, 40))
    assert [f["spp"] for f in frames] == [1, 4, 8, 16, 24, 32, 40]   # passes of 1, 3, 4, 8, 8, ...
    assert [f["final"] for f in frames] == [False] * 6 + [True]
    assert all(f["image"].startswith("data:image/png;base64,") for f in frames)
    with pytest.raises(M.RequestError, match=r"res = 100 is invalid; valid: one of 128, 256"):
        ex.frames({"type": "phong"}, 100, 4)


def sphere_centre(ex, material: dict) -> np.ndarray:
    """The mean linear RGB of the preview's central quarter (all sphere)."""
    _, _, scene = ex.preview(material, 128)
    image = np.array(mi.render(scene, spp=64, seed=3))[32:96, 32:96, :3]
    return image.mean(axis=(0, 1))


def test_scanline_previews_are_as_bright_as_hdr_ones(ex):
    """The lecture's scan-line Lambert m_D·cos has no 1/π: its preview's
    lights are divided by π, so the sphere shows the radiance the hdr
    Lambert m_D/π·cos gives (direct light on a convex object: the two
    integrators estimate the same integral). A built-in keeps its lights."""
    hdr = sphere_centre(ex, {"type": "lambert", "reflectance": [0.3, 0.2, 0.1]})
    scanline = sphere_centre(ex, {"type": "lambert", "reflectance": [0.3, 0.2, 0.1],
                                  "mode": "scanline"})
    np.testing.assert_allclose(scanline, hdr, rtol=0.03)
    builtin = sphere_centre(ex, {"type": "diffuse", "reflectance": [0.3, 0.2, 0.1],
                                 "mode": "scanline"})
    np.testing.assert_allclose(builtin, hdr, rtol=0.03)


def test_fit_recovers_a_model_fitted_to_itself(ex):
    """Fitting cook_torrance to another cook_torrance of the same options
    finds its roughness (an exact solution exists; k, m_D, m_S and F0 trade
    off in part), and the fitted BSDF matches the target at direction pairs
    of its own, not the fit's."""
    target = {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith", "alpha": 0.18,
              "k": 0.35, "f0": 0.6, "diffuse_reflectance": [0.7, 0.2, 0.1]}
    start = {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith"}
    out = ex.fit(start, target)
    fitted = out["material"]
    assert out["brdf_error"] < 0.02
    assert fitted["alpha"] == pytest.approx(0.18, rel=0.05)
    f_fit, f_target = (evaluations(mi.load_dict(M.load_dict(ex.models, M.complete(ex.models, m))))
                       for m in (fitted, target))
    assert np.linalg.norm(f_fit - f_target) < 0.05 * np.linalg.norm(f_target)
    assert fitted["distribution"] == "ggx"                # the options stay
    with pytest.raises(M.RequestError, match="fit: the fitted model must be a course model"):
        ex.fit({"type": "diffuse"}, target)


# ----------------------------------------------------------------------------
#  The worker: newest request wins
# ----------------------------------------------------------------------------

def test_a_newer_job_abandons_the_older_one_between_steps():
    worker = Worker("test")
    steps, results, done = [], [], threading.Event()
    gate = threading.Event()

    def slow(label):
        for i in range(50):
            steps.append((label, i))
            if label == "old" and i == 0:
                gate.wait(5)                  # the old render's first pass is running
            yield f"{label}{i}"

    def deliver(result, error, finished):
        results.append(result)
        if finished:
            done.set()
    try:
        worker.submit(("c", "left", "render"), lambda: slow("old"), deliver)
        while not steps:
            time.sleep(0.01)
        worker.submit(("c", "left", "render"), lambda: iter(["new"]), deliver)
        other = []
        worker.submit(("c", "right", "plots"), lambda: "plots", lambda r, e, f: other.append(r))
        gate.set()
        assert done.wait(5)
    finally:
        worker.stop()
    assert [s for s in steps if s[0] == "old"] == [("old", 0)]     # no second pass
    assert results == ["new", None] and other == ["plots"]


def test_a_failing_job_is_one_line_and_the_worker_goes_on():
    worker = Worker("test")
    try:
        with pytest.raises(RuntimeError, match=r"^ZeroDivisionError: division by zero$|division"):
            worker.call(lambda: 1 / 0)
        assert worker.call(lambda: 42) == 42
    finally:
        worker.stop()
