"""mi-brdfs compare: metrics by hand, FLIP against NVIDIA's flip command, the FLIP
mode from file types, one PSNR peak, PNG inputs, masking, verdicts, bad input."""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mi_brdfs.render import exr, tonemap
from mi_brdfs.tools import compare

BIN = Path(sys.executable).parent


def tiny():
    r = np.zeros((2, 2, 3))
    r[0, 0] = [1.0, 0.5, 0.0]
    r[1, 1] = [0.2, 0.2, 0.2]
    t = r.copy()
    t[0, 0, 0] = 1.5        # +0.5 in one value
    t[1, 0, 2] = 0.1        # +0.1 where r = 0
    return r, t


def test_metrics_by_hand():
    r, t = tiny()
    m = compare.metrics(r, t, with_flip=False)
    n = 12
    assert m["mse"] == pytest.approx((0.25 + 0.01) / n)
    assert m["rmse"] == pytest.approx(np.sqrt(0.26 / n))
    assert m["relmse"] == pytest.approx((0.25 / 1.01**2 + 0.01 / 0.01**2) / n)
    assert m["mae"] == pytest.approx(0.6 / n)
    assert m["smape"] == pytest.approx((2 * 0.5 / 2.5 + 2 * 0.1 / 0.1) / n)
    assert m["max_abs"] == pytest.approx(0.5)
    assert m["psnr"] == pytest.approx(10 * np.log10(1.0 / (0.26 / n)))
    red = m["channels"]["R"]
    assert red["mse"] == pytest.approx(0.25 / 4) and red["max_abs"] == pytest.approx(0.5)
    assert m["channels"]["G"]["mse"] == 0 and m["channels"]["G"]["psnr"] == np.inf


def flip_cli(ref_path, test_path, tmp_path):
    out = subprocess.run([str(BIN / "flip"), "-r", str(ref_path), "-t", str(test_path),
                          "-d", str(tmp_path / "flipout")], capture_output=True, text=True)
    return float(re.search(r"Mean: ([0-9.]+)", out.stdout).group(1))


def test_flip_hdr_matches_flip_command(tmp_path):
    rng = np.random.default_rng(5)
    r = rng.lognormal(size=(32, 32, 3)).astype(np.float32)
    t = (r * rng.uniform(0.7, 1.3, size=r.shape)).astype(np.float32)
    exr.write_exr(str(tmp_path / "r.exr"), r)
    exr.write_exr(str(tmp_path / "t.exr"), t)
    value, _ = compare.flip(r.astype(np.float64), t.astype(np.float64), "hdr")
    assert value == pytest.approx(flip_cli(tmp_path / "r.exr", tmp_path / "t.exr", tmp_path), abs=2e-6)


def test_flip_ldr_matches_flip_command_on_srgb_pngs(tmp_path):
    rng = np.random.default_rng(6)
    r = rng.uniform(0, 1, size=(32, 32, 3))
    t = np.clip(r + rng.normal(0, 0.05, size=r.shape), 0, 1)
    # The same quantisation the flip command sees through the PNGs.
    r8, t8 = tonemap.to_srgb8(r), tonemap.to_srgb8(t)
    for name, img in (("r.png", r8), ("t.png", t8)):
        _write_png8(tmp_path / name, img)
    decode = lambda v: np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)
    value, _ = compare.flip(decode(r8 / 255.0), decode(t8 / 255.0), "ldr")
    assert value == pytest.approx(flip_cli(tmp_path / "r.png", tmp_path / "t.png", tmp_path), abs=1e-3)


def _write_png8(path, data):
    import mitsuba as mi
    mi.Bitmap(np.ascontiguousarray(data), mi.Bitmap.PixelFormat.RGB).write(str(path))


def write_pair(tmp_path, r, t):
    exr.write_exr(str(tmp_path / "r.exr"), r)
    exr.write_exr(str(tmp_path / "t.exr"), t)
    return str(tmp_path / "r.exr"), str(tmp_path / "t.exr")


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "mi_brdfs", "compare", *args],
                          capture_output=True, text=True, cwd=cwd)


