"""What mi-brdfs fit tells a user per target (issue 26, points 4 and 6): the
effective colours and the albedo against independent formulas, the target's
features no course model has (spectral Fresnel, anisotropy, then fitted by
anisotropic ward and cook_torrance), the report's verdict and explanations,
per-channel lobe slices, and the smaller checks: black or non-finite targets
refused, a repeated target fitted once, a partial trade sweep said so."""
import json
import math
import re
from pathlib import Path

import drjit as dr
import numpy as np
import pytest

import mitsuba as mi

from mi_brdfs.tools.fit import effective, fit, metric, models, optimise, targets, task

TINY = task.QUICK.replace(viewers=(4, 2), uniform=(4, 4), lobe=4, scan=4, starts=1, steps=20,
                          res=24, spp=4, cost=False)
GOLD = "roughconductor:material=Au,alpha=0.1"
ROOT = Path(__file__).resolve().parents[2]


def schlick(f0, cos_theta):
    return f0 + (1 - f0) * (1 - cos_theta) ** 5


def test_effective_colours_are_what_the_brdf_shows():
    p = {"diffuse_reflectance": [0.6, 0.4, 0.2], "specular_reflectance": [0.9, 0.8, 0.7],
         "k": 0.25, "f0": 0.1, "alpha": 0.2}
    e = effective.parameters("cook_torrance", p)
    assert e["diffuse"] == pytest.approx([0.15, 0.1, 0.05])
    assert e["specular_0"] == pytest.approx([0.75 * 0.1 * c for c in (0.9, 0.8, 0.7)])
    grazing = schlick(0.1, math.cos(math.radians(85)))
    assert e["specular_85"] == pytest.approx([0.75 * grazing * c for c in (0.9, 0.8, 0.7)])
    assert effective.parameters("cook_torrance", {**p, "k": 0.0})["notes"] == [
        "k = 0: diffuse_reflectance has no effect"]
    phong = effective.parameters("phong", {"diffuse_reflectance": 0.5, "specular_reflectance":
                                           [0.3, 0.2, 0.1], "exponent": 10.0})
    assert phong["specular_0"] == phong["specular_85"] == [0.3, 0.2, 0.1]


def test_albedo_of_lambert_and_of_a_conductor_at_normal_incidence():
    lam = mi.load_dict({"type": "lambert", "reflectance": {"type": "rgb", "value": [0.6, 0.3, 0.1]}})
    assert np.allclose(effective.albedo(lam), [[0.6, 0.3, 0.1]] * 3, atol=1e-3)
    gold = targets.parse(["roughconductor:material=Au,alpha=0.02"])[0].load()
    params = mi.traverse(gold)
    eta, k = (np.array(params[key], dtype=float).ravel() for key in ("eta.value", "k.value"))
    f0 = ((eta - 1) ** 2 + k ** 2) / ((eta + 1) ** 2 + k ** 2)      # Fresnel at normal incidence
    assert np.allclose(effective.albedo(gold, (0.0,))[0], f0, atol=0.01)


@pytest.mark.parametrize("spec, whitening, anisotropy", [
    (GOLD, True, False),
    ("principled:base_color=[0.9,0.75,0.4],roughness=0.25,metallic=1", True, False),
    ("roughconductor:material=Al,alpha=0.1", False, False),                 # nearly grey
    ("roughplastic:alpha=0.1,diffuse_reflectance=[0.6,0.2,0.1]", False, False),  # white highlight
    ("diffuse:reflectance=[0.7,0.5,0.3]", False, False),
    ("roughconductor:material=Al,alpha_u=0.05,alpha_v=0.3", False, True),
])
def test_features_no_course_model_has(spec, whitening, anisotropy):
    found = effective.target_features(targets.parse([spec])[0], task.QUICK)
    assert found["whitening"]["present"] is whitening, found
    assert found["anisotropy"]["present"] is anisotropy, found
    extended = [m.name for m in effective.extended_models(found, rungs=False)]
    assert extended == (["ward/anisotropic", "cook_torrance/ggx/smith/anisotropic"]
                        if anisotropy else [])


@pytest.mark.parametrize("truth", [
    {"type": "ward", "alpha_u": 0.08, "alpha_v": 0.3,
     "diffuse_reflectance": [0.3, 0.2, 0.1], "specular_reflectance": [0.4, 0.4, 0.3]},
    {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith", "alpha_u": 0.05,
     "alpha_v": 0.3, "k": 0.2, "f0": 0.9, "diffuse_reflectance": [0.3, 0.2, 0.1],
     "specular_reflectance": [0.9, 0.9, 0.8]},
], ids=["ward", "cook_torrance"])
def test_an_anisotropic_model_recovers_its_own_anisotropic_lobe(truth):
    truth = {**truth, "mode": "hdr"}
    s = task.QUICK.replace(render=False)
    pairs = metric.pairs(s.metric, s.viewers, s.uniform, s.lobe)
    prob = optimise.problem(mi.load_dict(models.load_dict(truth)), pairs, s.objective)
    found = effective.features(mi.load_dict(models.load_dict(truth)), pairs)
    (model,) = [m for m in effective.extended_models(found) if m.plugin == truth["type"]]
    result = optimise.fit_model(model, prob, s)
    assert result["brdf_error"] < 1e-4
    assert result["parameters"]["alpha_u"] == pytest.approx(truth["alpha_u"], rel=0.01)
    assert result["parameters"]["alpha_v"] == pytest.approx(truth["alpha_v"], rel=0.01)


