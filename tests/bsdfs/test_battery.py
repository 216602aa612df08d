"""The conformance battery: every registered plugin, in both modes, through the
same checks, driven by its cases (its module's ``cases()``, mi_brdfs/bsdfs/cases.py) and its
parameter declarations (``PARAMS``, ``OPTIONS``):

1. load, eval, pdf, sample: finite, non-negative, upwards, flags;
2. χ² of the sampler against the pdf (Mitsuba's test), with one Šidák
   correction over every χ² run of the suite, and a negative control per model;
3. sample weight × pdf = eval, pdf() = the pdf sample() reports, and
   eval_pdf() = (eval(), pdf());
4. reciprocity (hdr) where the model declares it;
5. the white furnace, by an independent quadrature: bounded, or 1 where the
   model promises it (energy compensation);
6. the numerical extremes: directions down to cos θ = 1e-30 and 0, parameter
   extremes — values, pdfs, sample weights and gradients finite, non-negative;
7. gradients against finite differences, for every parameter, and for colours
   and weights also at their bounds (one-sided); the sample weight's gradient
   that of eval / pdf at the sampled direction;
8. bad values refused with one line (plugin, parameter, value, valid range) at
   load time and at ``params.update()``; bad options too;
9. traverse and update; a lobe is dropped only when it cannot matter;
10. every property form a Mitsuba scene gives a parameter, read as Mitsuba's
    own plugins read it, and direct calls as Mitsuba's bindings take them
    (the other variants: tests/test_variants.py).
11. frozen evaluation (``dr.freeze``) of every compensated configuration: the
    tables a plugin reads are part of what Dr.Jit traverses.

A model's own module keeps only its independent transcription of the lecture
and what is particular to it.

The tests are built from the declarations and the cases alone: no BSDF is
loaded while pytest collects them, and each model's entry is built on its
own, so a broken model or its cases fail its own tests only (a plugin
whose entry cannot be built gets one failing case per test, ``NAME-entry``;
tests/bsdfs/test_registry.py checks that).
"""
from __future__ import annotations

import gc
import itertools
import math

import numpy as np
import pytest

import drjit as dr
import mitsuba as mi

from mi_brdfs.bsdfs import BY_NAME
from mi_brdfs.bsdfs.params import ParameterError
from mi_brdfs.bsdfs import cases
from mi_brdfs.bsdfs.cases import ALL as CASES
from support import (CHI2_ALPHA, BrokenCases, albedo, assert_refused, chi2_test, chi2_test_count,
                     config_id, direct_call_failures, eval_and_pdf, error_line, finite,
                     finite_difference, floats, points, f32, mirror_pairs,
                     property_form_failures, random_hemisphere, surface, vec)

PLUGINS = BY_NAME
MODES = ("hdr", "scanline")


def from_entries(make, nargs: int = 1) -> list:
    """pytest params: ``make(name, cases)`` for every plugin's cases. A
    plugin whose entry cannot be built gets one case, failing with its error
    (conftest.pytest_pyfunc_call), instead of a collection error for all."""
    params = []
    for name in PLUGINS:
        try:
            params += make(name, cases.of(name))
        except Exception as error:
            params.append(pytest.param(*[BrokenCases(name, error)] * nargs, id=f"{name}-cases"))
    return params


def modes_of(config: dict) -> tuple[str, ...]:
    """The modes a configuration runs in: its own, hdr only for compensated
    ones (compensation belongs to hdr), else both."""
    if "mode" in config:
        return (config["mode"],)
    return ("hdr",) if config.get("energy_compensation") else MODES


def in_mode(config: dict, mode: str) -> dict:
    return {**config, "mode": mode}


def each_mode(configs) -> list:
    """pytest params: every configuration in each of its modes."""
    return [pytest.param(in_mode(c, m), id=config_id(in_mode(c, m)))
            for c in configs for m in modes_of(c)]


def wants_scanline(config: dict) -> dict:
    """A configuration's colours scaled down for scanline mode (below the clamps)."""
    out = dict(config)
    for k, v in config.items():
        if isinstance(v, float) and k.endswith(("reflectance", "shade")):
            out[k] = 0.3 * v
    return out


