"""oren_nayar: the lecture's formulas transcribed independently in NumPy,
Lambert at σ = 0, degenerate directions, the lecture's table against the exact
formulas, the white furnace against a NumPy quadrature, the table's options,
and the energy-preserving EON (NumPy transcription of Portsmouth et al.).
What every model shares: the battery."""
import functools
import itertools
import math

import numpy as np
import pytest

import drjit as dr
import mitsuba as mi

from mi_brdfs._jit import from_numpy
from support import assert_refused, eval_and_pdf, f32, random_hemisphere, rgb, surface, vec


HALF_PI = 0.5 * math.pi
METHODS = ["exact", "table"]


def load(**kw):
    return mi.load_dict({"type": "oren_nayar", **kw})


# ----------------------------------------------------------------------------
#  An independent NumPy transcription of the lecture (d light, w viewer, n = z)
# ----------------------------------------------------------------------------

def lecture_oren_nayar(d, w, m_d, sigma):
    """L (A + B G sin α tan β), L = m_D clamp(d·n), per the lecture (float64).
    sigma: scalar or per-direction array."""
    sigma = np.asarray(sigma, dtype=np.float64)[..., None] if np.ndim(sigma) else sigma
    theta_i = np.arccos(np.clip(d[:, 2], -1, 1))
    theta_r = np.arccos(np.clip(w[:, 2], -1, 1))
    alpha = np.maximum(theta_i, theta_r)
    beta = np.minimum(theta_i, theta_r)
    A = 1 - 0.5 * sigma**2 / (sigma**2 + 0.33)
    B = 0.45 * sigma**2 / (sigma**2 + 0.09)
    n = np.array([0.0, 0.0, 1.0])
    v_i = d - np.sum(d * n, axis=1, keepdims=True) * n
    v_r = w - np.sum(w * n, axis=1, keepdims=True) * n
    len_i = np.linalg.norm(v_i, axis=1, keepdims=True)
    len_r = np.linalg.norm(v_r, axis=1, keepdims=True)
    v_i /= np.where(len_i > 0, len_i, 1)      # a direction along n: no azimuth, and
    v_r /= np.where(len_r > 0, len_r, 1)      # then beta = 0, so G does not matter
    G = np.maximum(0, np.sum(v_i * v_r, axis=1))
    L = m_d[None, :] * np.clip(d[:, 2:3], 0, 1)
    return L * (A + B * (G * np.sin(alpha) * np.tan(beta))[:, None])


def scanline_reference(d, w, m_d, sigma):
    return np.clip(lecture_oren_nayar(d, w, m_d, sigma), 0, 1)


def hdr_reference(d, w, m_d, sigma):
    """The hdr eval: m_D/π (A + B G sin α tan β) cos θ_o."""
    return lecture_oren_nayar(d, w, m_d, sigma) / np.pi


SIGMAS = [0.0, 0.25, 0.9, HALF_PI]


@pytest.mark.parametrize("sigma", SIGMAS)
def test_scanline_matches_lecture(rng, sigma):
    n = 4096
    d, w = f32(random_hemisphere(rng, n, 0.01)), f32(random_hemisphere(rng, n, 0.01))
    m_d = np.array([2.6, 1.1, 0.3])          # above 1: the clamp is exercised
    bsdf = load(mode="scanline", sigma=sigma, reflectance=rgb(m_d))
    v, _ = eval_and_pdf(bsdf, wi=w, wo=d)
    raw = lecture_oren_nayar(d, w, m_d, sigma)
    np.testing.assert_allclose(v, np.clip(raw, 0, 1), rtol=2e-4, atol=1e-6)
    assert (raw[:, 0] > 1).any() and ((raw[:, 0] > 0.05) & (raw[:, 0] < 1)).any()


@pytest.mark.parametrize("sigma", SIGMAS)
def test_hdr_matches_normalised_formula(rng, sigma):
    n = 4096
    d, w = f32(random_hemisphere(rng, n, 0.01)), f32(random_hemisphere(rng, n, 0.01))
    m_d = np.array([2.6, 1.1, 0.3])          # hdr: no clamp
    v, _ = eval_and_pdf(load(sigma=sigma, reflectance=rgb(m_d)), wi=w, wo=d)
    expected = hdr_reference(d, w, m_d, sigma)
    np.testing.assert_allclose(v, expected, rtol=2e-4, atol=1e-6)
    assert v.max() > 1.0 / np.pi              # unclamped values above the scanline's 1/π·...