def test_the_report_says_why_no_model_comes_close_and_what_each_fit_means(tmp_path):
    records = fit([GOLD], str(tmp_path / "r"), ["lambert", "phong"], settings=TINY)
    html = (tmp_path / "r" / "index.html").read_text()
    assert "No course model comes close" in html
    assert "specular colour turns white towards grazing incidence" in html
    assert "(render cost not measured)" in html
    saved = {r["model"]: r for r in json.loads((tmp_path / "r" / "fits.json").read_text())}
    for r in saved.values():
        assert len(r["albedo"]) == 3 and all(len(a) == 3 for a in r["albedo"])
        assert r["target_features"]["whitening"]["present"]
    assert saved["phong"]["effective"]["specular_0"] == saved["phong"]["parameters"][
        "specular_reflectance"]
    assert_contents_link_each_section(html, 1)
    # Lobe slices per colour channel: [viewer angle][channel][point].
    for r in records:
        for side in ("target", "model"):
            assert np.array(r["slices"][side]).shape == (len(task.SLICE_ANGLES), 3,
                                                         task.SLICE_POINTS)


def assert_contents_link_each_section(page: str, targets: int) -> None:
    """The page's table of contents links each target's section, in order;
    every in-page link (the contents' and each section's back to top) names
    an id the page has."""
    ids = re.findall(r'\bid="([^"]+)"', page)
    links = re.findall(r'href="#([^"]*)"', page)
    contents = page.split('<nav id="contents">', 1)[1].split("</nav>", 1)[0]
    sections = re.findall(r'<h2 id="([^"]+)">', page)
    assert len(sections) == targets and len(set(ids)) == len(ids)
    assert re.findall(r'href="#([^"]*)"', contents) == sections
    assert links.count("top") == targets and set(links) <= set(ids)


def test_the_committed_trade_report_has_contents_and_links_back():
    page = (ROOT / "docs" / "benchmarks" / "trade" / "index.html").read_text()
    targets = len({r["target"] for r in json.loads(
        (ROOT / "docs" / "benchmarks" / "trade" / "fits.json").read_text())})
    assert targets > 1
    assert_contents_link_each_section(page, targets)


def test_a_report_states_the_samples_its_costs_were_timed_at(tmp_path):
    """The committed sweep's page gives the spp its records were timed at;
    records that predate cost_spp are said to be timed at their views' spp."""
    folder = ROOT / "docs" / "benchmarks" / "trade"
    records = json.loads((folder / "fits.json").read_text())
    spp = {r["cost_spp"] for r in records if r.get("cost_ratio") is not None}
    assert len(spp) == 1
    assert f"(the environment view at {spp.pop()} spp)" in (folder / "index.html").read_text()
    from mi_brdfs.tools.fit import report
    older = [{k: v for k, v in r.items() if k != "cost_spp"} for r in records[:3]]
    for r in older:
        r["target_name"] = r["target"]
    report.write(str(tmp_path), older, task.FULL, "test")
    assert f"(the environment view at {task.FULL.spp} spp)" in (tmp_path / "index.html").read_text()


def test_the_committed_trade_report_reads_as_labels_and_full_size_slices():
    """Each section's heading is the material's short label (the sweep's own,
    not its spec, which follows in code), and each lobe-slice figure links to
    its full-size image, which exists."""
    from mi_brdfs.tools.fit import trade
    folder = ROOT / "docs" / "benchmarks" / "trade"
    page = (folder / "index.html").read_text()
    headings = re.findall(r'<h2 id="[^"]+">([^<]+)</h2>', page)
    specs = list(dict.fromkeys(r["target"] for r in json.loads(
        (folder / "fits.json").read_text())))
    labels = dict((spec, label) for label, spec in trade.TARGETS)
    assert headings == [html_escape(labels[s]) for s in specs]
    assert all(":" not in h and "=" not in h for h in headings)
    links = re.findall(r'<a href="([^"]+__slices\.png)"[^>]*><img src="([^"]+)"', page)
    assert len(links) == len(specs) and all(a == b for a, b in links)
    assert all((folder / a).is_file() for a, _ in links)
    assert page.count("click for full size") == len(specs)


def html_escape(text: str) -> str:
    import html
    return html.escape(text)


def test_label_of_a_target_spec():
    """A target outside the sweep reads as its plugin and values; a file as its name."""
    from mi_brdfs.tools.fit.report import label
    assert label("roughconductor:material=Au,alpha=0.1") == "Au α0.1"
    assert label("roughplastic:alpha=0.2,diffuse_reflectance=[0.1,0.2,0.6]") == (
        "roughplastic, alpha 0.2, diffuse_reflectance [0.1,0.2,0.6]")
    assert label("roughconductor:material=Cu,alpha=0.2") == "roughconductor, Cu, alpha 0.2"
    assert label("/somewhere/gold.xml") == "gold.xml"