# ----------------------------------------------------------------------------
#  0. Every plugin's cases cover every check
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("name", PLUGINS)
def test_cases_cover_the_plugin(name):
    entry = CASES[name]
    chi2_modes = {m for c in entry.chi2 for m in modes_of(c.config)}
    assert chi2_modes == set(MODES), f"{name}: χ² in {chi2_modes} only"
    for part in ("consistency", "furnace", "extremes", "interior", "fits"):
        assert getattr(entry, part), f"{name}: no {part} configurations"
    if PLUGINS[name].compensable:
        for part in ("consistency", "furnace", "extremes", "interior"):
            configs = [getattr(c, "config", c) for c in getattr(entry, part)]
            assert any(c.get("energy_compensation") for c in configs), \
                f"{name}: no compensated {part} configuration"
        assert any(c.config.get("energy_compensation") for c in entry.chi2)


# ----------------------------------------------------------------------------
#  1. Load, eval, pdf, sample
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("config", each_mode([{"type": n} for n in PLUGINS]))
def test_load_eval_pdf_sample(config, rng):
    bsdf = mi.load_dict(config)
    assert bsdf.flags() != 0 and bsdf.component_count() >= 1
    assert type(bsdf).__name__ in str(bsdf) and f"mode={config['mode']}" in str(bsdf)
    n = 4096
    wi, wo = random_hemisphere(rng, n), random_hemisphere(rng, n)
    value, pdf = eval_and_pdf(bsdf, wi, wo)
    assert finite(value) and finite(pdf) and (value >= 0).all() and (pdf >= 0).all()
    assert (value.max(axis=1) > 0).mean() > 0.5 and (pdf > 0).mean() > 0.5
    bs, weight = bsdf.sample(mi.BSDFContext(), surface(wi), floats(rng.random(n)),
                             points(rng.random(n), rng.random(n)))
    ok = np.array(bs.pdf) > 0
    assert finite(weight) and ok.mean() > 0.3 and (np.array(bs.wo)[2][ok] > 0).all()


# ----------------------------------------------------------------------------
#  2. χ²: one Šidák correction over every χ² run of the suite
# ----------------------------------------------------------------------------

CHI2_CASES = from_entries(lambda name, e: [
    pytest.param(c, theta, id=f"{config_id(c.config)}-theta={theta}")
    for c in e.chi2 for theta in c.thetas], nargs=2)
NEGATIVE = from_entries(lambda name, e: [pytest.param(name, id=name)] if e.negative else [])
CHI2_TEST_COUNT = chi2_test_count()      # every χ² run of the suite, the variants' included
ALPHA = CHI2_ALPHA


@pytest.mark.slow
@pytest.mark.parametrize("case, theta", CHI2_CASES)
def test_chi2(case, theta, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)          # a rejected test writes chi2_data.py
    chi2 = chi2_test(case.config, case.config, theta, case.phi, res=case.res, ires=case.ires)
    assert chi2.run(significance_level=ALPHA, test_count=CHI2_TEST_COUNT, quiet=True), \
        chi2.messages


@pytest.mark.slow
@pytest.mark.parametrize("name", NEGATIVE)
def test_chi2_detects_a_wrong_pdf(name, tmp_path, monkeypatch):
    """Negative control: a sampler tested against the pdf of a slightly
    different parameter must be rejected, or the χ² tests prove nothing."""
    monkeypatch.chdir(tmp_path)
    sampled, pdf, theta = CASES[name].negative
    chi2 = chi2_test(sampled, pdf, theta, CASES[name].negative_phi)
    assert not chi2.run(significance_level=ALPHA, test_count=CHI2_TEST_COUNT, quiet=True)


# ----------------------------------------------------------------------------
#  3. Sample weight x pdf = eval; eval_pdf = (eval, pdf)
# ----------------------------------------------------------------------------

def random_viewers(rng, n):
    """Mostly upper-hemisphere viewers (1/8 near grazing, 80–89.99°), 1/8 below."""
    wi = random_hemisphere(rng, n)
    m = n // 8
    t = np.radians(rng.uniform(80.0, 89.99, m))
    p = rng.uniform(0, 2 * np.pi, m)
    wi[:m] = np.column_stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
    wi[m:2 * m, 2] *= -1
    return f32(wi)


