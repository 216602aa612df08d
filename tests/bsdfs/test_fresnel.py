"""cook_torrance's Fresnel forms (``fresnel``) and plastic base (``base``):
each Fresnel form against an independent NumPy transcription of its formula,
the exact conductor against Mitsuba's ``roughconductor`` (eval, pdf and
sample, RGB and spectral), the dielectric with the plastic base against
``roughplastic``. What every option shares (χ², furnace, reciprocity,
extremes, bad values): the battery, through cook_torrance's cases."""
import math

import numpy as np
import pytest

import drjit as dr
import mitsuba as mi

from mi_brdfs.bsdfs import fresnel
from mi_brdfs._jit import from_numpy
import lecture
from support import (active_variant, assert_refused, eval_and_pdf, floats, points,
                     random_hemisphere, rgb, surface)


# ----------------------------------------------------------------------------
#  The formulas, transcribed independently in NumPy
# ----------------------------------------------------------------------------

def conductor_np(cos_i, eta, kappa):
    """|r_s|² and |r_p|² of the Fresnel equations in complex arithmetic, averaged:
    n = η + iκ, cos θ_t = √(n² - sin² θ)/n (Born & Wolf §14.2)."""
    n = eta + 1j * kappa
    root = np.sqrt(n * n - (1.0 - cos_i**2) + 0j)            # n cos θ_t
    r_s = (cos_i - root) / (cos_i + root)
    r_p = (n * n * cos_i - root) / (n * n * cos_i + root)
    return 0.5 * (np.abs(r_s) ** 2 + np.abs(r_p) ** 2)


def f82_np(f0, tint, cos_i):
    """Hoffman 2023, eq. of the F82-tint model: Schlick less a·μ(1 - μ)^6, a set
    so that F(μ̄ = 1/7) = tint · Schlick(μ̄)."""
    schlick = lambda mu: f0 + (1 - f0) * (1 - mu) ** 5
    mu_bar = 1.0 / 7.0
    target = tint * schlick(mu_bar)
    a = (schlick(mu_bar) - target) / (mu_bar * (1 - mu_bar) ** 6)
    return np.maximum(schlick(cos_i) - a * cos_i * (1 - cos_i) ** 6, 0.0)


def traced(fn, *columns):
    """fn of Floats made from NumPy columns, back in NumPy (float64)."""
    return np.array(fn(*(from_numpy(mi.Float, c) for c in columns)), dtype=np.float64)


COS = np.concatenate([np.linspace(0.0, 1.0, 2001), [1e-6, 1e-3]])


@pytest.mark.parametrize("eta, kappa", [(0.143, 3.98), (0.27, 2.78), (1.44, 1.8), (1.5, 0.0),
                                        (0.0, 1.0), (2.9, 3.1), (0.05, 7.6)])
def test_conductor_formula(eta, kappa):
    ours = traced(lambda c: fresnel.conductor(mi.Float(eta), mi.Float(kappa), c), COS)
    np.testing.assert_allclose(ours, conductor_np(COS, eta, kappa), rtol=2e-5, atol=2e-6)


@pytest.mark.parametrize("eta", [1.5, 1.0 / 1.5, 1.333, 2.4])
def test_dielectric_formula(eta):
    ours = traced(lambda c: fresnel.dielectric(mi.Float(eta), c), COS)
    # (the conductor with κ = 0 is the dielectric, total internal reflection included)
    np.testing.assert_allclose(ours, conductor_np(COS, eta, 0.0), rtol=2e-5, atol=2e-6)


@pytest.mark.parametrize("f0, tint", [(0.9, 0.6), (0.5, 1.0), (0.04, 0.0), (1.0, 0.3)])
def test_f82_formula(f0, tint):
    ours = traced(lambda c: fresnel.f82(mi.Float(f0), mi.Float(tint), c), COS)
    np.testing.assert_allclose(ours, f82_np(f0, tint, COS), rtol=2e-5, atol=2e-6)
    at = traced(lambda c: fresnel.f82(mi.Float(f0), mi.Float(tint), c), np.array([1 / 7]))
    assert at[0] == pytest.approx(tint * (f0 + (1 - f0) * (6 / 7) ** 5), rel=1e-5)