def test_self_comparison_passes_with_zero_error(tmp_path):
    rng = np.random.default_rng(1)
    r = rng.uniform(0, 2, size=(24, 24, 3))
    ref, _ = write_pair(tmp_path, r, r)
    out = run(ref, ref, "-o", str(tmp_path / "rep"), "--max-rmse", "0", "--max-flip", "0")
    assert out.returncode == 0, out.stderr
    m = json.loads((tmp_path / "rep" / "metrics.json").read_text())["tests"][0]
    assert m["passed"]
    for key in ("mse", "rmse", "relmse", "mae", "smape", "max_abs", "flip"):
        assert m["metrics"][key] == 0, key
    assert m["metrics"]["psnr"] == float("inf")
    files = set(os.listdir(tmp_path / "rep"))
    assert {"index.html", "metrics.json", "metrics.csv", "reference.png", "test0_test.png",
            "test0_difference.png", "test0_relative.png", "test0_flip.png", "maps.exr",
            ".mi-brdfs-report"} <= files


def test_perturbed_copy_moves_metrics_and_fails_thresholds(tmp_path):
    rng = np.random.default_rng(2)
    r = rng.uniform(0.1, 1, size=(24, 24, 3))
    small = r * 1.01
    big = r * 1.2
    exr.write_exr(str(tmp_path / "r.exr"), r)
    exr.write_exr(str(tmp_path / "s.exr"), small)
    exr.write_exr(str(tmp_path / "b.exr"), big)
    out = run(str(tmp_path / "r.exr"), str(tmp_path / "s.exr"), str(tmp_path / "b.exr"),
              "-o", str(tmp_path / "rep"), "--max-rmse", "0.05")
    assert out.returncode == 3, out.stderr
    tests = json.loads((tmp_path / "rep" / "metrics.json").read_text())["tests"]
    s, b = tests[0]["metrics"], tests[1]["metrics"]
    assert tests[0]["passed"] and not tests[1]["passed"]
    for key in ("mse", "rmse", "relmse", "mae", "smape", "max_abs", "flip"):
        assert 0 < s[key] < b[key], key
    assert b["psnr"] < s["psnr"]
    assert b["mae"] == pytest.approx(0.2 * r.mean(), rel=1e-5)
    assert "rmse" in tests[1]["failures"][0]
    csv_text = (tmp_path / "rep" / "metrics.csv").read_text().splitlines()
    assert len(csv_text) == 1 + 2 * 4 and csv_text[0].startswith("test,channel,mse")


def test_crop(tmp_path):
    r = np.zeros((10, 10, 3))
    t = r.copy()
    t[0, 0] = 1.0                       # outside the crop
    ref, test = write_pair(tmp_path, r, t)
    res = compare.compare(ref, [test], str(tmp_path / "rep"), region=(2, 2, 5, 5))
    assert res[0].metrics["max_abs"] == 0


def bad_cases(tmp_path):
    good = np.ones((4, 4, 3))
    exr.write_exr(str(tmp_path / "good.exr"), good)
    exr.write_exr(str(tmp_path / "small.exr"), np.ones((2, 4, 3)))
    nan = good.copy()
    nan[0, 0, 1] = np.nan
    nan[1, 1] = np.inf
    exr.write_exr(str(tmp_path / "nan.exr"), nan)
    (tmp_path / "text.exr").write_text("hello")
    (tmp_path / "text.tiff").write_text("hello")
    g = str(tmp_path / "good.exr")
    return {
        "missing": ([g, str(tmp_path / "none.exr")], "no such file"),
        "not exr": ([g, str(tmp_path / "text.exr")], "not a readable EXR"),
        "resolution": ([g, str(tmp_path / "small.exr")], "is 4x2 but the reference"),
        "nan": ([g, str(tmp_path / "nan.exr")], "2 pixels are not finite (1 NaN, 1 Inf)"),
        "type": ([g, str(tmp_path / "text.tiff")], "unknown image type '.tiff'"),
        "flip mode": ([g, g, "--flip", "sdr"], "argument --flip: invalid choice: 'sdr'"),
        "threshold": ([g, g, "--max-rmse", "-1"], "argument --max-rmse: invalid value -1"),
        "crop": ([g, g, "--crop", "3,3,4,4"], "outside the 4x4 image"),
    }