@pytest.mark.parametrize("config", from_entries(lambda name, e: each_mode(e.consistency)))
def test_sample_weight_matches_eval_over_pdf(config, rng):
    n = 100_000
    wi = random_viewers(rng, n)
    below = wi[:, 2] <= 0
    bsdf = mi.load_dict(config)
    ctx = mi.BSDFContext()
    si = surface(wi)
    bs, weight = bsdf.sample(ctx, si, floats(rng.random(n)),
                             points(rng.random(n), rng.random(n)))
    value, pdf = bsdf.eval_pdf(ctx, si, bs.wo)
    alone = (bsdf.eval(ctx, si, bs.wo), bsdf.pdf(ctx, si, bs.wo))     # what eval_pdf joins
    dr.eval(weight, value, pdf, bs.wo, bs.pdf, *alone)
    weight, value = np.array(weight).T, np.array(value).T
    bs_pdf, pdf, wo = np.array(bs.pdf), np.array(pdf), np.array(bs.wo).T
    for a in (weight, value, bs_pdf, pdf):
        assert finite(a) and (a >= 0).all()
    np.testing.assert_allclose(np.array(alone[0]).T, value, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(np.array(alone[1]), pdf, rtol=1e-6, atol=1e-9)
    ok = bs_pdf > 0
    # A real sampler: a usable direction for a good part of the upper viewers
    # (toon's blinn cone over the whole hemisphere reflects ~2/3 below).
    assert np.count_nonzero(ok & ~below) > 0.3 * np.count_nonzero(~below)
    assert not np.any(ok & below) and np.all(weight[~ok] == 0) and np.all(wo[ok, 2] > 0)
    np.testing.assert_allclose(weight[ok] * bs_pdf[ok, None], value[ok], rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(pdf[ok], bs_pdf[ok], rtol=1e-4)
    failed_up = ~ok & ~below              # only where there is no density
    assert np.all((wo[failed_up, 2] <= 0) | (pdf[failed_up] == 0))


# ----------------------------------------------------------------------------
#  4. Reciprocity
# ----------------------------------------------------------------------------

RECIPROCAL = from_entries(lambda name, e: [pytest.param(c, id=config_id(c))
                                            for c in e.interior + e.reciprocity
                                            if PLUGINS[name].reciprocal])


@pytest.mark.parametrize("config", RECIPROCAL)
def test_reciprocity(config, rng):
    """hdr: eval(w_i, w_o)/cos θ_o = eval(w_o, w_i)/cos θ_i (the BRDF is symmetric)."""
    wi, wo = mirror_pairs(rng, 4096, CASES[config["type"]].lobe_width, min_cos=0.01)
    bsdf = mi.load_dict(config)
    forward = eval_and_pdf(bsdf, wi, wo)[0] / wo[:, 2:3]
    backward = eval_and_pdf(bsdf, wo, wi)[0] / wi[:, 2:3]
    rtol = 1e-3 if config.get("energy_compensation") else 1e-4
    np.testing.assert_allclose(forward, backward, rtol=rtol, atol=1e-6 * forward.max())
    assert forward.max() > 0.1


# ----------------------------------------------------------------------------
#  5. White furnace
# ----------------------------------------------------------------------------

FURNACE = from_entries(lambda name, e: [pytest.param(f, id=f"{name}-{f.label}")
                                         for f in e.furnace])


@pytest.mark.parametrize("case", FURNACE)
def test_white_furnace(case):
    """E(θ_i) = ∫ eval dω_o by uniform-hemisphere quadrature (not the plugin's
    sampler): within [lo, hi] at every listed angle (1 ± 1 % where energy is
    preserved)."""
    bsdf = mi.load_dict({**case.config, "mode": "hdr"})
    values = {(th, ph): float(albedo(bsdf, th, ph, case.points).max())
              for th in case.thetas for ph in case.phis}
    text = ", ".join(f"{th}°/{ph}°: {e:.4f}" for (th, ph), e in values.items())
    assert max(values.values()) <= case.hi + case.tol, f"albedo above {case.hi}: {text}"
    assert min(values.values()) >= case.lo - case.tol, f"albedo below {case.lo}: {text}"


@pytest.mark.parametrize("name", PLUGINS)
def test_scanline_furnace_is_bounded(name):
    """The scan-line lobes are clamped to [0, 1] per value, so a surface cannot
    reflect more than 2π per lobe (the lecture's formulas carry no 1/π)."""
    bsdf = mi.load_dict({"type": name, "mode": "scanline"})
    lobes = bsdf.component_count()
    for th in (0, 45, 85):
        e = albedo(bsdf, th, n=256)
        assert finite(e) and (e >= 0).all() and e.max() <= 2 * np.pi * lobes + 1e-3


# ----------------------------------------------------------------------------
#  6. The numerical extremes
# ----------------------------------------------------------------------------

GRAZING = (1e-6, 1e-10, 1e-12, 1e-19, 1e-30, 0.0)


def extreme_viewers():
    """The normal, oblique and grazing directions (cos θ in GRAZING) along t, b
    and diagonally."""
    dirs = [np.array([0.0, 0.0, 1.0]), np.array([0.6, 0.0, 0.8]),
            np.array([0.0, math.sqrt(0.75), 0.5]), np.array([math.sqrt(1 - 0.81), 0.0, 0.9])]
    for c in GRAZING:
        s = math.sqrt(1 - c * c)
        dirs += [np.array([s, 0.0, c]), np.array([0.0, -s, c]),
                 np.array([s / math.sqrt(2), s / math.sqrt(2), c])]
    return np.array(dirs)


def extreme_directions():
    """(wi, wo): each extreme direction against every other, itself, its mirror
    (the highlight), its opposite, and mirrored below the surface."""
    wi, wo = [], []
    for a in extreme_viewers():
        for b in extreme_viewers():
            wi.append(a)
            wo.append(b)
        wi += [a, a, a]
        wo += [a * [-1, -1, 1], -a, a * [1, 1, -1]]
    return np.array(wi), np.array(wo)


def differentiable_keys(params) -> list[str]:
    return [k for k in params.keys()
            if not (params.flags(k) & mi.ParamFlags.NonDifferentiable)
            and dr.is_array_v(params[k]) and dr.is_float_v(params[k])]


def assert_finite_everywhere(config: dict) -> None:
    """Values, pdfs, sample weights and their gradients (every differentiable
    parameter enabled, through traverse) are finite and non-negative at the
    extreme directions and sample numbers."""
    bsdf = mi.load_dict(config)
    params = mi.traverse(bsdf)
    keys = differentiable_keys(params)
    for key in keys:
        dr.enable_grad(params[key])
    params.update()
    wi, wo = extreme_directions()
    ctx = mi.BSDFContext()
    value, pdf = bsdf.eval_pdf(ctx, surface(wi), vec(wo))
    viewers = extreme_viewers()
    u = np.array([0.0, 1e-7, 0.5, 1 - 1e-7, 1 - 2.0**-24])
    s1, s2x, s2y = (a.ravel() for a in np.meshgrid(u, u, u))
    si = surface(np.repeat(viewers, len(s1), axis=0))
    n = len(viewers)
    bs, weight = bsdf.sample(ctx, si, floats(np.tile(s1, n)),
                             points(np.tile(s2x, n), np.tile(s2y, n)))
    outputs = {"eval": value, "pdf": pdf, "weight": weight, "sample pdf": bs.pdf}
    dr.eval(*outputs.values(), bs.wo)          # one launch, then plain copies
    for what, a in outputs.items():
        x = np.array(dr.detach(a))
        assert finite(x), f"{config_id(config)}: {what} not finite"
        assert (x >= 0).all(), f"{config_id(config)}: {what} negative"
    assert finite(dr.detach(bs.wo))
    dr.backward(dr.sum(dr.sum(value)) + dr.sum(pdf) + dr.sum(dr.sum(weight)) + dr.sum(bs.pdf))
    grads = [dr.grad(params[key]) for key in keys]
    dr.eval(*grads)
    for key, grad in zip(keys, grads):
        assert finite(grad), f"{config_id(config)}: gradient of {key} not finite"


@pytest.mark.parametrize("config", from_entries(lambda name, e: each_mode(e.extremes)))
def test_extremes(config):
    assert_finite_everywhere(config)


def option_variants(cls) -> list[dict]:
    """Every combination of a plugin's choice options (not mode or sampling),
    each in both modes and, for a compensable plugin, compensated."""
    choices = [o for o in cls.OPTIONS if o.choices]
    combos = [dict(zip((o.name for o in choices), values))
              for values in itertools.product(*(o.choices for o in choices))]
    modes = [{"mode": m} for m in MODES]
    if cls.compensable:
        modes.append({"mode": "hdr", "energy_compensation": True})
    return [{"type": cls.name, **c, **m} for c in combos for m in modes]


@pytest.mark.parametrize("name, p, end", [
    pytest.param(name, p, end, id=f"{name}-{p.name}-{end}")
    for name, cls in PLUGINS.items() for p in cls.PARAMS if not p.optional
    for end in ("lo", "hi")])
def test_declared_bounds(name, p, end):
    """Every parameter at each end of the range its plugin states (an open end:
    the largest float32), the others at their defaults, for every option
    combination and mode: what a plugin accepts it evaluates finitely. The
    range is the one a loaded instance checks (e.g. Blinn's alpha <= 1);
    combinations the plugin refuses (EON's table, Blinn's D with alpha_u) are
    left out: refused for what they combine, not for the value's range."""
    def refused(config) -> str | None:
        try:
            return mi.load_dict(config) and None
        except Exception as error:              # (Mitsuba wraps the ParameterError)
            line = error_line(error)
            assert "is invalid; valid:" in line, line
            return line
    tried = 0
    for config in option_variants(PLUGINS[name]):
        if refused(config):
            continue
        declared = mi.load_dict(config).state.params.get(p.name, p)   # (read only if given)
        lo, hi = declared.far()
        config = {**config, p.name: lo if end == "lo" else hi}
        why = refused(config)
        if why is not None:
            assert declared.valid() not in why, why       # a combination, not the range
            continue
        assert_finite_everywhere(config)
        tried += 1
    assert tried


# ----------------------------------------------------------------------------
#  7. Gradients against finite differences
# ----------------------------------------------------------------------------

def traverse_key(p) -> str:
    return p.name if p.kind == "float" else p.name + ".value"


def gradient_cases(name: str, entry) -> list:
    """Every parameter an interior configuration gives as a number (a given
    parameter is always read), at that number and, for colours and weights,
    at its bounds."""
    cases = []
    for config in entry.interior:
        for mode in modes_of(config):
            base = in_mode(config if mode == "hdr" else wants_scanline(config), mode)
            for p in PLUGINS[name].PARAMS:
                if not isinstance(base.get(p.name), float):
                    continue                    # not given, or a texture: not a single number
                points = [("interior", base[p.name])]
                if p.role in ("colour", "weight"):
                    points += [("at 0" if p.lo == 0 else "at lo", p.lo), ("at hi", p.probe_hi())]
                for where, x in points:
                    cases.append(pytest.param(base, p, where, x,
                                              id=f"{config_id(base)}-{p.name}-{where}"))
    return cases


@pytest.mark.parametrize("config, p, where, x", from_entries(gradient_cases, nargs=4))
def test_gradient_matches_finite_differences(config, p, where, x, rng):
    """AD of Σ eval with respect to one parameter (enabled and updated through
    traverse, as an optimiser does) = a finite difference of fresh loads:
    central inside the range, one-sided at a bound (where a lobe whose colour
    or weight is 0 must still get its gradient)."""
    wi, wo = mirror_pairs(rng, 1024, CASES[config["type"]].lobe_width, min_cos=0.1)
    config = {**config, p.name: x}
    bsdf = mi.load_dict(config)
    params = mi.traverse(bsdf)
    key = traverse_key(p)
    dr.enable_grad(params[key])
    params.update()
    dr.backward(dr.sum(dr.sum(bsdf.eval(mi.BSDFContext(), surface(wi), vec(wo)))))
    grad = float(dr.sum(dr.ravel(dr.grad(params[key])))[0])
    h = 1e-3 * max(1.0, abs(x))
    side = {"at 0": "forward", "at lo": "forward", "at hi": "backward"}.get(where, "central")
    fd = finite_difference(
        lambda v: float(eval_and_pdf(mi.load_dict({**config, p.name: v}), wi, wo)[0].sum()),
        x, h, side)
    assert abs(fd) > 1e-3, f"the loss does not depend on {p.name} here (fd = {fd})"
    np.testing.assert_allclose(grad, fd, rtol=2e-2)


@pytest.mark.parametrize("config", from_entries(lambda name, e: [
    pytest.param(e.interior[0], id=config_id(e.interior[0]))]))
def test_sample_weight_gradient_is_that_of_eval_over_pdf(config, rng):
    """A path tracer differentiated as a whole (Mitsuba's ``path``) takes the
    derivatives of the sample weights: at each sampled direction, held fixed
    as the integrators hold it, the weight's gradient with respect to every
    parameter is that of eval / pdf there (whose gradient the test above
    checks), under a different weight per lane. Each model's first interior
    configuration (the compensated ones take the same code path, at 2-10 s of
    compiling each)."""
    bsdf = mi.load_dict(config)
    params = mi.traverse(bsdf)
    keys = differentiable_keys(params)
    for key in keys:
        dr.enable_grad(params[key])
    params.update()
    n = 4096
    wi = random_hemisphere(rng, n, 0.05)
    si, ctx, lanes = surface(wi), mi.BSDFContext(), floats(rng.uniform(0.5, 1.5, n))
    bs, weight = bsdf.sample(ctx, si, floats(rng.random(n)), points(rng.random(n), rng.random(n)))
    assert np.mean(np.array(dr.detach(bs.pdf)) > 0) > 0.5

    def gradients(per_lane) -> list[np.ndarray]:
        for k in keys:
            dr.clear_grad(params[k])
        dr.backward(dr.sum((per_lane[0] + per_lane[1] + per_lane[2]) * lanes))
        return [np.array(dr.grad(params[k]), dtype=np.float64).ravel() for k in keys]

    of_weight = gradients(weight)
    value, pdf = bsdf.eval_pdf(ctx, si, dr.detach(bs.wo))
    of_ratio = gradients(dr.select(dr.detach(bs.pdf) > 0, value / pdf, 0.0))
    for key, a, b in zip(keys, of_weight, of_ratio):
        assert np.abs(b).max() > 0, key
        np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-6 * np.abs(b).max(), err_msg=key)


# ----------------------------------------------------------------------------
#  8. Bad values and options: one line, at load time and at update()
# ----------------------------------------------------------------------------

def plain_params():
    """(plugin name, Param, a configuration reading it as a plain value: the
    parameter given at its default) for every declared parameter."""
    for name, cls in PLUGINS.items():
        for p in cls.PARAMS:
            yield name, p, {"type": name, p.name: p.default}


def bad_values(p) -> list[tuple[str, object, float]]:
    """(label, value given, value reported) that lie outside p's range."""
    out = []
    if p.lo is not None:
        bad = p.lo - 0.5 * max(1.0, abs(p.lo))
        out.append(("below", bad, bad))
    if p.hi is not None:
        bad = p.hi + 0.5 * max(1.0, abs(p.hi))
        out.append(("above", bad, bad))
    out.append(("inf", math.inf, math.inf))          # never valid, whatever the range
    out.append(("nan", math.nan, math.nan))
    if p.kind != "float" and p.lo is not None:
        bad = p.lo - 0.5 * max(1.0, abs(p.lo))
        ok = p.lo if p.hi is None else 0.5 * (p.lo + p.hi)
        out.append(("texture", {"type": "checkerboard", "color0": ok, "color1": bad}, bad))
    return out


def bad_value_cases():
    return [pytest.param(config, p, value, shown, id=f"{name}-{p.name}-{label}")
            for name, p, config in plain_params() for label, value, shown in bad_values(p)]


@pytest.mark.parametrize("config, p, value, shown", bad_value_cases())
def test_bad_value_is_refused_at_load(config, p, value, shown):
    assert_refused({**config, p.name: value}, p.name, repr(shown), p.valid())


@pytest.mark.parametrize("config, p, value, shown",
                         [c for c in bad_value_cases() if not isinstance(c.values[2], dict)])
def test_bad_value_is_refused_at_update(config, p, value, shown):
    """The same message at params.update(): negative colours or an
    exponent of -1 would render negative pixels or a silently dropped lobe."""
    bsdf = mi.load_dict(config)
    params = mi.traverse(bsdf)
    params[traverse_key(p)] = value
    with pytest.raises(ParameterError) as info:
        params.update()
    shown = float(np.float32(shown)) if math.isfinite(shown) else shown
    last = error_line(info.value)                         # the load-time message
    assert f"{config['type']}: parameter '{p.name}' = {shown!r} is invalid" in last, last
    assert p.valid() in last, last


OPTION_CASES = [pytest.param(name, o, id=f"{name}-{o.name}")
                for name, cls in PLUGINS.items() for o in cls.all_options()]


@pytest.mark.parametrize("name, option", OPTION_CASES)
def test_bad_option_is_refused(name, option):
    bad = "yes" if isinstance(option.default, bool) else "nonsense"
    assert_refused({"type": name, option.name: bad}, option.name, repr(bad), option.valid())


@pytest.mark.parametrize("name", [n for n, c in PLUGINS.items() if c.compensable])
def test_energy_compensation_belongs_to_hdr(name):
    assert_refused({"type": name, "mode": "scanline", "energy_compensation": True},
                   "energy_compensation", "True", 'mode="hdr"')


def edge_cases():
    """Every parameter at the ends of its range (colours also far above 1: the
    scanline clamp limits them, as in the lecture)."""
    cases = []
    for name, p, config in plain_params():
        values = {p.lo if p.lo is not None else -1e3, p.probe_hi()}
        if p.role == "colour":
            values.add(3.0)
        cases += [pytest.param({**config, p.name: v}, id=f"{name}-{p.name}={v:g}")
                  for v in sorted(values)]
    return cases


@pytest.mark.parametrize("config", edge_cases())
def test_edge_values_are_accepted(config, rng):
    bsdf = mi.load_dict(config)
    wi, wo = random_hemisphere(rng, 256), random_hemisphere(rng, 256)
    value, pdf = eval_and_pdf(bsdf, wi, wo)
    assert finite(value) and finite(pdf) and (value >= 0).all() and (pdf >= 0).all()


@pytest.mark.parametrize("name", PLUGINS)
def test_unknown_parameter_is_refused(name):
    with pytest.raises(Exception, match="unreferenced property.*\n.*colour"):
        mi.load_dict({"type": name, "colour": 0.3})


# ----------------------------------------------------------------------------
#  9. traverse, update, and which lobes are traced
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("config", from_entries(lambda name, e: [
    pytest.param(c, id=config_id(c)) for c in [{"type": name}] + e.interior]))
def test_traverse_exposes_every_parameter_read(config):
    bsdf = mi.load_dict(config)
    params = mi.traverse(bsdf)
    names = {k.split(".")[0] for k in params.keys()}
    assert names == set(bsdf.state.params)
    for key in params.keys():
        if key.endswith(".to_uv"):          # a bitmap's own transform
            continue
        assert not (params.flags(key) & mi.ParamFlags.NonDifferentiable), key


@pytest.mark.parametrize("config", from_entries(lambda name, e: [
    pytest.param(c, id=config_id(c)) for c in e.interior]))
def test_update_matches_a_fresh_load(config, rng):
    """Every parameter changed through traverse + update() gives the BSDF a
    fresh load with those values gives."""
    wi, wo = mirror_pairs(rng, 1024, CASES[config["type"]].lobe_width, min_cos=0.05)
    bsdf = mi.load_dict(config)
    params = mi.traverse(bsdf)
    changed = {}
    for p in bsdf.state.params.values():
        if isinstance(config.get(p.name), float):
            lo = p.lo if p.lo is not None else -1.0
            hi = p.probe_hi()
            changed[p.name] = lo + 0.37 * (hi - lo)       # another valid value
            params[traverse_key(p)] = changed[p.name]
    params.update()
    assert changed
    fresh = mi.load_dict({**config, **changed})
    for a, b in zip(eval_and_pdf(bsdf, wi, wo), eval_and_pdf(fresh, wi, wo)):
        np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-7)


