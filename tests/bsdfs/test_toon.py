"""toon: the lecture's stepped colours transcribed independently in NumPy, in
both modes, smooth bands and ramps, the dark side for lights behind (scanline),
the white-furnace report and the ramps' own rules. What every model shares:
the battery."""
import math

import numpy as np
import pytest

import mitsuba as mi

from support import assert_refused, albedo, eval_and_pdf, f32, random_hemisphere, rgb


MODELS = ["phong", "blinn"]


def load(**kw):
    return mi.load_dict({"type": "toon", **kw})


def ramp_texture(colours, filter_type="bilinear"):
    """A 1-D ramp: a bitmap one pixel high, left edge cos = -1, right edge +1."""
    data = np.asarray(colours, dtype=np.float32)[None, :, :]
    return {"type": "bitmap", "bitmap": mi.Bitmap(data), "raw": True,
            "wrap_mode": "clamp", "filter_type": filter_type}


# ----------------------------------------------------------------------------
#  An independent NumPy transcription of the lecture (d light, w viewer, n = z)
# ----------------------------------------------------------------------------

def lecture_cosines(d, w):
    """d·n, ω_r·r with r = 2(d·n)n - d, and n·h with h = normalize(d + ω_r)."""
    n = np.array([0.0, 0.0, 1.0])
    dn = d @ n
    r = 2 * dn[:, None] * n - d
    h = d + w
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    return dn, np.sum(w * r, axis=1), h @ n


def smoothstep_weight(c, t, width):
    if width == 0:
        return (c >= t).astype(np.float64)
    x = np.clip((c - t) / width + 0.5, 0, 1)
    return x * x * (3 - 2 * x)


def ramp_colour(colours, c, filter_type):
    """Bilinear (texel centres at (i + 1/2)/N, clamped) or nearest lookup at
    u = (c + 1)/2."""
    colours = np.asarray(colours, dtype=np.float64)
    n = len(colours)
    u = (c + 1) / 2
    if filter_type == "nearest":
        return colours[np.clip(np.floor(u * n).astype(int), 0, n - 1)]
    xp = (np.arange(n) + 0.5) / n
    return np.stack([np.interp(u, xp, colours[:, k]) for k in range(3)], axis=1)


def lecture_toon(d, w, p):
    """(f_diffuse, f_specular) of the lecture's toon model, per direction pair."""
    dn, c_phong, c_blinn = lecture_cosines(d, w)
    c = c_phong if p.get("specular_model", "phong") == "phong" else c_blinn
    width = p.get("smoothness", 0.0)
    if "diffuse_ramp" in p:
        f_d = ramp_colour(p["diffuse_ramp"], dn, p.get("ramp_filter", "bilinear"))
    else:
        k = smoothstep_weight(dn, p["t_D"], width)[:, None]
        f_d = p["m_D2"] + (p["m_D1"] - p["m_D2"]) * k
    if "specular_ramp" in p:
        f_s = ramp_colour(p["specular_ramp"], c, p.get("ramp_filter", "bilinear"))
    else:
        k = smoothstep_weight(c, p["t_S"], width)[:, None]
        f_s = p["m_S2"] + (p["m_S1"] - p["m_S2"]) * k
    f_s = np.where(dn[:, None] > 0, f_s, 0.0)         # no highlight from lights behind
    return f_d, f_s


def reference(d, w, p, mode):
    """scanline: clamp01(f_d) + clamp01(f_s), lights behind included (the dark
    side); hdr: (f_d + f_s)/(2π) for lights above the surface (the hdr
    normalisation: a constant colour c reflects c over the hemisphere; the
    surface is opaque); 0 for a viewer below."""
    f_d, f_s = lecture_toon(d, w, p)
    if mode == "scanline":
        v = np.clip(f_d, 0, 1) + np.clip(f_s, 0, 1)
    else:
        v = np.where(d[:, 2:3] > 0, (f_d + f_s) / (2 * np.pi), 0.0)
    return np.where(w[:, 2:3] > 0, v, 0.0)


