"""The χ² test whose density table is refined until it converges: it accepts
sharp lobes that Mitsuba's fixed ires rejects, keeps its power against a wrong
pdf, and fails where the table cannot converge."""
import math

import mitsuba as mi
import pytest

from mi_brdfs.tools.chi2 import ConvergedChiSquareTest

PHONG_1000 = {"type": "phong", "exponent": 1000.0, "diffuse_reflectance": 0.0}
TOON_BAND = {"type": "toon", "specular_threshold": 0.97, "diffuse_reflectance": 0.0,
             "diffuse_shade": 0.0}


def chi2_of(cls, sampled, pdf, theta=0.0, **kwargs):
    wi = mi.ScalarVector3f(math.sin(math.radians(theta)), 0, math.cos(math.radians(theta)))
    sample_func, _ = mi.chi2.BSDFAdapter(sampled["type"], sampled, wi=wi)
    _, pdf_func = mi.chi2.BSDFAdapter(pdf["type"], pdf, wi=wi)
    return cls(domain=mi.chi2.SphericalDomain(), sample_func=sample_func, pdf_func=pdf_func,
               sample_dim=3, sample_count=1_000_000, res=101, **kwargs)


@pytest.mark.parametrize("config, theta", [
    (PHONG_1000, 0.0), (TOON_BAND, 0.0),
    ({"type": "blinn", "exponent": 1000.0, "diffuse_reflectance": 0.0}, 85.0),
    ({"type": "ward", "alpha": 0.05, "diffuse_reflectance": 0.0}, 85.0),
], ids=["phong 1000", "toon band", "blinn 1000 at 85", "ward 0.05 at 85"])
def test_sharp_lobes_pass_where_a_fixed_ires_fails(tmp_path, monkeypatch, config, theta):
    monkeypatch.chdir(tmp_path)                    # a rejected test writes chi2_data.py
    fixed = chi2_of(mi.chi2.ChiSquareTest, config, config, theta, ires=16)
    assert not fixed.run(0.01, quiet=True)         # the integration error, not the sampler
    converged = chi2_of(ConvergedChiSquareTest, config, config, theta)
    assert converged.run(0.01, quiet=True), converged.messages
    assert converged.ires_reached >= 64 and converged.unconverged == 0


def test_a_wrong_pdf_is_still_rejected(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    phong = {**PHONG_1000, "exponent": 100.0}
    right = chi2_of(ConvergedChiSquareTest, phong, phong, theta=30.0)
    assert right.run(0.01, quiet=True)
    wrong = chi2_of(ConvergedChiSquareTest, phong, {**phong, "exponent": 110.0}, theta=30.0)
    assert not wrong.run(0.01, quiet=True) and wrong.unconverged == 0


def test_a_table_that_cannot_converge_fails(tmp_path, monkeypatch):
    """The toon band's edge needs more than 33 points per axis: capped there,
    the test reports the cells and fails instead of giving a p-value."""
    monkeypatch.chdir(tmp_path)
    capped = chi2_of(ConvergedChiSquareTest, TOON_BAND, TOON_BAND, max_ires=33)
    assert not capped.run(0.01, quiet=True)
    assert capped.unconverged > 0 and "did not converge" in capped.messages


@pytest.mark.parametrize("scale, message", [(2.0, "more than 1"), (-1.0, "negative")])
def test_a_density_that_is_no_density_fails(tmp_path, monkeypatch, scale, message):
    """lambert's pdf doubled (it integrates to 2) or negated: the table itself
    is refused, with the reason."""
    monkeypatch.chdir(tmp_path)
    chi2 = chi2_of(ConvergedChiSquareTest, {"type": "lambert"}, {"type": "lambert"})
    pdf = chi2.pdf_func
    chi2.pdf_func = lambda *args: scale * pdf(*args)
    assert not chi2.run(0.01, quiet=True)
    assert "Failure: the density integrates to" in chi2.messages and message in chi2.messages
