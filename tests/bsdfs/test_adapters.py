"""Every plugin inside Mitsuba's adapters ``twosided``, ``blendbsdf`` and
``normalmap``, by direct BSDF calls (``bumpmap`` and ``mask`` are rendered
frozen in tests/render/test_frozen_adapters.py).

An adapter hands the plugin what the plugin never gets from a plain surface:
viewers mirrored to the back side, a component index, a remapped ``sample1``,
directions in a perturbed frame, masks. Each test builds what the adapter's
definition says it must return from the plugin called directly (the
directions transformed in NumPy) and compares; it runs for every registered
plugin at its configuration of :func:`support.plugin_configs`, paired where
an adapter holds two BSDFs with the next plugin of the registry
(:func:`support.neighbour`) or with another configuration of itself
(:func:`support.moved`).
"""
from __future__ import annotations

import functools
import operator

import numpy as np
import pytest

import drjit as dr
import mitsuba as mi

import mi_brdfs
from support import (BLEND_CHI2_THETA, BLEND_WEIGHT, CHI2_ALPHA, active_variant,
                     assert_weight_is_value_over_pdf, blend, blend_chi2_configs, chi2_test,
                     chi2_test_count, eval_and_pdf, floats, interaction, mirrored, moved,
                     neighbour, numbers, outputs, plugin_configs, points, random_hemisphere,
                     sampled, surface, twosided, unit, vec)

NAMES = [cls.name for cls in mi_brdfs.PLUGINS]
F = mi.BSDFFlags
SIDES = int(F.FrontSide) | int(F.BackSide)


@functools.cache
def configs() -> dict[str, dict]:
    return plugin_configs()


def lobes(bsdf) -> list[int]:
    """The flags of each component, as integers."""
    return [int(bsdf.flags(i)) for i in range(bsdf.component_count())]