@pytest.mark.parametrize("case", ["missing", "not exr", "resolution", "nan", "crop", "type",
                                  "flip mode", "threshold"])
def test_bad_input(tmp_path, case):
    args, message = bad_cases(tmp_path)[case]
    out = run(*args, "-o", str(tmp_path / "rep"))
    assert out.returncode == 1
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], out.stderr
    assert lines[0].startswith("mi-brdfs compare: error: ")
    leftovers = [p for p in os.listdir(tmp_path) if "rep" in p]
    assert leftovers == []


# ----------------------------------------------------------------------------
#  The FLIP mode, the PSNR peak, PNG inputs, masking, verdicts, maps.exr
# ----------------------------------------------------------------------------

def report(tmp_path, name="rep"):
    return json.loads((tmp_path / name / "metrics.json").read_text())


def test_flip_mode_follows_file_types_not_pixel_values(tmp_path):
    rng = np.random.default_rng(7)
    r = rng.uniform(0.05, 0.9, size=(32, 32, 3))
    t = np.clip(r + rng.normal(0, 0.05, size=r.shape), 0, 1)
    ref, test = write_pair(tmp_path, r, t)
    assert run(ref, test, "-o", str(tmp_path / "a")).returncode == 0
    bright = t.copy()
    bright[3, 3] = 1.5                                      # one pixel above 1
    exr.write_exr(str(tmp_path / "bright.exr"), bright)
    assert run(ref, str(tmp_path / "bright.exr"), "-o", str(tmp_path / "b")).returncode == 0
    a, b = report(tmp_path, "a"), report(tmp_path, "b")
    assert a["flip_mode"] == b["flip_mode"] == "hdr"
    fa, fb = a["tests"][0]["metrics"]["flip"], b["tests"][0]["metrics"]["flip"]
    assert abs(fb - fa) < 0.01 * fa + 1e-3                  # one pixel moves FLIP a little only
    tonemap.write_png(str(tmp_path / "r.png"), r)
    tonemap.write_png(str(tmp_path / "t.png"), t)
    assert run(str(tmp_path / "r.png"), str(tmp_path / "t.png"), "-o",
               str(tmp_path / "c")).returncode == 0
    assert report(tmp_path, "c")["flip_mode"] == "ldr"
    assert run(ref, test, "-o", str(tmp_path / "d"), "--flip", "ldr").returncode == 0
    d = report(tmp_path, "d")
    assert d["flip_mode"] == "ldr" and d["tests"][0]["metrics"]["flip"] != fa


def test_overall_psnr_lies_between_the_channels(tmp_path):
    rng = np.random.default_rng(8)
    r = rng.uniform(0, 1, size=(16, 16, 3)) * [4.0, 1.0, 0.25]      # channels of unequal range
    t = r + rng.normal(0, 1, size=r.shape) * [0.01, 0.05, 0.2]     # and unequal errors
    m = compare.metrics(r, t, with_flip=False)
    per = [m["channels"][c]["psnr"] for c in "RGB"]
    assert min(per) < m["psnr"] < max(per)
    peak = r.max()                                                  # one peak for all
    assert m["psnr_peak"] == pytest.approx(peak)
    for i, c in enumerate("RGB"):
        mse = np.mean((t[..., i] - r[..., i]) ** 2)
        assert m["channels"][c]["psnr"] == pytest.approx(10 * np.log10(peak**2 / mse))


def test_png_inputs_are_srgb_decoded_and_peak_is_one(tmp_path):
    rng = np.random.default_rng(9)
    r = rng.uniform(0, 1, size=(8, 8, 3))
    t = np.clip(r * 0.9, 0, 1)
    for name, image in (("r.png", r), ("t.jpg", t)):
        import mitsuba as mi
        mi.Bitmap(np.ascontiguousarray(tonemap.to_srgb8(image)),
                  mi.Bitmap.PixelFormat.RGB).write(str(tmp_path / name))
    out = run(str(tmp_path / "r.png"), str(tmp_path / "t.jpg"), "-o", str(tmp_path / "rep"))
    assert out.returncode == 0, out.stderr
    decode = lambda v: np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)
    linear_r = decode(tonemap.to_srgb8(r) / 255.0)
    m = report(tmp_path)["tests"][0]["metrics"]
    assert m["psnr_peak"] == 1.0
    assert compare.load(str(tmp_path / "r.png")) == pytest.approx(linear_r, abs=1e-6)
    assert report(tmp_path)["flip_mode"] == "ldr"