def switches(name: str) -> list[tuple]:
    """(Param, value) of plugin ``name`` that switch a lobe off at load time:
    a colour at 0, a weight at either end (loaded: at run time)."""
    default = mi.load_dict({"type": name}).flags()
    read = mi.load_dict({"type": name}).state.params
    found = []
    for p in PLUGINS[name].PARAMS:
        if p.role not in ("colour", "weight") or p.name not in read:
            continue
        for value in sorted({0.0, p.probe_hi()} if p.role == "weight" else {0.0}):
            if mi.load_dict({"type": name, p.name: value}).flags() != default:
                found.append((p, value))
    return found


@pytest.mark.parametrize("name", PLUGINS)
def test_a_lobe_is_dropped_only_when_it_cannot_matter(name):
    """Model only what a scene requires — but a parameter that is grad-enabled
    or changed through update() keeps its lobe traced. Every model has a
    parameter that switches a lobe off."""
    default = mi.load_dict({"type": name}).flags()
    found = switches(name)
    assert found, f"{name}: no colour or weight switches a lobe off"
    for p, value in found:
        where = f"{name}.{p.name} = {value}"
        key = traverse_key(p)
        # grad-enabled: the lobe comes back, so an optimiser can leave the bound
        bsdf = mi.load_dict({"type": name, p.name: value})
        params = mi.traverse(bsdf)
        dr.enable_grad(params[key])
        params.update()
        assert bsdf.flags() == default, f"{where}, grad-enabled: lobe still dropped"
        # changed through update() to the switching value: the lobe stays
        bsdf = mi.load_dict({"type": name})
        params = mi.traverse(bsdf)
        params[key] = value
        params.update()
        assert bsdf.flags() == default, f"{where} through update(): lobe dropped"
        # a texture (not a constant) keeps its lobe
        if p.kind != "float":
            tex = {"type": "checkerboard", "color0": value, "color1": value}
            assert mi.load_dict({"type": name, p.name: tex}).flags() == default, \
                f"{where} as a texture: lobe dropped"