def hemispherical_average(F):
    """2 ∫ F(μ) μ dμ by the trapezoid rule on 400,001 points (NumPy)."""
    mu = np.linspace(0.0, 1.0, 400_001)
    return float(np.trapezoid(2.0 * F(mu) * mu, mu))


@pytest.mark.parametrize("form, args, numpy", [
    ("conductor", (0.143, 3.98), lambda mu: conductor_np(mu, 0.143, 3.98)),
    ("conductor", (1.66, 9.22), lambda mu: conductor_np(mu, 1.66, 9.22)),
    ("conductor", (0.0, 1.0), lambda mu: np.ones_like(mu)),
    ("dielectric", (1.5,), lambda mu: conductor_np(mu, 1.5, 0.0)),
    ("dielectric", (1.0 / 1.33,), lambda mu: conductor_np(mu, 1.0 / 1.33, 0.0)),
    ("dielectric", (1.0 / 2.4,), lambda mu: conductor_np(mu, 1.0 / 2.4, 0.0)),
    ("f82", (0.9, 0.2), lambda mu: f82_np(0.9, 0.2, mu)),
    ("f82", (0.04, 1.0), lambda mu: f82_np(0.04, 1.0, mu)),
    ("schlick", (0.3,), lambda mu: 0.3 + 0.7 * (1 - mu) ** 5),
])
def test_hemispherical_average(form, args, numpy):
    """F_avg of each form (what energy compensation reads the walk tables
    with) against the trapezoid rule of the NumPy transcriptions; the F0 of the
    equivalent Schlick curve has that average (Schlick's own F0 maps to itself)."""
    ours = float(np.array(getattr(fresnel, form + "_average")(*(mi.Float(a) for a in args)))[0])
    truth = hemispherical_average(numpy)
    assert ours == pytest.approx(truth, abs=2e-6)
    f0 = float(np.array(fresnel.schlick_equivalent(mi.Float(truth)))[0])
    assert f0 + (1 - f0) / 21 == pytest.approx(truth, abs=1e-6) or f0 in (0.0, 1.0)
    if form == "schlick":
        assert f0 == pytest.approx(args[0], abs=1e-6)


# ----------------------------------------------------------------------------
#  The exact conductor is roughconductor
# ----------------------------------------------------------------------------

CONDUCTORS = [{"material": "Au"}, {"material": "Cu"}, {"eta": 1.3, "kappa": 2.0}, {}]
ROUGHNESS = [{"alpha": 0.3}, {"alpha_u": 0.1, "alpha_v": 0.4}]
WAVELENGTHS = (420.0, 520.0, 610.0, 690.0)


def conductor_pair(distribution: str, roughness: dict, material: dict, m_s=None):
    """cook_torrance with the exact conductor (k 0, Smith G) and roughconductor,
    alike (roughconductor's extinction is ``k``, ours ``kappa``)."""
    theirs = {("k" if k == "kappa" else k): v for k, v in material.items()}
    reflectance = {} if m_s is None else {"specular_reflectance": m_s}
    return (mi.load_dict({"type": "cook_torrance", "fresnel": "conductor", "k": 0.0,
                          "geometry": "smith", "distribution": distribution, **roughness,
                          **material, **reflectance}),
            mi.load_dict({"type": "roughconductor", "distribution": distribution, **roughness,
                          **theirs, **reflectance}))


def at(si):
    """si with the wavelengths set in spectral variants (a measured spectrum is
    read at them)."""
    if mi.is_spectral:
        si.wavelengths = mi.Spectrum(*WAVELENGTHS)
    return si