def plugin_dict(p):
    out = {"specular_model": p.get("specular_model", "phong")}
    if "smoothness" in p:
        out["smoothness"] = p["smoothness"]
    if "diffuse_ramp" in p:
        out["diffuse_ramp"] = ramp_texture(p["diffuse_ramp"], p.get("ramp_filter", "bilinear"))
    else:
        out.update(diffuse_reflectance=rgb(p["m_D1"]), diffuse_shade=rgb(p["m_D2"]),
                   diffuse_threshold=p["t_D"])
    if "specular_ramp" in p:
        out["specular_ramp"] = ramp_texture(p["specular_ramp"], p.get("ramp_filter", "bilinear"))
    else:
        out.update(specular_reflectance=rgb(p["m_S1"]), specular_shade=rgb(p["m_S2"]),
                   specular_threshold=p["t_S"])
    return out


COLOURS = {"m_D1": np.array([1.6, 0.8, 0.3]), "m_D2": np.array([0.3, 1.4, 0.1]),
           "m_S1": np.array([2.0, 1.0, 0.5]), "m_S2": np.array([0.0, 0.2, 1.3]),
           "t_D": 0.3, "t_S": 0.6}


def direction_pairs(rng, n):
    """Viewers mostly above (1/8 below), lights a quarter below the surface;
    half of the lights near the mirror direction (inside the highlight)."""
    w = random_hemisphere(rng, n)
    d = random_hemisphere(rng, n)
    m = n // 2
    d[:m] = np.column_stack([-w[:m, 0], -w[:m, 1], w[:m, 2]]) + 0.5 * rng.normal(size=(m, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d[:, 2] = np.abs(d[:, 2])
    d[n - n // 4:, 2] *= -1                        # lights behind the surface
    w[: n // 8, 2] *= -1                           # viewers below
    return f32(d), f32(w)


def away_from_steps(d, w, p):
    """Pairs whose cosines are not within float32 rounding of a hard step."""
    dn, c_phong, c_blinn = lecture_cosines(d, w)
    c = c_phong if p.get("specular_model", "phong") == "phong" else c_blinn
    keep = np.ones(len(d), bool)
    if "t_D" in p:
        keep &= np.abs(dn - p["t_D"]) > 1e-5
    if "t_S" in p:
        keep &= np.abs(c - p["t_S"]) > 1e-5
    return keep


CASES = [dict(COLOURS, specular_model=m, smoothness=s) for m in MODELS for s in (0.0, 0.3)]


@pytest.mark.parametrize("mode", ["scanline", "hdr"])
@pytest.mark.parametrize("p", CASES, ids=[f"{c['specular_model']}-w={c['smoothness']}" for c in CASES])
def test_matches_lecture(rng, mode, p):
    n = 8192
    d, w = direction_pairs(rng, n)
    keep = away_from_steps(d, w, p)
    v, _ = eval_and_pdf(load(mode=mode, **plugin_dict(p)), wi=w[keep], wo=d[keep])
    expected = reference(d[keep], w[keep], p, mode)
    np.testing.assert_allclose(v, expected, rtol=1e-5, atol=1e-5)
    f_d, f_s = lecture_toon(d[keep], w[keep], p)
    up = w[keep, 2] > 0
    # Every branch is exercised: both diffuse tones, both specular tones, the
    # clamps (colours above 1), the dark side for lights behind.
    dn, c_phong, c_blinn = lecture_cosines(d[keep], w[keep])
    c = c_phong if p["specular_model"] == "phong" else c_blinn
    for mask in (dn >= p["t_D"], dn < p["t_D"], dn < 0, (c >= p["t_S"]) & (dn > 0),
                 (c < p["t_S"]) & (dn > 0)):
        assert np.count_nonzero(mask & up) > 100
    assert (f_s > 1).any() and (f_d > 1).any()
    behind = (d[keep, 2] < 0) & up
    if p["smoothness"] == 0:
        dark = np.clip(p["m_D2"], 0, 1) if mode == "scanline" else 0.0 * p["m_D2"]
        np.testing.assert_allclose(v[behind], np.broadcast_to(dark, v[behind].shape), rtol=1e-6)


@pytest.mark.parametrize("mode", ["scanline", "hdr"])
@pytest.mark.parametrize("filter_type", ["nearest", "bilinear"])
def test_ramps(rng, mode, filter_type):
    """1-D ramp textures looked up at u = (cos + 1)/2 replace the two tones."""
    p = {"diffuse_ramp": [[0.05, 0.02, 0.1], [0.2, 0.1, 0.3], [0.5, 0.4, 0.2],
                          [0.9, 0.7, 0.3], [1.6, 1.2, 0.5]],
         "specular_ramp": [[0.0, 0.0, 0.0]] * 6 + [[0.3, 0.3, 0.3], [2.0, 1.5, 1.0]],
         "ramp_filter": filter_type, "specular_model": "blinn"}
    n = 8192
    d, w = direction_pairs(rng, n)
    dn, _, c = lecture_cosines(d, w)
    keep = np.ones(n, bool)
    if filter_type == "nearest":      # not on a texel boundary
        for cos, texels in ((dn, 5), (c, 8)):
            u = (cos + 1) / 2 * texels
            keep &= np.abs(u - np.round(u)) > 1e-4
    v, _ = eval_and_pdf(load(mode=mode, **plugin_dict(p)), wi=w[keep], wo=d[keep])
    np.testing.assert_allclose(v, reference(d[keep], w[keep], p, mode), rtol=1e-5, atol=1e-5)
    assert len(np.unique(np.round(v[:, 0], 4))) >= (5 if filter_type == "nearest" else 100)


def test_thresholds_exactly_hit():
    """A cosine equal to its threshold takes the first colour (>=); with a
    smooth band it is the mean of both. No NaN."""
    wi = np.array([[0.0, 0.0, 1.0]] * 2)                    # viewer along n: ω_r·r = d·n
    wo = np.array([[math.sqrt(0.75), 0.0, 0.5], [0.0, math.sqrt(1 - 0.75**2), 0.75]])
    base = {"diffuse_reflectance": 0.9, "diffuse_shade": 0.1, "diffuse_threshold": 0.5,
            "specular_reflectance": 0.6, "specular_shade": 0.2, "specular_threshold": 0.75}
    v, p = eval_and_pdf(load(**base, mode="scanline"), wi, wo)
    assert np.isfinite(v).all() and np.isfinite(p).all()
    # d·n = 0.5 = t_D: m_D1; ω_r·r = 0.5 < t_S: m_S2
    np.testing.assert_allclose(v[0], 0.9 + 0.2, rtol=1e-6)
    # d·n = 0.75 >= t_D: m_D1; ω_r·r = 0.75 = t_S: m_S1
    np.testing.assert_allclose(v[1], 0.9 + 0.6, rtol=1e-6)
    v, _ = eval_and_pdf(load(**base, smoothness=0.2, mode="scanline"), wi, wo)
    np.testing.assert_allclose(v[0], 0.5 + 0.2, rtol=1e-6)   # diffuse band midpoint
    np.testing.assert_allclose(v[1], 0.9 + 0.4, rtol=1e-6)   # specular band midpoint
    v_hdr, _ = eval_and_pdf(load(**base, smoothness=0.2), wi, wo)  # hdr: the same over 2π
    np.testing.assert_allclose(v_hdr, v / (2 * np.pi), rtol=1e-6)


# ----------------------------------------------------------------------------
#  Lights behind, viewers below, flags
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("mode", ["scanline", "hdr"])
def test_lights_behind_see_the_dark_side_viewers_below_see_nothing(rng, mode):
    """scanline: lights behind see the dark side (the lecture's rasteriser
    lights with every light); hdr: the surface is opaque, they see nothing."""
    w, d = random_hemisphere(rng, 1024, 0.01), random_hemisphere(rng, 1024, 0.01)
    bsdf = load(mode=mode, diffuse_shade=rgb([0.3, 0.2, 0.1]), specular_shade=0.5,
                specular_threshold=-1.0)                     # highlight everywhere above
    v, p = eval_and_pdf(bsdf, wi=w, wo=d * [1, 1, -1])           # lights behind
    dark = [0.3, 0.2, 0.1] if mode == "scanline" else [0.0, 0.0, 0.0]
    np.testing.assert_allclose(v, np.broadcast_to(dark, v.shape), rtol=1e-6)
    assert not p.any()                                        # never sampled there
    v, p = eval_and_pdf(bsdf, wi=w * [1, 1, -1], wo=d)            # viewers below
    assert not v.any() and not p.any()
    v, _ = eval_and_pdf(bsdf, wi=w * [1, 1, -1], wo=d * [1, 1, -1])
    assert not v.any()


def test_scanline_integrator_shows_the_dark_side():
    """A sphere lit only from behind, rendered by the scan-line integrator (no
    shadows): the side facing the camera is m_D2 times the light, not black."""
    scene = mi.load_dict({
        "type": "scene", "integrator": {"type": "scanline"},
        "sensor": {"type": "perspective", "fov": 20,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 6], target=[0, 0, 0],
                                                              up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": 16, "height": 16,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 1}},
        "sphere": {"type": "sphere", "radius": 0.5,
                   "bsdf": {"type": "toon", "mode": "scanline", "diffuse_shade": rgb([0.3, 0.2, 0.1])}},
        "light": {"type": "point", "position": [0, 0, -10], "intensity": rgb([100, 100, 100])},
    })
    image = np.array(mi.render(scene))
    centre = image[8, 8]
    # the light at distance ~10.5 from the visible (front) side: E = 100/r²
    assert 0.05 < centre[0] < 0.5
    np.testing.assert_allclose(centre / centre[0], [1, 2 / 3, 1 / 3], rtol=1e-4)


def test_flags_declare_smooth_lobes():
    F = mi.BSDFFlags
    both = load()
    assert both.flags() == F.DiffuseReflection | F.GlossyReflection | F.FrontSide
    assert mi.has_flag(both.flags(), F.Smooth) and both.component_count() == 2
    diffuse = load(specular_reflectance=0.0)
    assert diffuse.flags() == F.DiffuseReflection | F.FrontSide
    glossy = load(diffuse_reflectance=0.0, diffuse_shade=0.0)
    assert glossy.flags() == F.GlossyReflection | F.FrontSide


# ----------------------------------------------------------------------------
#  White furnace (hdr): the stylised model's "albedo", reported
# ----------------------------------------------------------------------------

THETAS = (0, 15, 30, 45, 60, 75, 85, 89)


def albedos(bsdf, thetas=THETAS):
    """{θ_i: E(θ_i)} by the suite's uniform-hemisphere quadrature (channel 0)."""
    return {th: float(albedo(bsdf, th, n=512)[0]) for th in thetas}


def _fmt(values):
    return ", ".join(f"{th}°: {e:.4f}" for th, e in values.items())


# Closed forms at normal incidence: the hdr value is the colour over 2π, so
# E(0) = m_D1 (1 - t_D) + m_D2 t_D + the highlight's solid angle over 2π
# (2π(1 - t_S) for phong, 4π(1 - t_S²) for blinn).
FURNACE = {
    "defaults (phong)": ({}, 0.8 * 0.5 + 0.2 * 0.5 + 0.1),
    "defaults, blinn": ({"specular_model": "blinn"}, 0.5 + 2 * (1 - 0.9**2)),
    "defaults, smoothness 0.2": ({"smoothness": 0.2}, 0.5 + 0.1),
    "white diffuse only (m_D1 = m_D2 = 1)": ({"diffuse_shade": 1.0, "diffuse_reflectance": 1.0,
                                             "specular_reflectance": 0.0}, 1.0),
}


def test_furnace_reports_the_albedo(capsys):
    """E(θ_i) = ∫ eval dω over the hemisphere, printed, and at normal incidence
    equal to its closed form; each lobe reflects at most its brightest colour,
    a white diffuse-only toon exactly 1 at every angle (within 1 %)."""
    results = {label: albedos(load(**cfg)) for label, (cfg, _) in FURNACE.items()}
    with capsys.disabled():
        print("\ntoon white furnace (hdr; eval = the stepped colour / 2π, no cos): E(theta_i)")
        for label, values in results.items():
            print(f"  {label}: {_fmt(values)}")
    for label, (_, closed_form) in FURNACE.items():
        assert results[label][0] == pytest.approx(closed_form, rel=2e-3), label
    # A constant colour of 1 reflects exactly 1 at every angle.
    assert all(e == pytest.approx(1.0, abs=0.01)
               for e in results["white diffuse only (m_D1 = m_D2 = 1)"].values())
    # Each lobe at most its brightest colour: diffuse <= 0.8, specular <= 1.
    for values in results.values():
        assert max(values.values()) <= 1.0 + 0.8 + 1e-3
    # The highlight cone leaves the hemisphere at grazing incidence: less specular.
    d = results["defaults (phong)"]
    assert d[89] < d[0] - 0.2 / (2 * np.pi)


RAMP = [[0.1, 0.1, 0.1], [0.4, 0.3, 0.2], [1.0, 0.9, 0.8]]
SPEC_RAMP = [[0.2, 0.2, 0.2]] * 3 + [[1.5, 1.5, 1.5]]


# ----------------------------------------------------------------------------
#  Ramps replace colours and thresholds: load-time errors
# ----------------------------------------------------------------------------

# The ramps' own rules (every parameter's range and choice: the battery).
ERRORS = [
    ({"diffuse_ramp": ramp_texture([[0.1, 0.1, 0.1], [-0.5, 0.2, 0.2]])},
     "diffuse_ramp", "-0.5", "[0, 1e+06]"),
    ({"diffuse_ramp": ramp_texture(RAMP), "diffuse_shade": 0.1}, "diffuse_shade", "0.1",
     "not with diffuse_ramp"),
    ({"specular_ramp": ramp_texture(RAMP), "specular_threshold": 0.5}, "specular_threshold",
     "0.5", "not with specular_ramp"),
    ({"diffuse_ramp": ramp_texture(RAMP), "specular_ramp": ramp_texture(RAMP),
      "smoothness": 0.1}, "smoothness", "0.1", "not with both diffuse_ramp and specular_ramp"),
]


@pytest.mark.parametrize("config, name, value, valid", ERRORS,
                         ids=[f"{e[1]}={e[2]}" for e in ERRORS])
def test_bad_input_is_a_clear_load_time_error(config, name, value, valid):
    assert_refused({"type": "toon", **config}, name, value, valid)


# ----------------------------------------------------------------------------
#  What a ramp exposes
# ----------------------------------------------------------------------------

STEP_KEYS = {"diffuse_reflectance.value", "diffuse_shade.value", "diffuse_threshold.value",
             "specular_reflectance.value", "specular_shade.value",
             "specular_threshold.value", "smoothness"}


def test_traverse_lists_every_parameter_as_differentiable():
    for bsdf, keys in [(load(), STEP_KEYS),
                       (load(diffuse_ramp=ramp_texture(RAMP), specular_ramp=ramp_texture(RAMP)),
                        {"diffuse_ramp.data", "diffuse_ramp.to_uv", "specular_ramp.data",
                         "specular_ramp.to_uv", "smoothness"})]:
        params = mi.traverse(bsdf)
        assert set(params.keys()) == keys
        for key in keys - {"diffuse_ramp.to_uv", "specular_ramp.to_uv"}:   # the bitmap's own
            assert not (params.flags(key) & mi.ParamFlags.NonDifferentiable), key
