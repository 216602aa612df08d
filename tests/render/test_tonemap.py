"""Tone mapping against its formulas; EXR round trip and atomic writes."""
import os

import numpy as np
import pytest

import mitsuba as mi

from mi_brdfs.render import exr, tonemap
from test_integrator import scene_dict

X = np.array([0.0, 0.01, 0.18, 0.5, 1.0, 2.0, 16.0, 1e30])


def test_operators_match_their_formulas():
    np.testing.assert_allclose(tonemap.tonemap(X, "clamp"), np.minimum(X, 1.0))
    np.testing.assert_allclose(tonemap.tonemap(X, "gamma", exposure=1.0), np.minimum(2 * X, 1.0))
    np.testing.assert_allclose(tonemap.tonemap(X, "reinhard"), X / (1 + X))
    aces = X * (2.51 * X + 0.03) / (X * (2.43 * X + 0.59) + 0.14)
    np.testing.assert_allclose(tonemap.tonemap(X, "aces"), np.clip(aces, 0, 1))
    # Narkowicz's fit: 0.18 grey maps to ~0.27 before encoding; large values to 1.
    assert tonemap.tonemap(np.array([0.18]), "aces")[0] == pytest.approx(0.2665, abs=1e-3)


@pytest.mark.parametrize("op", sorted(tonemap.OPERATORS))
def test_bad_values_do_not_crash(op):
    y = tonemap.tonemap(np.array([-1.0, np.nan, np.inf, -np.inf, 0.0]), op)
    np.testing.assert_array_equal(y, [0, 0, 1, 0, 0])
    assert tonemap.to_srgb8(np.array([np.nan, np.inf]), op).tolist() == [0, 255]


def test_srgb_encoding():
    v = np.array([0.0, 0.0031308, 0.5, 1.0])
    expected = [0.0, 12.92 * 0.0031308, 1.055 * 0.5 ** (1 / 2.4) - 0.055, 1.0]
    np.testing.assert_allclose(tonemap.srgb_encode(v), expected, rtol=1e-12)
    assert tonemap.to_srgb8(np.array([0.5])).tolist() == [188]


def test_unknown_operator():
    with pytest.raises(ValueError, match="unknown tone-mapping operator 'drago'"):
        tonemap.tonemap(X, "drago")


def test_exr_round_trip_is_exact(tmp_path):
    rng = np.random.default_rng(3)
    rgb = (rng.lognormal(size=(17, 23, 3)) * 10).astype(np.float32)
    rgb[0, 0] = [0.0, 1e-30, 6e4]
    exr.write_exr(str(tmp_path / "a.exr"), rgb)
    back = exr.read_exr(str(tmp_path / "a.exr"))
    assert back.dtype == np.float32
    np.testing.assert_array_equal(back, rgb)
    assert os.listdir(tmp_path) == ["a.exr"]


def test_failed_write_leaves_nothing(tmp_path):
    target = tmp_path / "a.exr"

    def fail(tmp):
        with open(tmp, "wb") as f:
            f.write(b"half an image")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        exr.write_atomically(str(target), fail)
    assert os.listdir(tmp_path) == []
    exr.write_exr(str(target), np.ones((2, 2, 3)))              # an existing file ...
    with pytest.raises(ValueError):
        exr.write_exr(str(target), np.ones((2, 2)))              # ... survives a failed rewrite
    np.testing.assert_array_equal(exr.read_exr(str(target)), np.ones((2, 2, 3)))
    assert os.listdir(tmp_path) == ["a.exr"]


def test_read_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        exr.read_exr(str(tmp_path / "none.exr"))
    (tmp_path / "bad.exr").write_bytes(b"not an exr")
    with pytest.raises(ValueError, match="not a readable EXR"):
        exr.read_exr(str(tmp_path / "bad.exr"))


def test_clamp_of_hdr_render_reproduces_scanline_image():
    """An HDR render of a scanline-mode scene (Mitsuba's path tracer, direct light:
    one point light, a convex sphere), tone-mapped with `clamp`, equals the
    scanline integrator's own clamped image, 8-bit for 8-bit."""
    bsdf = {"type": "lambert", "mode": "scanline", "reflectance": 0.9}
    hdr = np.array(mi.render(mi.load_dict(scene_dict(bsdf, {"type": "path", "max_depth": 2},
                                                     light_intensity=40.0))))
    ldr = np.array(mi.render(mi.load_dict(scene_dict(bsdf, {"type": "scanline"},
                                                     light_intensity=40.0))))
    assert hdr.max() > 1.5                       # the clamp matters here
    assert ldr.max() <= 1.0
    np.testing.assert_array_equal(tonemap.to_srgb8(hdr, "clamp"), tonemap.to_srgb8(ldr, "clamp"))