def compare(ours, theirs, rng, rtol, n=8192, pdf_rtol=None):
    """eval and pdf of two BSDFs at the same random viewers and lights; and
    ours's samples (direction, pdf, weight) against theirs's pdf and eval / pdf
    at the direction ours sampled (the two samplers map the random numbers to
    directions differently; that they draw the same density is the χ² tests')."""
    wi, wo = random_hemisphere(rng, n, 0.02), random_hemisphere(rng, n, 0.02)
    ctx = mi.BSDFContext()
    si = at(surface(wi))
    to_np = lambda x: np.array(x, dtype=np.float64)
    wo = mi.Vector3f(*(mi.Float(x) for x in wo.T))
    v, p = to_np(ours.eval(ctx, si, wo)), to_np(ours.pdf(ctx, si, wo))
    v_, p_ = to_np(theirs.eval(ctx, si, wo)), to_np(theirs.pdf(ctx, si, wo))
    big = v_ > 1e-5 * v_.max()
    assert big.sum() > 1000
    np.testing.assert_allclose(v[big], v_[big], rtol=rtol)
    np.testing.assert_allclose(v, v_, rtol=rtol, atol=1e-5 * v_.max())
    pdf_rtol = pdf_rtol or rtol
    np.testing.assert_allclose(p, p_, rtol=pdf_rtol, atol=1e-6)
    bs, weight = ours.sample(ctx, si, floats(rng.random(n)), points(rng.random(n), rng.random(n)))
    q, w = to_np(bs.pdf), to_np(weight)
    q_, f_ = to_np(theirs.pdf(ctx, si, bs.wo)), to_np(theirs.eval(ctx, si, bs.wo))
    # (where ours failed, a reflection below the surface, it reports pdf 0 and wo = 0)
    ok = (q_ > 1e-3) & (q > 0)
    assert ok.mean() > 0.5 and (q > 0).mean() > 0.9
    np.testing.assert_allclose(q[ok], q_[ok], rtol=pdf_rtol)
    np.testing.assert_allclose(w[..., ok], f_[..., ok] / q_[ok], rtol=max(rtol, pdf_rtol),
                               atol=1e-6)
    return v_


# GGX: to float precision. Beckmann: Mitsuba's G1 is a rational fit of the erf
# form (within 0.35 % per G1, test_cook_torrance.RTOL), ours another.
RTOL = {"ggx": 2e-5, "beckmann": 7e-3}


@pytest.mark.parametrize("material", CONDUCTORS, ids=lambda m: ",".join(m) or "default")
@pytest.mark.parametrize("roughness", ROUGHNESS, ids=lambda r: ",".join(r))
@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
def test_conductor_equals_roughconductor(rng, distribution, roughness, material):
    ours, theirs = conductor_pair(distribution, roughness, material,
                                  rgb([0.9, 0.7, 0.8]) if material else None)
    value = compare(ours, theirs, rng, RTOL[distribution])
    if material.get("material") == "Au":       # the hue: red over blue
        assert value[0].sum() > 1.5 * value[2].sum()


@pytest.mark.parametrize("material", [{"material": "Au"}, {"material": "Cr"},
                                      {"eta": 1.3, "kappa": 2.0}],
                         ids=lambda m: ",".join(m))
@pytest.mark.parametrize("roughness", ROUGHNESS, ids=lambda r: ",".join(r))
def test_conductor_equals_roughconductor_spectral(rng, roughness, material):
    """In a spectral variant: the measured spectra read at the wavelengths."""
    with active_variant("llvm_ad_spectral"):
        ours, theirs = conductor_pair("ggx", roughness, material)
        value = compare(ours, theirs, rng, RTOL["ggx"])
        if "material" in material:      # not a constant spectrum: the channels differ
            assert np.ptp(value.sum(axis=1)) > 0.05 * value.sum(axis=1).max()


