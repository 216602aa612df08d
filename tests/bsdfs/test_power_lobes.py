"""What phong and blinn, the two power-cosine lobes, promise alike: the hdr lobe
is normalised at normal incidence (albedo m_S exactly), decreases towards
grazing incidence and never exceeds m_D + m_S; a textured exponent is looked
up per shading point; very narrow lobes (gamma up to 1e8) are sampled and
evaluated exactly in float32. Each model's module supplies its closed forms
and the float64 statistics used here (``test_phong``, ``test_blinn``).

The directional albedo is a deterministic product quadrature in the lobe's own
polar coordinates about the viewer's mirror direction (support.lobe_quadrature),
independent of the plugin's sampler. TOL: measured quadrature error of this
rule against the same rule with 2x the Gauss nodes and 4x the phi nodes, over
every (gamma, theta_i) below with m_S = 1: at most 8.3e-6 (phong) and 1.1e-5
(blinn), float32 evaluation included; TOL = 1e-4 leaves a margin of ~10.
"""
import itertools

import numpy as np
import pytest
from scipy import stats

import mitsuba as mi

import test_blinn
import test_phong
from support import (eval_and_pdf, mirror_lobe_albedo, rgb, sample_narrow_lobe, surface,
                     uniform_hemisphere_grid)

MODULES = {"phong": test_phong, "blinn": test_blinn}
MODELS = pytest.mark.parametrize("model", sorted(MODULES))
TOL = 1e-4
THETAS = [0, 15, 30, 45, 60, 75, 80, 85, 88, 89]
COLOURS = [(0.0, 1.0), (0.0, 0.7), (0.3, 0.7)]      # (m_D, m_S)


M_D = np.array([1.4, 0.5, 0.2])       # colours above 1: the clamps must act
M_S = np.array([0.9, 2.0, 0.3])


def load(model, **params):
    return mi.load_dict({"type": model, **params})


def lecture_pairs(module, rng, gamma):
    """Pairs near the lobe, with lights and viewers below the surface too."""
    d, w = module.pairs(rng, 4096, gamma)
    d[:256, 2] *= -1                   # lights below the surface
    w[256:512, 2] *= -1                # viewers below it
    return d, w


@MODELS
@pytest.mark.parametrize("gamma", [1.0, 7.5, 120.0, 1e4])
def test_scanline_matches_lecture(model, rng, gamma):
    """The plugin against the model's NumPy transcription of the lecture."""
    module = MODULES[model]
    d, w = lecture_pairs(module, rng, gamma)
    bsdf = load(model, mode="scanline", diffuse_reflectance=rgb(M_D),
                specular_reflectance=rgb(M_S), exponent=gamma)
    value, _ = eval_and_pdf(bsdf, wi=w, wo=d)
    np.testing.assert_allclose(value, module.lecture_scanline(d, w, M_D, M_S, gamma),
                               rtol=2e-5, atol=1e-6)
    spec = M_S[None, :] * np.clip(module.lobe_cosine(d, w), 0, 1)[:, None] ** gamma
    assert (spec > 1).any() and ((spec > 0.01) & (spec < 1)).any()    # clamp acts and not
    assert (M_D[0] * d[:, 2] > 1).any()


@MODELS
@pytest.mark.parametrize("gamma", [1.0, 7.5, 120.0, 1e4])
def test_hdr_matches_normalised_formula(model, rng, gamma):
    """The plugin against the model's NumPy transcription of its normalised hdr lobe."""
    module = MODULES[model]
    d, w = lecture_pairs(module, rng, gamma)
    bsdf = load(model, diffuse_reflectance=rgb(M_D), specular_reflectance=rgb(M_S),
                exponent=gamma)
    value, _ = eval_and_pdf(bsdf, wi=w, wo=d)
    expected = module.normalised_hdr(d, w, M_D, M_S, gamma)
    np.testing.assert_allclose(value, expected, rtol=2e-5, atol=1e-6 * expected.max())
    assert gamma < 5 or (value > 1).any()       # unclamped


_tables = {}


def furnace_table(model):
    """{(m_D, m_S, gamma): [E(theta) for theta in THETAS]} (channel 0; lobes are grey)."""
    if model not in _tables:
        module = MODULES[model]
        table = {}
        for (m_d, m_s), gamma in itertools.product(COLOURS, module.GAMMAS):
            bsdf = load(model, diffuse_reflectance=m_d, specular_reflectance=m_s, exponent=gamma)
            width = module.lobe_width(gamma)
            table[m_d, m_s, gamma] = np.array(
                [mirror_lobe_albedo(bsdf, th, width)[0] for th in THETAS])
        _tables[model] = table
    return _tables[model]


@MODELS
def test_furnace_never_above_one(model, capsys):
    table = furnace_table(model)
    with capsys.disabled():
        print(f"\n{model} (hdr) white furnace: directional albedo E(theta_i), m_D + m_S = 1")
        print("  m_D  m_S  gamma   " + " ".join(f"{th:>7d}" for th in THETAS))
        for (m_d, m_s, gamma), values in table.items():
            if m_d + m_s == 1.0:
                print(f"  {m_d:.1f}  {m_s:.1f}  {gamma:7.0e} " + " ".join(f"{e:7.5f}" for e in values))
    for (m_d, m_s, gamma), values in table.items():
        assert values.max() <= m_d + m_s + TOL, (m_d, m_s, gamma, values)
        assert values.min() >= m_d - TOL            # the diffuse lobe alone reflects m_D