def both_sides(rng, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(wi, wo): viewers and lights on both sides of the surface, half of each
    below it, independently (half of the pairs on opposite sides)."""
    wi, wo = random_hemisphere(rng, n, 0.02), random_hemisphere(rng, n, 0.02)
    wi[::2] = mirrored(wi[::2])
    wo[n // 4: 3 * n // 4] = mirrored(wo[n // 4: 3 * n // 4])
    return wi, wo


def per_side(up: np.ndarray, front: np.ndarray, back: np.ndarray) -> np.ndarray:
    """The front's value where the viewer is above the surface, else the back's."""
    return np.where(up.reshape(-1, *([1] * (front.ndim - 1))), front, back)


# ----------------------------------------------------------------------------
#  twosided
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("name", NAMES)
def test_twosided_lists_the_lobes_of_each_side(name):
    """The front's components flagged FrontSide, then the back's flagged
    BackSide (one nested BSDF: its components on both sides); flags() is
    their union. The plugin's own lobes are front-side reflections."""
    front_config, back_config = configs()[name], configs()[neighbour(name)]
    front, back = mi.load_dict(front_config), mi.load_dict(back_config)
    kinds = [[f & ~SIDES for f in lobes(b)] for b in (front, back)]
    assert all(f & int(F.FrontSide) and not f & int(F.BackSide) and f & int(F.Reflection)
               and not f & int(F.Transmission) for f in lobes(front))
    cases = [(twosided(front_config, back_config), kinds[0], kinds[1]),
             (twosided(front_config), kinds[0], kinds[0])]
    for config, front_kinds, back_kinds in cases:
        adapter = mi.load_dict(config)
        expected = ([k | int(F.FrontSide) for k in front_kinds]
                    + [k | int(F.BackSide) for k in back_kinds])
        assert lobes(adapter) == expected, config
        assert int(adapter.flags()) == functools.reduce(operator.or_, expected)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("nested", ["one", "two"])
def test_twosided_evaluates_each_side(name, nested, rng):
    """eval and pdf above the surface are the front's; below, the back's at
    the mirrored directions (one nested BSDF: its own, mirrored). A light on
    the other side of the surface than the viewer gets nothing."""
    config = configs()[name]
    back_config = config if nested == "one" else moved(config)
    adapter = mi.load_dict(twosided(config) if nested == "one" else twosided(config, back_config))
    front, back = mi.load_dict(config), mi.load_dict(back_config)
    wi, wo = both_sides(rng, 4096)
    up, same_side = wi[:, 2] > 0, wi[:, 2] * wo[:, 2] > 0
    value, pdf = eval_and_pdf(adapter, wi, wo)
    front_value, front_pdf = eval_and_pdf(front, wi, wo)
    back_value, back_pdf = eval_and_pdf(back, mirrored(wi), mirrored(wo))
    np.testing.assert_allclose(value, per_side(up, front_value, back_value), rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(pdf, per_side(up, front_pdf, back_pdf), rtol=1e-6, atol=1e-8)
    assert not value[~same_side].any() and not pdf[~same_side].any()
    for side in (up, ~up):              # each side reflects
        assert (value[side & same_side].max(axis=1) > 0).mean() > 0.5
    if nested == "two":                 # and the back is the back's BSDF, not the front's
        mirrored_front = eval_and_pdf(front, mirrored(wi), mirrored(wo))[0]
        assert not np.allclose(value[~up & same_side], mirrored_front[~up & same_side],
                               rtol=1e-3, atol=0)


@pytest.mark.parametrize("name", NAMES)
def test_twosided_samples_each_side(name, rng):
    """sample() above the surface is the front's; below, the back's for the
    mirrored viewer, its direction mirrored back (the same random numbers);
    and on both sides weight · pdf = eval, pdf() = the sample's pdf."""
    config, back_config = configs()[name], moved(configs()[name])
    adapter = mi.load_dict(twosided(config, back_config))
    n = 8192
    wi = random_hemisphere(rng, n, 0.02)
    wi[::2] = mirrored(wi[::2])
    up = wi[:, 2] > 0
    s = sampled(adapter, wi, np.random.default_rng(7))
    assert_weight_is_value_over_pdf(s, f"twosided({name})")
    held = s["pdf"] > 0
    assert np.all(np.sign(s["wo"][held, 2]) == np.sign(wi[held, 2]))
    for side in (up, ~up):
        assert held[side].mean() > 0.3
    front = sampled(mi.load_dict(config), wi, np.random.default_rng(7))
    back = sampled(mi.load_dict(back_config), mirrored(wi), np.random.default_rng(7))
    np.testing.assert_allclose(s["wo"][held], per_side(up, front["wo"], mirrored(back["wo"]))[held],
                               atol=1e-6)
    for key in ("pdf", "weight"):
        np.testing.assert_allclose(s[key], per_side(up, front[key], back[key]),
                                   rtol=1e-6, atol=1e-8)


def viewers(rng, n: int = 256) -> tuple[np.ndarray, np.ndarray]:
    """Viewers on both sides (every other one below), and which are above."""
    wi = random_hemisphere(rng, n, 0.02)
    wi[::2] = mirrored(wi[::2])
    return wi, wi[:, 2] > 0


@pytest.mark.parametrize("name", NAMES)
def test_twosided_diffuse_reflectance_is_each_side(name, rng):
    """eval_diffuse_reflectance: the front's above the surface, the back's
    (for the mirrored viewer) below; the two differ."""
    config, back_config = configs()[name], moved(configs()[name])
    adapter = mi.load_dict(twosided(config, back_config))
    front, back = mi.load_dict(config), mi.load_dict(back_config)
    wi, up = viewers(rng)

    def reflectance(bsdf, w):
        return np.array(bsdf.eval_diffuse_reflectance(surface(w)), dtype=np.float64).T

    ours = reflectance(adapter, wi)
    front_value, back_value = reflectance(front, wi), reflectance(back, mirrored(wi))
    np.testing.assert_allclose(ours, per_side(up, front_value, back_value), rtol=1e-6, atol=1e-8)
    assert ours[up].max() > 0 and ours[~up].max() > 0
    assert not np.allclose(front_value, back_value, rtol=1e-3, atol=0)


def test_twosided_diffuse_reflectance_of_lambert(rng):
    """The closed form: a Lambert side's diffuse reflectance is its colour
    (0.1 in front, 0.9 behind, the values of Mitsuba's own twosided tests)."""
    adapter = mi.load_dict(twosided({"type": "lambert", "reflectance": 0.1},
                                    {"type": "lambert", "reflectance": 0.9}))
    wi, up = viewers(rng)
    value = np.array(adapter.eval_diffuse_reflectance(surface(wi)), dtype=np.float64).T
    np.testing.assert_allclose(value, np.where(up, 0.1, 0.9)[:, None] * np.ones(3), rtol=1e-6)


@pytest.mark.parametrize("name", NAMES)
def test_twosided_attributes_are_each_side(name, rng):
    """Every parameter is an attribute through twosided, holding the front's
    value for viewers above the surface and the back's below; an unknown
    name is none."""
    config, back_config = configs()[name], moved(configs()[name])
    adapter = mi.load_dict(twosided(config, back_config))
    wi, up = viewers(rng)
    si = surface(wi)
    given = numbers(config)
    assert given
    for key, value in given.items():
        assert bool(np.array(adapter.has_attribute(key)).ravel()[0]), key
        expected = np.where(up, value, back_config[key])
        ours = np.array(adapter.eval_attribute_1(key, si), dtype=np.float64).ravel()
        np.testing.assert_allclose(np.broadcast_to(ours, expected.shape), expected, rtol=1e-6,
                                   err_msg=key)
    assert not bool(np.array(adapter.has_attribute("nonsense")).ravel()[0])


# ----------------------------------------------------------------------------
#  blendbsdf
# ----------------------------------------------------------------------------

def blend_of(name: str):
    """(blend, first, second): the plugin blended with the next one of the registry."""
    first, second = configs()[name], configs()[neighbour(name)]
    return mi.load_dict(blend(first, second)), mi.load_dict(first), mi.load_dict(second)


def component(i: int) -> mi.BSDFContext:
    ctx = mi.BSDFContext()
    ctx.component = i
    return ctx


@pytest.mark.parametrize("name", NAMES)
def test_blend_lists_both_bsdfs_lobes(name):
    mixture, first, second = blend_of(name)
    assert lobes(mixture) == lobes(first) + lobes(second)
    assert int(mixture.flags()) == int(first.flags()) | int(second.flags())


@pytest.mark.parametrize("name", NAMES)
def test_blend_evaluates_the_mixture(name, rng):
    """eval and pdf are (1 - w) · first + w · second, w = 0.2."""
    mixture, first, second = blend_of(name)
    wi, wo = random_hemisphere(rng, 4096), random_hemisphere(rng, 4096)
    value, pdf = eval_and_pdf(mixture, wi, wo)
    (v1, p1), (v2, p2) = eval_and_pdf(first, wi, wo), eval_and_pdf(second, wi, wo)
    w = BLEND_WEIGHT
    np.testing.assert_allclose(value, (1 - w) * v1 + w * v2, rtol=1e-5, atol=1e-8)
    np.testing.assert_allclose(pdf, (1 - w) * p1 + w * p2, rtol=1e-5, atol=1e-8)
    assert (v1.max(axis=1) > 0).mean() > 0.5 and (v2.max(axis=1) > 0).mean() > 0.5


@pytest.mark.parametrize("name", NAMES)
def test_blend_evaluates_and_samples_one_component(name, rng):
    """With ctx.component = i: eval is the scaled eval of the nested BSDF's
    lobe i (the first's lobes, then the second's), pdf is that lobe's own pdf,
    sample() is its sample with the weight scaled; the lobes add up to the
    whole, in the blend and in each plugin."""
    mixture, first, second = blend_of(name)
    wi, wo = random_hemisphere(rng, 2048), random_hemisphere(rng, 2048)
    n_first = first.component_count()
    total = np.zeros((len(wi), 3))
    for i in range(mixture.component_count()):
        nested, j, scale = ((first, i, 1 - BLEND_WEIGHT) if i < n_first
                            else (second, i - n_first, BLEND_WEIGHT))
        value, pdf = eval_and_pdf(mixture, wi, wo, ctx=component(i))
        own_value, own_pdf = eval_and_pdf(nested, wi, wo, ctx=component(j))
        np.testing.assert_allclose(value, scale * own_value, rtol=1e-5, atol=1e-8,
                                   err_msg=f"component {i}")
        np.testing.assert_allclose(pdf, own_pdf, rtol=1e-5, atol=1e-8, err_msg=f"component {i}")
        assert own_value.max() > 0, f"component {i} of {nested} is black"
        total += value
        s = sampled(mixture, wi, np.random.default_rng(i), ctx=component(i))
        own = sampled(nested, wi, np.random.default_rng(i), ctx=component(j))
        held = own["pdf"] > 0
        assert held.mean() > 0.3
        np.testing.assert_allclose(s["wo"][held], own["wo"][held], atol=1e-6)
        np.testing.assert_allclose(s["pdf"], own["pdf"], rtol=1e-6, atol=1e-8)
        np.testing.assert_allclose(s["weight"], scale * own["weight"], rtol=1e-5, atol=1e-8)
    np.testing.assert_allclose(total, eval_and_pdf(mixture, wi, wo)[0], rtol=1e-5, atol=1e-8)


@pytest.mark.parametrize("name", NAMES)
def test_blend_sample_weight_is_eval_over_pdf(name, rng):
    """The blend's sample weight is its eval over its pdf (both BSDFs' lobes
    counted), wherever the sample falls."""
    mixture, _, _ = blend_of(name)
    s = sampled(mixture, random_hemisphere(rng, 20_000, 0.02), rng)
    assert_weight_is_value_over_pdf(s, f"blend({name}, {neighbour(name)})")


CHI2_TEST_COUNT = chi2_test_count()


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMES)
def test_blend_chi2(name, tmp_path, monkeypatch):
    """The blend of the plugin and a rough dielectric (α 0.5, which also
    transmits) samples its pdf: Mitsuba's χ² test, 10⁶ samples, one Šidák
    correction over every χ² test of the suite."""
    monkeypatch.chdir(tmp_path)          # a rejected test writes chi2_data.py
    config = blend_chi2_configs()[name]
    chi2 = chi2_test(config, config, BLEND_CHI2_THETA)
    assert chi2.run(significance_level=CHI2_ALPHA, test_count=CHI2_TEST_COUNT, quiet=True), \
        chi2.messages


# ----------------------------------------------------------------------------
#  normalmap
# ----------------------------------------------------------------------------
# What Mitsuba 3.9.1's normalmap does (its documentation and, measured here, its
# results): the map's colour c gives the normal n = 2c - 1 in the shading frame;
# with flip_invalid_normals (default) a normal that faces away from the viewer
# (cos θ_i · wi·n <= 0) is mirrored to (-n_x, -n_y, n_z) (Schüssler et al. 2017);
# the perturbed frame is n, s = the x axis made orthogonal to n, t = n × s; the
# nested BSDF sees wi and wo in that frame, and nothing where wo changes side;
# with use_shadowing_function (default) eval and the sample weight are multiplied
# by Estevez et al.'s shadowing term (Ray Tracing Gems, 2019), see `terminator`.

TILTED = unit(np.array([0.3, -0.2, 0.9]))
GRAZING = unit(np.array([1.0, 0.01, 0.01]))


def normalmap(nested: dict, normal, **options) -> dict:
    colour = (0.5 * np.asarray(normal) + 0.5).tolist()
    return {"type": "normalmap", "normalmap": {"type": "rgb", "value": colour}, "bsdf": nested,
            **options}


def perturbed_frame(normal, wi, flip: bool = True):
    """(s, t, n) per viewer, each (len(wi), 3): the frame the nested BSDF
    sees, in the shading frame's coordinates."""
    n = np.tile(unit(np.asarray(normal, dtype=np.float64)), (len(wi), 1))
    if flip:
        away = wi[:, 2] * np.sum(wi * n, axis=1) <= 0
        n[away, :2] *= -1
    s = np.array([1.0, 0.0, 0.0]) - n * n[:, :1]
    s /= np.linalg.norm(s, axis=1, keepdims=True)
    return s, np.cross(n, s), n


def to_frame(frame, v):
    s, t, n = frame
    return np.stack([np.sum(v * s, 1), np.sum(v * t, 1), np.sum(v * n, 1)], axis=1)


def from_frame(frame, v):
    s, t, n = frame
    return v[:, :1] * s + v[:, 1:2] * t + v[:, 2:] * n


def tan2(v):
    return (1.0 - v[:, 2] ** 2) / v[:, 2] ** 2


def terminator(n, wo):
    """Estevez et al.'s shadowing term for a normal n tilted from the
    geometric one: G = 2 / (1 + sqrt(1 + α² tan²θ_o)), α² = min(tan²θ_n / 8, 1)."""
    alpha2 = np.minimum(0.125 * tan2(n), 1.0)
    return 2.0 / (1.0 + np.sqrt(1.0 + alpha2 * tan2(wo)))


def framed_surface(wi):
    """An interaction whose shading frame is not the world's (the plugin must
    only see local directions)."""
    si = surface(wi)
    si.sh_frame = mi.Frame3f(dr.normalize(mi.Vector3f(1.0, 1.0, 1.0)))
    return si


def through_normalmap(name, normal, wi, wo, flip=True, shadowing=True):
    """(eval, pdf) of the plugin under a constant normal map, as NumPy; and
    the same computed from the plugin called directly in the perturbed frame."""
    config = configs()[name]
    adapter = mi.load_dict(normalmap(config, normal, flip_invalid_normals=flip,
                                     use_shadowing_function=shadowing))
    ctx, si = mi.BSDFContext(), framed_surface(wi)
    value, pdf = adapter.eval_pdf(ctx, si, vec(wo))
    ours = (np.array(value, dtype=np.float64).T, np.array(pdf, dtype=np.float64))
    frame = perturbed_frame(normal, wi, flip)
    local_wo = to_frame(frame, wo)
    value, pdf = eval_and_pdf(mi.load_dict(config), to_frame(frame, wi), local_wo)
    kept = local_wo[:, 2] * wo[:, 2] > 0
    scale = np.where(kept, terminator(frame[2], wo) if shadowing else 1.0, 0.0)
    return ours, (value * scale[:, None], pdf * kept)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("flip, shadowing", [(True, True), (False, True), (True, False)],
                         ids=["defaults", "no_flip", "no_shadowing"])
def test_normalmap_evaluates_in_the_perturbed_frame(name, flip, shadowing, rng):
    wi, wo = random_hemisphere(rng, 4096, 0.02), random_hemisphere(rng, 4096, 0.02)
    (value, pdf), (expected, expected_pdf) = through_normalmap(name, TILTED, wi, wo, flip,
                                                               shadowing)
    np.testing.assert_allclose(value, expected, rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(pdf, expected_pdf, rtol=1e-4, atol=1e-6)
    assert (expected.max(axis=1) > 0).mean() > 0.5
    # The viewers the normal faces away from: mirrored normal, or nothing.
    away = np.sum(wi * TILTED, axis=1) <= 0
    assert away.sum() > 100
    if flip:
        assert (value[away].max(axis=1) > 0).mean() > 0.5
    else:
        assert not value[away].any() and not pdf[away].any()


@pytest.mark.parametrize("name", NAMES)
def test_normalmap_shadowing_darkens_grazing_normals(name, rng):
    """A normal map whose normal lies almost in the surface, lit along that
    normal: the plugin answers as at normal incidence, and the shadowing term
    takes that back to a few per cent (the term itself:
    test_normalmap_evaluates_in_the_perturbed_frame)."""
    wi = np.tile([0.0, 0.0, 1.0], (64, 1))
    wo = unit(GRAZING + 0.005 * rng.normal(size=(64, 3)))
    (bare, _), (expected_bare, _) = through_normalmap(name, GRAZING, wi, wo, shadowing=False)
    (shadowed, _), (expected, _) = through_normalmap(name, GRAZING, wi, wo, shadowing=True)
    np.testing.assert_allclose(bare, expected_bare, rtol=1e-4, atol=1e-7)
    np.testing.assert_allclose(shadowed, expected, rtol=1e-4, atol=1e-7)
    assert bare.max(axis=1).min() > 0
    assert (shadowed <= 0.05 * bare + 1e-9).all()


@pytest.mark.parametrize("name", NAMES)
def test_normalmap_samples_in_the_perturbed_frame(name, rng):
    """sample(): the plugin's sample for the viewer in the perturbed frame,
    its direction taken back to the shading frame (dropped where it changes
    side), the weight times the shadowing term; and weight · pdf = eval."""
    n = 8192
    wi = random_hemisphere(rng, n, 0.02)
    adapter = mi.load_dict(normalmap(configs()[name], TILTED))
    u = rng.random((n, 3))
    bs, weight = adapter.sample(mi.BSDFContext(), framed_surface(wi), floats(u[:, 0]),
                                points(u[:, 1], u[:, 2]))
    wo, pdf = np.array(bs.wo, dtype=np.float64).T, np.array(bs.pdf, dtype=np.float64)
    weight = np.array(weight, dtype=np.float64).T
    frame = perturbed_frame(TILTED, wi)
    own_bs, own_weight = mi.load_dict(configs()[name]).sample(
        mi.BSDFContext(), surface(to_frame(frame, wi)), floats(u[:, 0]), points(u[:, 1], u[:, 2]))
    own_wo = np.array(own_bs.wo, dtype=np.float64).T
    back = from_frame(frame, own_wo)
    kept = (np.array(own_bs.pdf) > 0) & (back[:, 2] * own_wo[:, 2] > 0)
    assert kept.mean() > 0.3
    np.testing.assert_allclose(wo[kept], back[kept], atol=1e-5)
    np.testing.assert_allclose(pdf[kept], np.array(own_bs.pdf)[kept], rtol=1e-5)
    expected = (np.array(own_weight, dtype=np.float64).T[kept]
                * terminator(frame[2][kept], wo[kept])[:, None])
    np.testing.assert_allclose(weight[kept], expected, rtol=1e-4, atol=1e-7)
    assert not weight[~kept].any() and not pdf[~kept].any()
    value = eval_and_pdf(adapter, wi, wo)[0]
    np.testing.assert_allclose(weight[kept] * pdf[kept, None], value[kept], rtol=1e-4, atol=1e-6)


@pytest.mark.parametrize("name", NAMES)
def test_a_flat_normalmap_changes_nothing(name, rng):
    """A map of the unperturbed normal (colour 0.5, 0.5, 1) in any shading
    frame: the plugin's own samples, values and pdfs."""
    n = 4096
    wi, wo = random_hemisphere(rng, n, 0.02), random_hemisphere(rng, n, 0.02)
    adapter, plain = (mi.load_dict(normalmap(configs()[name], [0.0, 0.0, 1.0])),
                      mi.load_dict(configs()[name]))
    for a, b in zip(eval_and_pdf(adapter, wi, wo), eval_and_pdf(plain, wi, wo)):
        np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-7)
    s, own = (sampled(b, wi, np.random.default_rng(3)) for b in (adapter, plain))
    held = own["pdf"] > 0
    assert held.mean() > 0.3
    np.testing.assert_allclose(s["wo"][held], own["wo"][held], atol=1e-5)
    for key in ("pdf", "weight"):
        np.testing.assert_allclose(s[key], own[key], rtol=1e-4, atol=1e-7)


# ----------------------------------------------------------------------------
#  One lane at a time: scalar_rgb
# ----------------------------------------------------------------------------

def adapters_of(name: str) -> dict[str, dict]:
    config = configs()[name]
    return {"twosided": twosided(config, moved(config)),
            "blendbsdf": blend(config, configs()[neighbour(name)]),
            "normalmap": normalmap(config, TILTED)}


@pytest.mark.parametrize("name", NAMES)
def test_adapters_in_scalar_rgb(name):
    """In scalar_rgb the adapters call the plugin one lane at a time, with
    Python booleans for masks (False where normalmap drops a direction):
    eval, pdf, eval_pdf and sample give llvm_ad_rgb's values (to the
    tolerance of tests/test_variants.py), for viewers on both sides."""
    rng = np.random.default_rng(17)
    n = 12
    wi, wo = both_sides(rng, n)
    u = rng.random((n, 3))
    expected = {}
    for adapter, config in adapters_of(name).items():
        args = (interaction(wi), vec(wo), floats(u[:, 0]), points(u[:, 1], u[:, 2]))
        expected[adapter] = outputs(mi.load_dict(config), *args)
    with active_variant("scalar_rgb"):
        for adapter, config in adapters_of(name).items():
            bsdf = mi.load_dict(config)
            lanes = [outputs(bsdf, interaction(wi[k]), mi.Vector3f(*map(float, wo[k])),
                             float(u[k, 0]), mi.Point2f(float(u[k, 1]), float(u[k, 2])))
                     for k in range(n)]
            held = expected[adapter]["sample pdf"][0] > 0     # (a failed sample's wo is
            for key, value in expected[adapter].items():        # whatever is left in it)
                scalar = np.concatenate([lane[key] for lane in lanes], axis=1)
                lanes_compared = held if key == "sample wo" else slice(None)
                np.testing.assert_allclose(scalar[:, lanes_compared], value[:, lanes_compared],
                                           rtol=1e-4, atol=1e-6,
                                           err_msg=f"{adapter}({name}): {key}")
    assert all(e["eval"].any() for e in expected.values())