@pytest.mark.parametrize("name", [n for n, c in PLUGINS.items()
                                  if any(p.kind == "float" for p in c.PARAMS)])
def test_a_number_folded_at_0_or_1_unfolds_when_it_changes(name, rng):
    """A plain number at 0 or 1 (k = 0, f0 = 1, ...) is traced as that number
    (BRDF.switch); changed through update(), the BSDF equals a fresh load with
    the new value, and what its calls trace changes with it (trace_key: a
    frozen render records again instead of replaying the folded number)."""
    wi, wo = mirror_pairs(rng, 1024, CASES[name].lobe_width, min_cos=0.05)
    cases = [(p, v) for p in PLUGINS[name].PARAMS if p.kind == "float" for v in (0.0, 1.0)
             if (p.lo is None or p.lo <= v) and (p.hi is None or v <= p.hi)]
    assert cases
    for p, value in cases:
        bsdf = mi.load_dict({"type": name, p.name: value})
        folded = bsdf.trace_key()
        other = 0.37 if value == 0.0 else 0.63
        params = mi.traverse(bsdf)
        params[traverse_key(p)] = other
        params.update()
        assert bsdf.trace_key() != folded, f"{name}.{p.name} = {value}"
        fresh = mi.load_dict({"type": name, p.name: other})
        for a, b in zip(eval_and_pdf(bsdf, wi, wo), eval_and_pdf(fresh, wi, wo)):
            np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-7,
                                       err_msg=f"{name}.{p.name}: {value} -> {other}")