@pytest.mark.parametrize("variant", ["llvm_ad_spectral", "scalar_spectral"])
def test_compensated_conductor_per_wavelength(rng, variant):
    """Energy compensation in spectral variants reads the walk tables per
    wavelength: a compensated gold's value at each of the four wavelengths is
    that of a compensated conductor of the constant index gold has there."""
    with active_variant(variant):
        common = {"type": "cook_torrance", "fresnel": "conductor", "k": 0.0,
                  "geometry": "smith", "distribution": "ggx", "alpha": 0.6,
                  "energy_compensation": True}
        gold = mi.load_dict({**common, "material": "Au"})
        wi, wo = random_hemisphere(rng, 16, 0.05), random_hemisphere(rng, 16, 0.05)
        ctx = mi.BSDFContext()
        eta, kappa = (np.array(gold.eval_attribute(name, at(dr.zeros(mi.SurfaceInteraction3f))),
                               dtype=np.float64).ravel() for name in ("eta", "kappa"))
        assert np.ptp(eta) > 0.3                      # the wavelengths see different indices
        for k in range(len(wi)):
            si = at(dr.zeros(mi.SurfaceInteraction3f))
            si.wi = mi.Vector3f(*map(float, wi[k]))
            v = mi.Vector3f(*map(float, wo[k]))
            ours = np.array(gold.eval(ctx, si, v), dtype=np.float64).ravel()
            for j in range(len(WAVELENGTHS)):
                grey = mi.load_dict({**common, "eta": float(eta[j]), "kappa": float(kappa[j])})
                value = np.array(grey.eval(ctx, si, v), dtype=np.float64).ravel()[j]
                assert ours[j] == pytest.approx(value, rel=1e-4, abs=1e-7)


def walk_f0_np(F) -> np.ndarray:
    """The walk tables' F0 for a Fresnel form (NumPy): the Schlick curve's
    F0 of the same hemispherical average, (21 F_avg - 1)/20 in [0, 1]."""
    return np.clip((21.0 * hemispherical_average(F) - 1.0) / 20.0, 0.0, 1.0)


def test_the_walk_f0_of_constant_indices_is_computed_once(rng):
    """Compensated with the exact Fresnel of constant indices (RGB), the
    walk tables' F0 is computed at load, not at every call: it is the NumPy
    F_avg's Schlick equivalent per channel, and eval is that of the same
    indices through a texture (read per point, the F0 computed per call);
    differentiated indices are read per call too."""
    eta, kappa = np.array([0.2, 0.5, 1.4]), np.array([3.0, 2.4, 1.8])
    common = {"type": "cook_torrance", "fresnel": "conductor", "k": 0.0, "geometry": "smith",
              "distribution": "ggx", "alpha": 0.5, "energy_compensation": True}
    once = mi.load_dict({**common, "eta": rgb(eta), "kappa": rgb(kappa)})
    assert once.state.f0_walk
    expected = [walk_f0_np(lambda mu, e=e, k=k: conductor_np(mu, e, k)) for e, k in zip(eta, kappa)]
    np.testing.assert_allclose(np.array(once.m_f0_walk).ravel(), expected, atol=2e-5)
    unbounded = lambda v: {"type": "srgb", "color": list(map(float, v)), "unbounded": True}
    textured = {name: {"type": "checkerboard", "color0": unbounded(v), "color1": unbounded(v)}
                for name, v in (("eta", eta), ("kappa", kappa))}
    per_call = mi.load_dict({**common, **textured})
    assert not per_call.state.f0_walk
    wi, wo = random_hemisphere(rng, 2048, 0.05), random_hemisphere(rng, 2048, 0.05)
    a, b = eval_and_pdf(once, wi, wo)[0], eval_and_pdf(per_call, wi, wo)[0]
    np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-7)
    assert np.ptp(a.sum(axis=1)) > 0                     # not all black
    params = mi.traverse(once)
    dr.enable_grad(params["eta.value"])
    params.update()
    assert not once.state.f0_walk
    dielectric = mi.load_dict({**common, "fresnel": "dielectric", "int_ior": 1.5, "ext_ior": 1.0})
    assert dielectric.state.f0_walk
    assert float(np.array(dielectric.m_f0_walk).ravel()[0]) == pytest.approx(
        walk_f0_np(lambda mu: conductor_np(mu, 1.5, 0.0)), abs=2e-5)