def test_mask_nonfinite_leaves_pixels_out(tmp_path):
    rng = np.random.default_rng(10)
    r = rng.uniform(0.1, 1, size=(6, 6, 3))
    t = r * 1.1
    t[0, 0, 1] = np.nan
    t[2, 3] = np.inf
    ref, test = write_pair(tmp_path, r, t)
    assert run(ref, test, "-o", str(tmp_path / "refused")).returncode == 1
    out = run(ref, test, "-o", str(tmp_path / "rep"), "--mask-nonfinite")
    assert out.returncode == 0, out.stderr
    m = report(tmp_path)["tests"][0]["metrics"]
    keep = np.isfinite(t).all(axis=-1)
    assert m["masked_pixels"] == 2
    assert m["mae"] == pytest.approx(np.mean(np.abs(t[keep] - r[keep])), rel=1e-5)
    assert np.isfinite(m["flip"]) and m["flip"] > 0


def test_without_thresholds_the_verdict_is_no_thresholds(tmp_path):
    r = np.full((4, 4, 3), 0.5)
    ref, test = write_pair(tmp_path, r, r * 2)
    out = run(ref, test, "-o", str(tmp_path / "rep"))
    assert out.returncode == 0
    assert "-> no thresholds" in out.stdout and "PASS" not in out.stdout
    t = report(tmp_path)["tests"][0]
    assert t["verdict"] == "no thresholds" and t["passed"] is None
    html = (tmp_path / "rep" / "index.html").read_text()
    assert "no thresholds" in html and ">PASS<" not in html


def test_maps_exr_holds_every_map_as_a_layer(tmp_path):
    rng = np.random.default_rng(11)
    r = rng.uniform(0.1, 1, size=(5, 7, 3))
    t = r + 0.25
    ref, test = write_pair(tmp_path, r, t)
    assert run(ref, test, "-o", str(tmp_path / "rep")).returncode == 0
    import OpenEXR
    with OpenEXR.File(str(tmp_path / "rep" / "maps.exr")) as f:
        layers = {name: np.asarray(c.pixels) for name, c in f.channels().items()}
    assert set(layers) == {"reference", "test0.image", "test0.difference", "test0.relative",
                           "test0.flip.Y"}
    np.testing.assert_allclose(layers["test0.difference"], 0.25, atol=1e-5)
    np.testing.assert_allclose(layers["reference"], r, rtol=1e-6)
    assert layers["test0.flip.Y"].shape == (5, 7)


def test_difference_pictures_use_a_robust_scale():
    values = np.concatenate([np.linspace(-0.01, 0.01, 999), [50.0]])   # one outlier
    span = compare.robust_span(values)
    assert 0.009 < span < 0.011                  # the 99th percentile, not the outlier
    assert compare.robust_span(np.zeros(4)) == 1.0


@pytest.mark.parametrize("test_value", [0.0, 1.0])
def test_hdr_flip_of_a_black_reference_does_not_abort(test_value):
    """flip-evaluator takes HDR exposures from the reference and aborts the
    process on a black one (measured): compare must answer instead."""
    r = np.zeros((6, 6, 3))
    t = r.copy()
    t[2, 2] = test_value
    value, error_map = compare.flip(r, t, "hdr")
    assert error_map.shape == (6, 6)
    assert (value == 0) == (test_value == 0) and np.isfinite(value)


# ----------------------------------------------------------------------------
#  Every EXR that `mi-brdfs render` writes: mono (Y), RGB, RGBA, AOV layers
# ----------------------------------------------------------------------------