# ----------------------------------------------------------------------------
#  10. Every property form, every direct call
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("name", PLUGINS)
def test_every_property_form(name, tmp_path):
    """Each parameter as <float>, <integer>, <rgb>, <spectrum> (a constant,
    wavelength:value pairs, a file), a bitmap and a reference by id: a colour
    or scalar holds what Mitsuba's diffuse holds for the same element; a
    plain number takes numbers only; wrong types and spectrum values out of
    range are refused with one line (support.property_form_failures)."""
    failures = property_form_failures(name, tmp_path)
    assert not failures, "\n".join(failures)


@pytest.mark.parametrize("name", PLUGINS)
def test_direct_calls_as_mitsuba_takes_them(name):
    """Lists and tuples for wo and sample2 (as Mitsuba's bindings take them
    for its own plugins); has_attribute and eval_attribute* as for diffuse."""
    failures = direct_call_failures({"type": name})
    assert not failures, "\n".join(failures)


# ----------------------------------------------------------------------------
#  11. Frozen evaluation
# ----------------------------------------------------------------------------

def compensated(name, e) -> list:
    seen = []
    for c in e.consistency + e.extremes:
        if c.get("energy_compensation") and c not in seen:
            seen.append(c)
    return [pytest.param(c, id=config_id(c)) for c in seen]