def test_conductor_matches_numpy(rng):
    """cook_torrance's eval with the exact conductor against the lecture's
    Cook-Torrance (NumPy) with the NumPy conductor F in place of Schlick's."""
    d, w = random_hemisphere(rng, 4096, 0.05), random_hemisphere(rng, 4096, 0.05)
    eta, kappa, rho = np.array([0.2, 0.5, 1.4]), np.array([3.0, 2.4, 1.8]), 0.35
    bsdf = mi.load_dict({"type": "cook_torrance", "fresnel": "conductor", "k": 0.0,
                         "geometry": "smith", "distribution": "ggx", "alpha": rho,
                         "eta": rgb(eta), "kappa": rgb(kappa)})
    v, _ = eval_and_pdf(bsdf, w, d)
    h = lecture.half(d, w)
    wh = lecture.dot(w, h)
    shape = lecture.cook_torrance_terms(d, w, rho, 1.0, "ggx", "smith")        # F = 1
    expected = shape[:, None] * conductor_np(wh[:, None], eta[None], kappa[None])
    np.testing.assert_allclose(v, expected, rtol=2e-4, atol=1e-6)


def test_material_holds_roughconductors_data():
    """``material`` reads what roughconductor reads: its η and κ, as traverse shows them."""
    for name in ("Au", "Ag", "Al"):
        ours = mi.traverse(mi.load_dict({"type": "cook_torrance", "fresnel": "conductor",
                                         "material": name}))
        theirs = mi.traverse(mi.load_dict({"type": "roughconductor", "material": name}))
        for a, b in (("eta", "eta"), ("kappa", "k")):
            np.testing.assert_array_equal(np.array(ours[a + ".value"]),
                                          np.array(theirs[b + ".value"]))


# ----------------------------------------------------------------------------
#  F82-tint and the dielectric
# ----------------------------------------------------------------------------

def test_f82_with_tint_one_is_schlick(rng):
    d, w = random_hemisphere(rng, 2048, 0.02), random_hemisphere(rng, 2048, 0.02)
    common = {"type": "cook_torrance", "k": 0.3, "f0": 0.6, "distribution": "ggx",
              "geometry": "smith", "alpha": 0.3}
    a = eval_and_pdf(mi.load_dict({**common, "fresnel": "f82", "f82_tint": 1.0}), w, d)
    b = eval_and_pdf(mi.load_dict(common), w, d)
    for x, y in zip(a, b):
        np.testing.assert_allclose(x, y, rtol=1e-6, atol=1e-8)


def test_f82_matches_numpy(rng):
    d, w = random_hemisphere(rng, 4096, 0.05), random_hemisphere(rng, 4096, 0.05)
    tint, f0, rho = np.array([0.9, 0.6, 0.3]), 0.8, 0.3
    bsdf = mi.load_dict({"type": "cook_torrance", "fresnel": "f82", "k": 0.0, "f0": f0,
                         "f82_tint": rgb(tint), "geometry": "smith", "distribution": "ggx",
                         "alpha": rho})
    v, _ = eval_and_pdf(bsdf, w, d)
    wh = lecture.dot(w, lecture.half(d, w))
    shape = lecture.cook_torrance_terms(d, w, rho, 1.0, "ggx", "smith")
    expected = shape[:, None] * f82_np(f0, tint[None], wh[:, None])
    np.testing.assert_allclose(v, expected, rtol=2e-4, atol=1e-6)


@pytest.mark.parametrize("int_ior, ext_ior, eta", [(1.5, 1.0, 1.5), ("bk7", "air", 1.5046 / 1.000277),
                                                   (1.0, 1.333, 1.0 / 1.333)])
def test_dielectric_matches_numpy(rng, int_ior, ext_ior, eta):
    d, w = random_hemisphere(rng, 4096, 0.05), random_hemisphere(rng, 4096, 0.05)
    bsdf = mi.load_dict({"type": "cook_torrance", "fresnel": "dielectric", "k": 0.0,
                         "int_ior": int_ior, "ext_ior": ext_ior, "geometry": "smith",
                         "distribution": "beckmann", "alpha": 0.2})
    v, _ = eval_and_pdf(bsdf, w, d)
    wh = lecture.dot(w, lecture.half(d, w))
    shape = lecture.cook_torrance_terms(d, w, 0.2, 1.0, "beckmann", "smith")
    expected = shape * conductor_np(wh, eta, 0.0)
    np.testing.assert_allclose(v[:, 0], expected, rtol=2e-4, atol=1e-6)