def test_sigma_texture(rng):
    """σ from a texture: each lane uses its own σ (Mitsuba's checkerboard)."""
    n = 4096
    d, w = f32(random_hemisphere(rng, n, 0.01)), f32(random_hemisphere(rng, n, 0.01))
    tex = {"type": "checkerboard", "color0": 0.1, "color1": 1.3}
    for method in METHODS:
        bsdf = load(sigma=tex, method=method, reflectance=1.0)
        si = surface(w)
        si.uv = from_numpy(mi.Point2f, rng.random((2, n)))
        v = np.array(bsdf.eval(mi.BSDFContext(), si, vec(d)))[0]
        sigma = np.array(mi.load_dict(tex).eval_1(si))
        assert sorted(set(np.round(sigma.astype(float), 5))) == [0.1, 1.3]
        expected = hdr_reference(d, w, np.ones(3), sigma)[:, 0]
        tol = 2e-4 if method == "exact" else 0.05
        np.testing.assert_allclose(v, expected, rtol=tol, atol=1e-6 if method == "exact" else 5e-3)


def test_below_surface_is_black(rng):
    d, w = random_hemisphere(rng, 512, 0.01), random_hemisphere(rng, 512, 0.01)
    for mode, method in itertools.product(["scanline", "hdr"], METHODS):
        bsdf = load(mode=mode, method=method, sigma=1.0)
        for wi, wo in [(w, d * [1, 1, -1]), (w * [1, 1, -1], d)]:
            v, p = eval_and_pdf(bsdf, wi, wo)
            assert not v.any() and not p.any()


