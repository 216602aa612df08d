"""Scenes as users write them (tests/scenes/*.xml): Mitsuba's adapters
(twosided, bumpmap, normalmap, blendbsdf, mask), OBJ and PLY meshes with
shading normals, bitmap-textured colours and roughness, ``<spectrum>``
colours and light intensities, area, spot, point and environment lights,
materials declared once and shared by ``<ref id>``.

Each scene includes its materials from ``materials/$materials.xml``:
``ours`` (lambert, cook_torrance as a perfect conductor) or ``builtin``
(Mitsuba's diffuse and roughconductor, the same colours, textures and
roughness). In llvm_ad_rgb and llvm_ad_spectral:

- in hdr mode (Mitsuba's path tracer) the two render the same image up to
  noise: Welch's t-test per pixel on independent passes of each
  (:func:`mi_brdfs.tools.validate.welch_test`, the validation report's
  test), Bonferroni-corrected over the pixels and Šidák over the
  comparisons of this module; a negative control shows the test finds a
  5 % change of one material's reflectance in the same scene;
- in scanline mode (the scan-line integrator) every scene renders finite,
  non-negative and lit, in rgb within the integrator's [0, 1] clamp (in
  spectral variants the clamp applies per wavelength, and the sRGB values
  the film makes of clamped spectra may exceed 1).

Non-negative: in spectral variants the film's conversion to sRGB leaves
small negative values where a colour is outside sRGB's gamut (Mitsuba's
built-ins give them too), so there the bound is :data:`GAMUT` below 0,
relative to the image's maximum.
"""
from pathlib import Path

import numpy as np
import pytest

import mitsuba as mi

from mi_brdfs.tools.validate import ALPHA, welch_test
from support import active_variant

SCENES_DIR = Path(__file__).resolve().parents[1] / "scenes"
SCENES = ["studio", "adapters", "colours"]
VARIANTS = ["llvm_ad_rgb", "llvm_ad_spectral"]
RES, PASSES, SPP = 32, 16, 16
COMPARISONS = len(SCENES) * len(VARIANTS) + 1        # + the negative control
GAMUT = 0.02         # spectral variants: sRGB values down to -2 % of the maximum


@pytest.fixture(scope="module", params=VARIANTS)
def variant(request):
    with active_variant(request.param) as name:
        yield name


def load(name: str, **params) -> mi.Scene:
    return mi.load_file(str(SCENES_DIR / f"{name}.xml"), res=str(RES),
                        **{k: str(v) for k, v in params.items()})


def render_passes(scene: mi.Scene, seed0: int) -> np.ndarray:
    """(PASSES, RES, RES, channels) independent renders, float64."""
    return np.stack([np.array(mi.render(scene, spp=SPP, seed=seed0 + i), dtype=np.float64)
                     for i in range(PASSES)])


def assert_finite_and_positive(image: np.ndarray) -> None:
    assert np.isfinite(image).all()
    floor = -GAMUT * image.max() if mi.is_spectral else 0.0
    assert image.min() >= floor, (image.min(), image.max())


def lit(image: np.ndarray) -> float:
    """The fraction of pixels brighter than 1e-3 (channel mean)."""
    return float((image.mean(axis=-1) > 1e-3).mean())


def equal_to_noise(a: np.ndarray, b: np.ndarray) -> tuple[bool, dict]:
    test = welch_test(a, b)
    threshold = ALPHA / (test["pixels"] * COMPARISONS)
    return test["min_p"] > threshold, test


@pytest.mark.parametrize("name", SCENES)
def test_hdr_equals_mitsuba_builtins_to_noise(variant, name):
    ours = render_passes(load(name, materials="ours"), seed0=0)
    builtin = render_passes(load(name, materials="builtin"), seed0=1000)
    assert_finite_and_positive(ours)
    assert lit(builtin.mean(0)) > 0.5
    same, test = equal_to_noise(ours, builtin)
    assert same, f"{name} in {variant}: {test}"


def test_the_comparison_finds_a_small_difference():
    """Negative control: the same comparison tells ours from the built-ins
    when one material (the grey ground of the colours scene) is 5 % darker
    (in llvm_ad_rgb, whichever variant the module's other tests left active)."""
    with active_variant("llvm_ad_rgb"):
        scene = load("colours", materials="ours")
        params = mi.traverse(scene)
        params["grey.reflectance.value"] = params["grey.reflectance.value"] * 0.95
        params.update()
        builtin = load("colours", materials="builtin")
        same, test = equal_to_noise(render_passes(scene, seed0=0),
                                    render_passes(builtin, seed0=1000))
    assert not same, test


@pytest.mark.parametrize("name", SCENES)
def test_scanline_mode_renders(variant, name):
    image = np.array(mi.render(load(name, mode="scanline", materials="ours"), spp=4))
    assert_finite_and_positive(image)
    assert lit(image) > 0.5
    if not mi.is_spectral:         # the clamp is per wavelength; sRGB may exceed it
        assert image.max() <= 1.0                         # the integrator's final clamp