FROZEN = from_entries(compensated)


def interaction(wi) -> mi.SurfaceInteraction3f:
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = wi
    si.uv = mi.Point2f(0.5, 0.5)
    return si


@dr.freeze(state_fn=lambda bsdf, wi, wo: str(bsdf))
def frozen_eval_pdf(bsdf, wi, wo):
    """One frozen function for every case (a frozen function freed while
    another records aborts); the plugin's description, with its options, is
    part of the key (its Python-side choices are not traversed)."""
    return bsdf.eval_pdf(mi.BSDFContext(), interaction(wi), wo)


@pytest.mark.parametrize("config", FROZEN)
def test_frozen_eval_matches_the_plain_call(config, rng):
    """eval_pdf inside dr.freeze (recorded at the first call, replayed at the
    second with other directions) equals the plain call: arrays made before
    the recording (the compensation tables) reach the frozen function through
    the plugin's traversal, as its inputs."""
    gc.collect()                  # the earlier tests' objects, not during a recording
    bsdf = mi.load_dict(config)
    for _ in range(2):
        wi, wo = vec(random_hemisphere(rng, 512)), vec(random_hemisphere(rng, 512))
        value, pdf = frozen_eval_pdf(bsdf, wi, wo)
        expected, expected_pdf = bsdf.eval_pdf(mi.BSDFContext(), interaction(wi), wo)
        np.testing.assert_allclose(np.array(value), np.array(expected), rtol=1e-5, atol=1e-7)
        np.testing.assert_allclose(np.array(pdf), np.array(expected_pdf), rtol=1e-5, atol=1e-7)