@MODELS
def test_furnace_normal_incidence_reflects_m_s(model):
    """The normalised lobe: E(0) = m_S exactly, for every gamma (and m_D + m_S with a diffuse lobe)."""
    for (m_d, m_s, gamma), values in furnace_table(model).items():
        assert values[0] == pytest.approx(m_d + m_s, abs=TOL), (m_d, m_s, gamma)


@MODELS
def test_furnace_decreases_towards_grazing(model):
    for key, values in furnace_table(model).items():
        assert np.all(np.diff(values) <= TOL), (key, values)


@MODELS
def test_furnace_closed_forms(model):
    """Each model's closed forms of E(theta_i) (its module's ``closed_forms``)."""
    for (m_d, m_s, gamma), angles, expected in MODULES[model].closed_forms(np.array(THETAS)):
        values = furnace_table(model)[m_d, m_s, gamma]
        np.testing.assert_allclose(values[angles], expected, atol=TOL)


@MODELS
def test_furnace_uniform_hemisphere_estimate_agrees(model):
    """The albedo by jittered strata uniform over the hemisphere agrees too,
    for the broad lobes it can resolve. Measured error against the lobe
    quadrature (3 seeds): at most 4.7e-5 (phong, gamma = 0, 88°)."""
    wo = uniform_hemisphere_grid(512, 2048, seed=271828)
    table = furnace_table(model)
    for gamma in (0.0, 1.0, 10.0):
        bsdf = load(model, diffuse_reflectance=0.3, specular_reflectance=0.7, exponent=gamma)
        for i, th in enumerate(THETAS):
            wi = np.tile(np.array([np.sin(np.radians(th)), 0.0, np.cos(np.radians(th))]),
                         (len(wo), 1))
            e = 2 * np.pi * eval_and_pdf(bsdf, wi, wo)[0][:, 0].mean()
            assert e == pytest.approx(table[0.3, 0.7, gamma][i], abs=2.5e-4), (gamma, th)


@MODELS
def test_exponent_texture(model, rng):
    """A textured exponent is looked up (eval_1) at the shading point's uv.
    (Mitsuba's checkerboard.eval_1 puts color0 where eval puts color1, so the
    expected exponent is read from the texture itself.)"""
    tex = {"type": "checkerboard", "color0": 20.0, "color1": 300.0}
    d, w = MODULES[model].pairs(rng, 2048, 20.0)
    uv = rng.random((len(d), 2))
    value, pdf = eval_and_pdf(load(model, exponent=tex), w, d, uv=uv)
    si = surface(w, uv)
    gammas = np.array(mi.load_dict(tex).eval_1(si))
    for gamma in (20.0, 300.0):
        cells = gammas == gamma
        assert cells.sum() > 500
        v_ref, p_ref = eval_and_pdf(load(model, exponent=gamma), w[cells], d[cells])
        np.testing.assert_allclose(value[cells], v_ref, rtol=1e-6)
        np.testing.assert_allclose(pdf[cells], p_ref, rtol=1e-6)


@MODELS
def test_only_present_lobes_are_declared(model):
    F = mi.BSDFFlags
    assert load(model).flags() == F.DiffuseReflection | F.GlossyReflection | F.FrontSide
    spec = load(model, diffuse_reflectance=0.0)
    assert spec.flags() == F.GlossyReflection | F.FrontSide and spec.component_count() == 1
    diff = load(model, specular_reflectance=0.0)
    assert diff.flags() == F.DiffuseReflection | F.FrontSide and diff.component_count() == 1


@MODELS
@pytest.mark.parametrize("gamma", [1e4, 1e6, 1e8])
@pytest.mark.parametrize("theta", [0, 45])
def test_high_exponent_lobe_is_exact(model, gamma, theta):
    """Samples of a very narrow lobe follow the lobe's exact distribution
    (Kolmogorov-Smirnov on the model's float64 statistic, Exp(1)-distributed)
    and pdf() and eval() at the sampled directions match the float64 formulas:
    the lobe is not lost to float32 cancellation. (The rotationally uniform
    phi is covered by the battery's chi-square.)"""
    module = MODULES[model]
    bsdf = load(model, diffuse_reflectance=0.0, specular_reflectance=1.0, exponent=gamma)
    wi, wo, pdf = sample_narrow_lobe(bsdf, theta, 100_000, seed=int(gamma) + theta)
    assert np.all(pdf > 0)                            # nothing lost below the horizon
    ks = stats.kstest(module.lobe_statistic(wi, wo, gamma), "expon")
    assert ks.pvalue > 1e-3, ks
    pdf_ref, eval_ref = module.lobe_reference(wi, wo, gamma)
    rtol = 1e-5                       # measured: at most 2.5e-6 at every gamma
    np.testing.assert_allclose(pdf, pdf_ref, rtol=rtol)
    np.testing.assert_allclose(eval_and_pdf(bsdf, wi, wo)[0][:, 0], eval_ref, rtol=rtol)


@MODELS
def test_naive_sampler_would_fail_the_high_exponent_test(model):
    """Power of the test above: the textbook float32 sampler
    cos = u^(1/(e+1)), sin² = 1 - cos² is rejected."""
    gamma, n = 1e6, 100_000
    e = MODULES[model].sampled_exponent(gamma)
    u = np.random.default_rng(5).random(n).astype(np.float32)
    cos_ = np.power(u, np.float32(1.0 / (e + 1.0)), dtype=np.float32)
    sin2 = (np.float32(1.0) - cos_ * cos_).astype(np.float64)
    statistic = -(e + 1) * 0.5 * np.log1p(-sin2)
    assert stats.kstest(statistic, "expon").pvalue < 1e-6