# ----------------------------------------------------------------------------
#  σ = 0 is Lambert, exactly
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("reflectance", [0.5, [0.8, 0.4, 0.1]])
def test_sigma_zero_equals_mitsuba_diffuse(rng, method, reflectance):
    n = 4096
    wi, wo = random_hemisphere(rng, n), random_hemisphere(rng, n)
    wo[: n // 4, 2] *= -1          # lights below the surface too
    wi[n // 4: n // 2, 2] *= -1    # and viewers below it
    value = rgb(reflectance) if isinstance(reflectance, list) else reflectance
    ours = load(sigma=0.0, method=method, reflectance=value)
    ref = mi.load_dict({"type": "diffuse", "reflectance": value})
    v, p = eval_and_pdf(ours, wi, wo)
    v_ref, p_ref = eval_and_pdf(ref, wi, wo)
    np.testing.assert_allclose(v, v_ref, rtol=1e-6, atol=0)
    np.testing.assert_allclose(p, p_ref, rtol=1e-6, atol=0)
    assert np.count_nonzero(v[:, 0]) > n // 3


# ----------------------------------------------------------------------------
#  Degenerate directions
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("method", METHODS)
def test_direction_along_normal(method):
    """v_i or v_r of length 0: G is 0 (and β = 0 anyway): the value is A·Lambert."""
    sigma, m_d = 1.0, 0.7
    A = 1 - 0.5 * sigma**2 / (sigma**2 + 0.33)
    n = np.array([[0.0, 0.0, 1.0]])
    t = np.array([[0.6, 0.0, 0.8]])
    wi = np.concatenate([n, n, t])
    wo = np.concatenate([n, t, n])
    v, _ = eval_and_pdf(load(sigma=sigma, method=method, reflectance=m_d), wi, wo)
    np.testing.assert_allclose(v[:, 0], m_d * A / np.pi * wo[:, 2], rtol=1e-5)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("mode", ["hdr", "scanline"])
def test_grazing_is_bounded(method, mode):
    """tan β → ∞ as both directions graze the surface; eval stays finite and
    below m_D (A + B) (÷π in hdr), as tan β·cos θ_o <= 1."""
    sigma = HALF_PI
    A = 1 - 0.5 * sigma**2 / (sigma**2 + 0.33)
    B = 0.45 * sigma**2 / (sigma**2 + 0.09)
    cosines = [0.0, 1e-7, 1e-6, 1e-4, 1e-2]
    dirs = [np.array([math.sqrt(1 - c * c), 0.0, c]) for c in cosines]
    wi = np.array([a for a, b in itertools.product(dirs, dirs)])
    wo = np.array([b for a, b in itertools.product(dirs, dirs)])
    v, p = eval_and_pdf(load(sigma=sigma, method=method, mode=mode, reflectance=1.0), wi, wo)
    assert np.isfinite(v).all() and np.isfinite(p).all()
    bound = (A + B) / (1.0 if mode == "scanline" else np.pi)
    assert v.max() <= bound * (1 + 1e-5)
    # The model's own limit: light slightly above a grazing viewer, same azimuth:
    # sin α sin β cos θ_o / cos β -> 1, eval -> m_D (A·0 + B) (÷π).
    k = cosines.index(1e-4) * len(cosines) + cosines.index(1e-2)   # wi 1e-4, wo 1e-2
    if method == "exact":
        assert v[k, 0] == pytest.approx(bound * (B + A * 1e-2) / (A + B), rel=1e-3)


# ----------------------------------------------------------------------------
#  The table against the exact formulas
# ----------------------------------------------------------------------------

def table_errors(res, d, w):
    """Errors of the table's hdr eval (m_D = 1, σ = π/2, the largest B) against
    the exact one on the same direction pairs: max, RMS, max with both cosines
    >= 0.1, and the maximum relative error there."""
    exact = eval_and_pdf(load(sigma=HALF_PI), w, d)[0][:, 0]
    table = eval_and_pdf(load(sigma=HALF_PI, method="table", table_resolution=res), w, d)[0][:, 0]
    err = np.abs(table - exact)
    away = (d[:, 2] >= 0.1) & (w[:, 2] >= 0.1)
    return (err.max(), np.sqrt(np.mean(err**2)), err[away].max(),
            (err[away] / exact[away]).max())


def test_table_error_is_bounded_and_falls_with_resolution(rng, capsys):
    n = 400_000
    d, w = random_hemisphere(rng, n), random_hemisphere(rng, n)   # uniform on the hemisphere
    peak = (1 - 0.5 * HALF_PI**2 / (HALF_PI**2 + 0.33) + 0.45 * HALF_PI**2 / (HALF_PI**2 + 0.09)) / np.pi
    results = {res: table_errors(res, d, w) for res in (16, 64, 256)}
    with capsys.disabled():
        print(f"\noren_nayar table vs exact, hdr eval, m_D = 1, sigma = pi/2 (eval <= {peak:.4f}),"
              f" {n} uniform direction pairs:")
        for res, (mx, rms, mx_away, rel_away) in results.items():
            print(f"  table_resolution {res:3d}: max |err| {mx:.5f}, RMS {rms:.6f};"
                  f" both cos >= 0.1: max |err| {mx_away:.6f} (max relative {rel_away:.3%})")
    mx, rms, mx_away, rel_away = results[64]           # the default resolution
    assert mx < 0.2 * peak                             # worst case: both directions grazing
    assert rms < 2e-3
    assert mx_away < 5e-3 and rel_away < 0.05
    # Refinement helps: the RMS error falls about linearly with the node
    # spacing h, the worst error away from grazing about as sqrt(h) (the
    # sqrt(1 - cos²) of sin α and tan β near the normal).
    for lo, hi in [(16, 64), (64, 256)]:
        assert results[hi][1] < 0.35 * results[lo][1]
        assert results[hi][2] < 0.7 * results[lo][2]


def test_table_default_resolution_is_64():
    assert load(method="table").options.table_resolution == 64


# ----------------------------------------------------------------------------
#  White furnace (hdr): quadrature independent of the plugin's sampler
# ----------------------------------------------------------------------------

NU, NV = 512, 1024
THETAS = (0, 15, 30, 45, 60, 75, 80, 85, 88, 89)


@pytest.fixture(scope="module")
def hemisphere():
    """Jittered stratified directions, uniform in (cos θ_o, φ_o): density 1/(2π)."""
    rng = np.random.default_rng(27182)
    u = ((np.arange(NU)[:, None] + rng.random((NU, NV))) / NU).ravel()
    v = ((np.arange(NV)[None, :] + rng.random((NU, NV))) / NV).ravel()
    s = np.sqrt(np.maximum(0.0, 1.0 - u * u))
    return from_numpy(mi.Vector3f, (s * np.cos(2 * np.pi * v), s * np.sin(2 * np.pi * v), u))


def albedos(bsdf, wo, thetas=THETAS):
    """{θ_i: E(θ_i)} = 2π mean(eval) over the uniform hemisphere (channel 0)."""
    out = {}
    for th in thetas:
        t = math.radians(th)
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(dr.opaque(mi.Float, math.sin(t)), 0.0,
                            dr.opaque(mi.Float, math.cos(t)))
        value = bsdf.eval(mi.BSDFContext(), si, wo)
        out[th] = float(dr.sum(mi.Float64(value[0]))[0]) * 2 * np.pi / dr.width(wo)
    return out


@functools.lru_cache(maxsize=None)
def reference_albedo(theta, sigma, n_mu=512, n_phi=512):
    """Float64 Gauss-Legendre (cos θ_o) x midpoint (φ_o) quadrature of the NumPy
    transcription."""
    x, wt = np.polynomial.legendre.leggauss(n_mu)
    mu, w_mu = 0.5 * (x + 1), 0.5 * wt
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    MU, PH = np.meshgrid(mu, phi, indexing="ij")
    S = np.sqrt(1 - MU**2)
    d = np.stack([S * np.cos(PH), S * np.sin(PH), MU], -1).reshape(-1, 3)
    t = math.radians(theta)
    w = np.tile([math.sin(t), 0.0, math.cos(t)], (len(d), 1))
    f = hdr_reference(d, w, np.ones(1), sigma)[:, 0].reshape(MU.shape)
    return float(np.sum(f * w_mu[:, None]) * 2 * np.pi / n_phi)


def _fmt(values):
    return ", ".join(f"{th}°: {e:.4f}" for th, e in values.items())


@pytest.mark.parametrize("method", METHODS)
def test_furnace(hemisphere, capsys, method):
    results = {s: albedos(load(sigma=s, method=method, reflectance=1.0), hemisphere)
               for s in (0.0, 0.2, 0.5, 1.0, HALF_PI)}
    with capsys.disabled():
        print(f"\noren_nayar ({method}) white furnace, hdr, m_D = 1: albedo E(theta_i)")
        for s, values in results.items():
            print(f"  sigma = {s:.3f}: {_fmt(values)}")
    # σ = 0: Lambert, E = 1 within 1 %.
    assert all(abs(e - 1) < 0.01 for e in results[0.0].values()), _fmt(results[0.0])
    # Large σ loses energy at every angle; at normal incidence β = 0 and E = A.
    for s in (0.5, 1.0, HALF_PI):
        A = 1 - 0.5 * s**2 / (s**2 + 0.33)
        assert max(results[s].values()) < 0.96, _fmt(results[s])
        assert results[s][0] == pytest.approx(A, abs=2e-3)
    # Small σ at grazing incidence: the qualitative model slightly exceeds 1.
    small = results[0.2]
    assert 1.005 < small[88] < 1.025 and small[88] > small[75] > small[0], _fmt(small)
    # The plugin's E equals a float64 quadrature of the NumPy transcription.
    tol = 2e-3 if method == "exact" else 6e-3
    for s in (0.2, HALF_PI):
        for th in (0, 60, 88):
            assert results[s][th] == pytest.approx(reference_albedo(th, s), abs=tol), (s, th)


# ----------------------------------------------------------------------------
#  The table's options: load-time errors
# ----------------------------------------------------------------------------

# The table's own options (every parameter's range and choice: the battery).
ERRORS = [
    ({"method": "table", "table_resolution": 1}, "table_resolution", "1", "[2, 4096]"),
    ({"method": "table", "table_resolution": 5000}, "table_resolution", "5000", "[2, 4096]"),
    ({"method": "table", "table_resolution": 64.5}, "table_resolution", "64.5",
     "an integer in [2, 4096]"),
    ({"table_resolution": 32}, "table_resolution", "32", 'only with method="table"'),
    ({"method": "table", "energy_compensation": True}, "method", "'table'",
     '"exact" with energy_compensation'),
]


@pytest.mark.parametrize("config, name, value, valid", ERRORS,
                         ids=[f"{e[1]}={e[2]}" for e in ERRORS])
def test_bad_input_is_a_clear_load_time_error(config, name, value, valid):
    assert_refused({"type": "oren_nayar", **config}, name, value, valid)


# ----------------------------------------------------------------------------
#  EON: energy_compensation (Portsmouth, Kutz & Hill, JCGT 2025)
# ----------------------------------------------------------------------------
#
# Transcribed from the paper, independently of mi_brdfs/bsdfs/oren_nayar.py:
# Fujii's form f_ss = ρ/π A (1 + r s/t), s = ω_i·ω_o - μ_i μ_o, t = max(μ_i, μ_o)
# for s > 0 (else 1), A = 1/(1 + (1/2 - 2/(3π)) r); the multiple scattering
# f_ms = ρ_ms/π (1 - E(μ_i)) (1 - E(μ_o)) / (1 - E_avg), ρ_ms = ρ² E_avg /
# (1 - ρ (1 - E_avg)), with E and E_avg of f_ss at ρ = 1. The roughness r is
# the lecture's B/A at σ (Fujii's mixing ratio).

def eon_r(sigma):
    A = 1 - 0.5 * sigma**2 / (sigma**2 + 0.33)
    B = 0.45 * sigma**2 / (sigma**2 + 0.09)
    return B / A


def fon_albedo_paper(mu, r):
    """The paper's closed form of E_FON(μ) (float64)."""
    A = 1 / (1 + (0.5 - 2 / (3 * np.pi)) * r)
    S = np.sqrt(1 - mu**2)
    G = S * (np.arccos(mu) - S * mu) + 2 / 3 * ((S / mu) * (1 - S**3) - S)
    return A + r * A / np.pi * G


def eon_eval(d, w, rho, sigma):
    """EON in eval convention (f · cos θ_o), float64."""
    r = eon_r(sigma)
    mu_i, mu_o = w[:, 2], d[:, 2]
    s = np.sum(d * w, axis=1) - mu_i * mu_o
    t = np.where(s > 0, np.maximum(mu_i, mu_o), 1.0)
    A = 1 / (1 + (0.5 - 2 / (3 * np.pi)) * r)
    f_ss = rho[None, :] / np.pi * (A * (1 + r * s / t))[:, None]
    e_avg = A * (1 + (2 / 3 - 28 / (15 * np.pi)) * r)
    rho_ms = rho**2 * e_avg / (1 - rho * (1 - e_avg))
    f_ms = rho_ms[None, :] / np.pi * ((1 - fon_albedo_paper(mu_i, r)) * (1 - fon_albedo_paper(mu_o, r))
                                      / (1 - e_avg))[:, None]
    return (f_ss + f_ms) * mu_o[:, None]


@pytest.mark.parametrize("sigma", [0.2, 0.8, HALF_PI])
def test_eon_matches_the_paper(rng, sigma):
    d, w = f32(random_hemisphere(rng, 4096, 0.01)), f32(random_hemisphere(rng, 4096, 0.01))
    rho = np.array([0.9, 0.5, 0.2])
    v, _ = eval_and_pdf(load(sigma=sigma, reflectance=rgb(rho), energy_compensation=True), w, d)
    np.testing.assert_allclose(v, eon_eval(d, w, rho, sigma), rtol=2e-4, atol=1e-7)


@pytest.mark.parametrize("sigma", [0.3, 1.2])
def test_eon_albedo_closed_form_is_the_quadrature_of_fujii(sigma):
    """The paper's E_FON(μ) equals a float64 quadrature of f_ss (ρ = 1) over the
    hemisphere: the analytic term the compensation rests on is right."""
    r = eon_r(sigma)
    x, wx = np.polynomial.legendre.leggauss(400)
    mu_o, w_mu = 0.5 * (x + 1), 0.5 * wx
    phi = (np.arange(512) + 0.5) * 2 * np.pi / 512
    M, P = np.meshgrid(mu_o, phi, indexing="ij")
    d = np.stack([np.sqrt(1 - M**2) * np.cos(P), np.sqrt(1 - M**2) * np.sin(P), M], -1).reshape(-1, 3)
    A = 1 / (1 + (0.5 - 2 / (3 * np.pi)) * r)
    for mu_i in (0.1, 0.5, 0.95):
        w = np.array([np.sqrt(1 - mu_i**2), 0.0, mu_i])
        s = d @ w - mu_i * d[:, 2]
        t = np.where(s > 0, np.maximum(mu_i, d[:, 2]), 1.0)
        f = A / np.pi * (1 + r * s / t) * d[:, 2]
        e = np.sum(f.reshape(M.shape) * w_mu[:, None]) * 2 * np.pi / 512
        assert e == pytest.approx(fon_albedo_paper(np.array(mu_i), r), abs=2e-4)


def test_eon_roughness_follows_the_lecture_sigma():
    """σ = 0 is Lambert with and without compensation; σ = π/2 gives r = B/A = 0.776."""
    assert eon_r(HALF_PI) == pytest.approx(0.776, abs=1e-3)
    rng = np.random.default_rng(3)
    d, w = random_hemisphere(rng, 512, 0.01), random_hemisphere(rng, 512, 0.01)
    lam, _ = eval_and_pdf(mi.load_dict({"type": "lambert", "reflectance": 0.7}), w, d)
    eon, _ = eval_and_pdf(load(sigma=0.0, reflectance=0.7, energy_compensation=True), w, d)
    np.testing.assert_allclose(eon, lam, rtol=1e-5)