LAYERED_SCENE = """<scene version="3.0.0">
    <default name="format" value="rgb"/>
    <integrator type="aov">
        <string name="aovs" value="dd.y:depth,nn:sh_normal,alb:albedo"/>
        <integrator type="scanline" name="image"/>
    </integrator>
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="2"/></sampler>
        <film type="hdrfilm"><integer name="width" value="12"/><integer name="height" value="10"/>
            <string name="pixel_format" value="$format"/></film>
    </sensor>
    <emitter type="point"><point name="position" x="2" y="2" z="3"/><rgb name="intensity" value="9"/></emitter>
    <shape type="sphere"><bsdf type="lambert"><rgb name="reflectance" value="0.2, 0.4, 0.8"/></bsdf></shape>
</scene>
"""


@pytest.fixture(scope="module")
def renders(tmp_path_factory):
    """What `mi-brdfs render` writes: a mono render (Y and AOVs), an RGB
    render and an RGBA one with the AOV layers alpha, albedo, depth, normals."""
    work = tmp_path_factory.mktemp("renders")
    scene = work / "layered.xml"
    scene.write_text(LAYERED_SCENE)
    files = {}
    for name, args in {"mono": ["-m", "llvm_ad_mono", "-D", "format=luminance"],
                       "rgb": [], "rgba": ["-D", "format=rgba"]}.items():
        files[name] = str(work / f"{name}.exr")
        done = subprocess.run([sys.executable, "-m", "mi_brdfs", "render", str(scene), "-q",
                               "--passes", "1", "-o", files[name], *args],
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
    return files


def channels_of(path):
    """The file's channels, read with OpenEXR here (not through the package)."""
    import OpenEXR
    with OpenEXR.File(path, separate_channels=True) as f:
        return {k: np.asarray(v.pixels, dtype=np.float64) for k, v in f.channels().items()}


def twice(path, tmp_path):
    """A copy of an EXR with every channel doubled (written with OpenEXR)."""
    import OpenEXR
    data = {k: (v * 2).astype(np.float32) for k, v in channels_of(path).items()}
    target = str(tmp_path / "twice.exr")
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION,
                       "type": OpenEXR.scanlineimage}, data) as f:
        f.write(target)
    return target


def mae_of(ref, tmp_path, layer=None):
    """compare's mean absolute error between ``ref`` and its double."""
    compare.compare(ref, [twice(ref, tmp_path)], str(tmp_path / "rep"), layer=layer)
    r = report(tmp_path)
    return r["tests"][0]["metrics"]["mae"], r


@pytest.mark.parametrize("kind, colour", [("mono", ["Y"] * 3), ("rgb", ["R", "G", "B"]),
                                          ("rgba", ["R", "G", "B"])])     # alpha left out
def test_reads_the_colour_of_every_render(renders, tmp_path, kind, colour):
    found = channels_of(renders[kind])
    assert set(colour) <= set(found) and ("A" in found) == (kind == "rgba")
    expected = np.stack([found[c] for c in colour], axis=-1)
    assert expected.max() > 0.05
    mae, _ = mae_of(renders[kind], tmp_path)
    assert mae == pytest.approx(np.abs(expected).mean(), rel=1e-5)       # |2x - x|


@pytest.mark.parametrize("kind, layer, colour", [
    ("rgba", "alb", ["alb.R", "alb.G", "alb.B"]),
    ("rgb", "nn", ["nn.X", "nn.Y", "nn.Z"]),
    ("mono", "dd.y", ["dd.y.T"] * 3),            # one channel, in all three
])
def test_layer_picks_an_aov(renders, tmp_path, kind, layer, colour):
    found = channels_of(renders[kind])
    expected = np.stack([found[c] for c in colour], axis=-1)
    assert np.abs(expected).max() > 0.1
    mae, r = mae_of(renders[kind], tmp_path, layer)
    assert r["layer"] == layer and mae == pytest.approx(np.abs(expected).mean(), rel=1e-5)


def test_an_unknown_layer_names_the_layers(renders, tmp_path, capsys):
    from mi_brdfs.tools import cli
    ref = renders["rgba"]
    assert cli.main(["compare", ref, ref, "-o", str(tmp_path / "rep"), "--layer", "albedo"]) == 1
    assert capsys.readouterr().err.strip() == (
        f"mi-brdfs compare: error: {ref}: no layer 'albedo'; its layers: (base), alb, dd.y, nn")
    assert not (tmp_path / "rep").exists()