# ----------------------------------------------------------------------------
#  The plastic base is roughplastic's
# ----------------------------------------------------------------------------

def roughplastic_tables(distribution: str, alpha: float, eta: float):
    """roughplastic's own t(μ) at the 64 nodes μ_j and internal reflectance R,
    read back from its diffuse lobe: m_D/(1 - R)·t(μ_i) t(μ_o) μ_o/(π η²), and
    m_D/(1 - m_D R)·... with ``nonlinear`` (m_D = 0.5): their ratio at one pair
    of directions gives R, then t(1) and t(μ_j)."""
    mu = np.maximum(np.linspace(0.0, 1.0, 64), 1e-6)
    wi = np.stack([np.sqrt(1.0 - mu * mu), 0.0 * mu, mu], axis=1)
    up = np.tile([[0.0, 0.0, 1.0]], (64, 1))
    ctx = mi.BSDFContext()
    ctx.component = 1                                     # its diffuse lobe
    def f(nonlinear, a, b):
        bsdf = mi.load_dict({"type": "roughplastic", "distribution": distribution,
                             "alpha": alpha, "int_ior": eta, "ext_ior": 1.0,
                             "diffuse_reflectance": 0.5, "nonlinear": nonlinear})
        return eval_and_pdf(bsdf, a, b, ctx=ctx)[0][:, 0]
    lin, non = f(False, up, up)[0], f(True, up, up)[0]
    q = lin / non                                         # (1 - R/2)/(1 - R)
    R = (q - 1.0) / (q - 0.5)
    K = 0.5 / (1.0 - R) / np.pi / eta**2
    t1 = math.sqrt(lin / K)
    return f(False, wi, up) / K / t1, R


@pytest.mark.parametrize("distribution, alpha, eta", [("ggx", 0.01, 1.5), ("ggx", 0.1, 1.49),
                                                      ("ggx", 1.0, 1.2), ("beckmann", 0.3, 1.5)])
def test_plastic_tables_are_roughplastics(distribution, alpha, eta):
    """Our quadrature of the interface's transmittance (slopes, Gauss-Legendre
    in tan) and roughplastic's (visible normals, Gauss-Legendre in the sample
    square) of the same integrals: within 4e-4 (measured 1.9e-4 to 3.6e-4,
    Beckmann's G1 fit included), and R within 5e-4 (measured 2.2e-4)."""
    from mi_brdfs.bsdfs.cook_torrance import plastic_tables
    t, r = plastic_tables(distribution, alpha, eta)
    t_ref, r_ref = roughplastic_tables(distribution, alpha, eta)
    np.testing.assert_allclose(t, t_ref, atol=4e-4)
    assert r == pytest.approx(r_ref, abs=5e-4)
    assert 0.0 < t.min() and t.max() < 1.0


PLASTICS = [("ggx", 0.1, {}), ("ggx", 0.4, {"nonlinear": True}),
            ("ggx", 0.2, {"specular_reflectance": rgb([0.5, 0.7, 0.9]),
                          "diffuse_reflectance": rgb([0.8, 0.2, 0.1]), "int_ior": "bk7"}),
            ("beckmann", 0.3, {})]


@pytest.mark.parametrize("distribution, alpha, more", PLASTICS,
                         ids=lambda x: x if isinstance(x, str) else None)