def test_from_records_on_a_folder_without_a_sweep_says_so(tmp_path, capsys):
    from mi_brdfs.tools.fit import trade
    assert trade.main(["--from-records", "-o", str(tmp_path)]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err == [f"python -m mi_brdfs.tools.fit.trade: error: {tmp_path} holds no trade "
                   "sweep (no fits.json): nothing to write again; run the sweep there "
                   "without --from-records"]


def test_a_repeated_target_is_fitted_once_with_a_warning(tmp_path):
    said = []
    records = fit(["diffuse:reflectance=[0.5,0.4,0.3]", "diffuse:reflectance=[0.5, 0.4, 0.3]"],
                      str(tmp_path / "r"), ["lambert"], settings=TINY.replace(render=False),
                      warn=said.append)
    assert len(records) == 1
    assert said == ["target diffuse:reflectance=[0.5, 0.4, 0.3] is given more than once; "
                    "it is fitted once"]


class NotFinite(mi.BSDF):
    """A BSDF whose eval is NaN: a broken material a user might hand the fit."""

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.m_flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
        self.m_components = [self.m_flags]

    def eval(self, ctx, si, wo, active=True):
        return mi.Color3f(dr.nan)

    def pdf(self, ctx, si, wo, active=True):
        return mi.Float(0.0)

    def sample(self, ctx, si, sample1, sample2, active=True):
        return dr.zeros(mi.BSDFSample3f), mi.Color3f(0.0)


def test_a_target_with_non_finite_values_is_refused():
    mi.register_bsdf("fit_test_not_finite", lambda props: NotFinite(props))
    (t,) = targets.parse(["fit_test_not_finite:"])
    with pytest.raises(targets.TargetError, match="its eval is not finite"):
        targets.check(t)


def test_a_partial_trade_sweep_says_what_it_left_out(capsys):
    """trade.md of a run over some materials names the others and the command
    that runs them all; an unknown material label is refused in one line."""
    from mi_brdfs.tools.fit import trade
    assert trade.subset_note(trade.TARGETS) == ""
    some = [t for t in trade.TARGETS if t[0] in ("diffuse", "Au α0.1")]
    note = trade.subset_note(some)
    assert note.startswith(f"**A partial run**: 2 of the {len(trade.TARGETS)} materials")
    left = note.split("not fitted here: ")[1].split(". The whole sweep")[0].split(", ")
    assert left == [label for label, _ in trade.TARGETS if label not in ("diffuse", "Au α0.1")]
    assert "python -m mi_brdfs.tools.fit.trade -o docs/benchmarks/trade" in note
    with pytest.raises(SystemExit) as exit_:
        trade.main(["-o", "unused", "--materials", "Au α0.2"])
    err = capsys.readouterr().err
    assert exit_.value.code == 1 and len(err.splitlines()) == 1
    assert "--materials: unknown label 'Au α0.2'" in err


def test_the_brdf_error_is_one_for_black_and_above_one_for_a_sharper_lobe():
    """brdf_error is E(f)/E(0): exactly 1 for a black BSDF, and above 1 for
    Mitsuba's own gold at half the roughness — a lobe sharper than the
    target's, whose directional albedo is within 5 % of the target's: L²
    weighs the taller peak by its height squared. The report's header says
    so rather than that 1 is the worst."""
    from mi_brdfs.tools.fit import report
    s = TINY.replace(viewers=(8, 4), uniform=(8, 8), lobe=16)
    p = metric.pairs(s.metric, s.viewers, s.uniform, s.lobe)
    target = mi.load_dict({"type": "roughconductor", "material": "Au", "alpha": 0.1})
    sharper = mi.load_dict({"type": "roughconductor", "material": "Au", "alpha": 0.05})
    prob = optimise.problem(target, p)
    values = optimise.values_of(sharper, prob.si, prob.wo)
    assert optimise.relative(np.zeros_like(values), prob) == pytest.approx(1.0, abs=1e-12)
    assert optimise.relative(values, prob) > 1.0
    a_t, a_s = effective.albedo(target), effective.albedo(sharper)
    assert np.allclose(a_s[0], a_t[0], rtol=0.05)
    assert "black = 1" in report.HEAD and "not bounded by 1" in report.BRDF_ERROR


def test_the_report_states_the_tolerance_the_seed_noise_and_a_plastics_reason(tmp_path):
    """A plastic no model comes close to gets the reason the guide gives
    (internal scattering under a coating), not "no feature"; the seed noise is
    explained as no floor for the fits and named as the tolerance; the verdict
    says whether a cheaper model looks the same."""
    fit(["roughplastic:alpha=0.1,diffuse_reflectance=[0.6,0.2,0.1]"], str(tmp_path / "r"),
        ["lambert"], settings=TINY)
    page = (tmp_path / "r" / "index.html").read_text()
    assert "No course model comes close" in page and "internal scattering" in page
    assert "No feature the fit can name" not in page
    assert "It is no floor for the fits" in page and "It is the tolerance" in page
    assert "★: first-ranked" in page