def test_plastic_equals_roughplastic(rng, distribution, alpha, more):
    """fresnel="dielectric", base="plastic": eval, pdf and sample weights equal
    roughplastic's up to the two quadratures of t and R (above): eval within
    1e-3 relative for GGX (measured 7e-4), the pdf within 6e-3 (its lobe choice
    holds 1 - t(θ_i), whose relative error grows where t -> 1); Beckmann within
    7e-3 (its G1 fit, test_cook_torrance.RTOL)."""
    ours = mi.load_dict({"type": "cook_torrance", "base": "plastic", "fresnel": "dielectric",
                         "geometry": "smith", "distribution": distribution, "alpha": alpha,
                         **more})
    theirs = mi.load_dict({"type": "roughplastic", "distribution": distribution, "alpha": alpha,
                           **more})
    rtol = {"ggx": 1e-3, "beckmann": 7e-3}[distribution]
    compare(ours, theirs, rng, rtol, pdf_rtol=6e-3 if distribution == "ggx" else 1e-2)


def test_plastic_attributes_are_roughplastics():
    """The diffuse colour and the roughness read back as roughplastic's
    (``eval_attribute``; the other checks of Mitsuba's roughplastic tests,
    χ² and eval_pdf, are in the battery's cases)."""
    common = {"diffuse_reflectance": rgb([0.5, 0.6, 0.7]), "alpha": 0.4}
    ours = mi.load_dict({"type": "cook_torrance", "base": "plastic", "fresnel": "dielectric",
                         "geometry": "smith", **common})
    theirs = mi.load_dict({"type": "roughplastic", **common})
    si = dr.zeros(mi.SurfaceInteraction3f)
    for bsdf in (ours, theirs):
        assert np.allclose(np.array(bsdf.eval_attribute("diffuse_reflectance", si)).ravel(),
                           [0.5, 0.6, 0.7])
        assert np.allclose(np.array(bsdf.eval_attribute_1("alpha", si)).ravel(), 0.4)


# ----------------------------------------------------------------------------
#  Bad input: one line
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("given, name, value, valid", [
    ({"fresnel": "conductor", "material": "Unobtainium"}, "material", "'Unobtainium'",
     "one of Ag, Al"),
    ({"material": "Au"}, "material", "'Au'", 'fresnel="conductor"'),
    ({"fresnel": "conductor", "material": "Au", "eta": 1.0}, "eta", "1.0",
     "either material or eta/kappa"),
    ({"fresnel": "conductor", "eta": -1.0}, "eta", "-1.0", "[0, "),
    ({"fresnel": "dielectric", "int_ior": "unobtainium"}, "int_ior", "'unobtainium'",
     "one of Mitsuba's names"),
    ({"fresnel": "dielectric", "int_ior": 0.0}, "int_ior", "0.0", "[0.001, "),
    ({"base": "plastic", "fresnel": "dielectric", "geometry": "smith",
      "energy_compensation": True}, "energy_compensation", "True",
     'false with base="plastic" (no random walk of the substrate'),
    ({"fresnel": "f82", "f82_tint": 1.5}, "f82_tint", "1.5", "[0, 1]"),
    ({"nonlinear": True}, "nonlinear", "True", 'false unless base="plastic"'),
    ({"base": "plastic", "fresnel": "dielectric", "geometry": "smith", "k": 0.5}, "k", "0.5",
     "not given with base=\"plastic\""),
    ({"base": "plastic", "geometry": "smith"}, "fresnel", "'schlick'", '"dielectric"'),
    ({"base": "plastic", "fresnel": "dielectric"}, "geometry", "'cook_torrance'", '"smith"'),
    ({"base": "plastic", "fresnel": "dielectric", "geometry": "smith", "mode": "scanline"},
     "mode", "'scanline'", '"hdr"'),
    ({"base": "plastic", "fresnel": "dielectric", "geometry": "smith", "distribution": "blinn"},
     "distribution", "'blinn'", '"beckmann" or "ggx"'),
    ({"base": "plastic", "fresnel": "dielectric", "geometry": "smith", "alpha_u": 0.1},
     "alpha_u", "0.1", "isotropic"),
    ({"base": "plastic", "fresnel": "dielectric", "geometry": "smith",
      "alpha": {"type": "checkerboard", "color0": 0.1, "color1": 0.2}}, "alpha",
     "a texture (Checkerboard)", "a constant"),
])
def test_bad_input_is_one_line(given, name, value, valid):
    assert_refused({"type": "cook_torrance", **given}, name, value, valid)
