"""Compare renders against a reference: metrics, pictures, a verdict, an HTML report.

    mi-brdfs compare REFERENCE TEST [TEST ...] -o REPORT_DIR [--flip ldr|hdr]
                     [--max-rmse X] [--max-relmse X] [--max-mae X] [--max-flip X]
                     [--max-abs X] [--min-psnr DB] [--crop X,Y,W,H] [--tonemap NAME]
                     [--mask-nonfinite] [--layer NAME]

Inputs are EXR (linear) or PNG/JPEG (sRGB-decoded to linear values), all of
the same size. An EXR is read as ``mi-brdfs render`` writes it in any
variant: its R, G, B channels (an alpha channel is left out), or its
luminance Y (mono variants: compared in all three channels). ``--layer NAME``
compares a layer of multi-layer EXRs instead (an AOV: ``NAME.R/G/B``,
``NAME.X/Y/Z``, or a single channel such as a depth, repeated); an unknown
layer is an error that lists the file's layers. PNG/JPEG inputs have no
layers (``--layer`` applies to the EXR inputs). Pixels that are NaN or Inf in an input
are refused, or left out of every metric with ``--mask-nonfinite`` (their
count is reported).

Metrics (r the reference, t the test, means over pixels and channels; each is
also given per channel):

=========  ===============================================================
mse        mean((t - r)²)
rmse       sqrt(mse)
relmse     mean((t - r)² / (r + 0.01)²)              (pbrt's relative MSE)
mae        ``mean(|t - r|)``
smape      ``mean(2 |t - r| / (|t| + |r|))``, 0 where both are 0
max_abs    ``max(|t - r|)``
psnr       10 log10(peak² / mse), inf if mse = 0, with ONE peak for the
           overall value and every channel: 1 when every input is PNG/JPEG,
           else the reference's maximum over all channels (1 if it is
           black). The overall mse is the mean of the channels', so the
           overall PSNR lies between the channels'.
flip       mean FLIP error (NVIDIA flip-evaluator), in the mode ``--flip``
           names; by default from the inputs' FILE TYPES, never from their
           pixel values: HDR-FLIP (linear values) if any input is EXR,
           LDR-FLIP (sRGB-encoded values, clamped to [0, 1]) when all are
           PNG/JPEG. The mode is recorded as ``flip_mode``.
=========  ===============================================================

Verdict per test image: PASS or FAIL against the thresholds given, "no
thresholds" when none is given. Exit status: 0 when no test fails, 3 when
one fails, 1 on an error.

The report folder (see :mod:`.destinations`: new, empty, or a previous report;
never a folder with other files) holds ``index.html``, ``metrics.json``,
``metrics.csv``, the pictures as PNG (both images tone-mapped the same way,
the signed difference and the relative error on a robust scale, the FLIP
map) and ``maps.exr``: every image and error map as one multi-layer EXR
(``reference``, ``testN.image``, ``testN.difference``, ``testN.relative``,
``testN.flip``) for an EXR viewer such as tev.
"""
from __future__ import annotations

import csv
import json
import math
import os
from dataclasses import dataclass, field
from typing import Iterator

import numpy as np

import mitsuba as mi

from ..render import exr, tonemap
from . import destinations, measures, pages
from .pages import esc

# flip-evaluator runs on its own OpenMP runtime (loaded with it), whose threads
# spin while they wait by default: on a loaded machine (2 cores, load 19) one
# HDR-FLIP of 128² pixels took 2.9-3.7 s so and 0.5-0.7 s with passive waiting,
# the same result. Set before flip_evaluator is imported; a user's choice stands.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

CHANNELS = "RGB"
THRESHOLDS = {            # option name -> (metric, comparison)
    "max_rmse": ("rmse", "<="),
    "max_relmse": ("relmse", "<="),
    "max_mae": ("mae", "<="),
    "max_abs": ("max_abs", "<="),
    "max_flip": ("flip", "<="),
    "min_psnr": ("psnr", ">="),
}
HDR_TYPES = (".exr",)
LDR_TYPES = (".png", ".jpg", ".jpeg")
FLIP_MODES = ("ldr", "hdr")
PERCENTILE = 99.0         # scale of the difference pictures: this percentile of |error|


class CompareError(ValueError):
    """Bad input for a comparison (reported on one line)."""


# ----------------------------------------------------------------------------
#  Loading and checking
# ----------------------------------------------------------------------------

def load(path: str, layer: str | None = None) -> np.ndarray:
    """An input as linear (H, W, 3) float64: an EXR's colour (of ``layer``,
    see :func:`.exr.read_exr`), or a PNG/JPEG decoded from sRGB (through
    mi.Bitmap). Non-finite values kept."""
    ext = check_type(path)
    if not os.path.exists(path):
        raise CompareError(f"no such file: {path}")
    if ext in HDR_TYPES:
        try:
            return exr.read_exr(path, layer).astype(np.float64)
        except (ValueError, OSError) as error:
            raise CompareError(str(error)) from None
    if ext in LDR_TYPES:
        try:
            bitmap = mi.Bitmap(path)
        except Exception:
            raise CompareError(f"{path}: not a readable {ext[1:].upper()} file") from None
        linear = bitmap.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32,
                                srgb_gamma=False)
        return np.array(linear, dtype=np.float64)


def check_type(path: str) -> str:
    """The extension of an input image; CompareError for an unknown type."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in HDR_TYPES + LDR_TYPES:
        raise CompareError(f"{path}: unknown image type {ext or '(none)'!r}; valid: "
                           f"{', '.join(HDR_TYPES + LDR_TYPES)}")
    return ext


def default_flip_mode(paths: list[str]) -> str:
    """'hdr' if any input is an HDR file type (EXR), 'ldr' if all are PNG/JPEG."""
    return "ldr" if all(os.path.splitext(p)[1].lower() in LDR_TYPES for p in paths) else "hdr"


def finite(image: np.ndarray) -> np.ndarray:
    """The image with NaN and Inf values set to 0 (for pictures of masked inputs)."""
    return np.where(np.isfinite(image), image, 0.0)


def nonfinite(image: np.ndarray) -> np.ndarray:
    """(H, W) mask of the pixels with a NaN or Inf channel."""
    return ~np.isfinite(image).all(axis=-1)


def refuse_nonfinite(image: np.ndarray, path: str) -> None:
    bad = nonfinite(image)
    if bad.any():
        nan = int(np.isnan(image).any(axis=-1).sum())
        raise CompareError(f"{path}: {int(bad.sum())} pixels are not finite "
                           f"({nan} NaN, {int(bad.sum()) - nan} Inf); "
                           "--mask-nonfinite leaves them out")


def require_reports() -> None:
    """Import the report dependencies now, so that a plain install (without the
    ``reports`` extra) fails before any work: ModuleNotFoundError names the module."""
    import flip_evaluator  # noqa: F401
    import matplotlib  # noqa: F401
    import scipy  # noqa: F401


def check_pair(ref: np.ndarray, test: np.ndarray, ref_path: str, test_path: str) -> None:
    if ref.shape != test.shape:
        raise CompareError(f"{test_path} is {test.shape[1]}x{test.shape[0]} but the reference "
                           f"{ref_path} is {ref.shape[1]}x{ref.shape[0]}")


def crop(image: np.ndarray, region: tuple[int, int, int, int] | None) -> np.ndarray:
    if region is None:
        return image
    x, y, w, h = region
    if w <= 0 or h <= 0 or x < 0 or y < 0 or x + w > image.shape[1] or y + h > image.shape[0]:
        raise CompareError(f"crop {x},{y},{w},{h} is outside the "
                           f"{image.shape[1]}x{image.shape[0]} image")
    return image[y:y + h, x:x + w]


# ----------------------------------------------------------------------------
#  Metrics
# ----------------------------------------------------------------------------

def psnr_peak(ref: np.ndarray, ldr: bool = False) -> float:
    """The one PSNR peak: 1 for LDR inputs, else max(ref) over every channel
    (1 for a black reference)."""
    if ldr:
        return 1.0
    peak = float(np.max(ref)) if ref.size else 0.0
    return peak if peak > 0 else 1.0


def _errors(r: np.ndarray, t: np.ndarray, axis, peak: float) -> dict:
    d = t - r
    mse = np.mean(d * d, axis=axis)
    denom = np.abs(t) + np.abs(r)
    smape_terms = np.where(denom > 0, 2 * np.abs(d) / np.where(denom > 0, denom, 1.0), 0.0)
    with np.errstate(divide="ignore"):
        psnr = np.where(mse > 0, 10 * np.log10(peak * peak / np.where(mse > 0, mse, 1.0)), np.inf)
    return {
        "mse": mse,
        "rmse": np.sqrt(mse),
        "relmse": measures.relmse(t, r, axis=axis),
        "mae": np.mean(np.abs(d), axis=axis),
        "smape": np.mean(smape_terms, axis=axis),
        "max_abs": np.max(np.abs(d), axis=axis),
        "psnr": psnr,
    }


def flip(ref: np.ndarray, test: np.ndarray, mode: str = "hdr") -> tuple[float, np.ndarray]:
    """Mean FLIP error and the (H, W) error map, in ``mode`` 'hdr' (linear
    values) or 'ldr' (clamped to [0, 1] and sRGB-encoded)."""
    import flip_evaluator               # optional: the reports extra

    if mode not in FLIP_MODES:
        raise CompareError(f"unknown FLIP mode {mode!r}; valid: {', '.join(FLIP_MODES)}")
    if mode == "hdr":
        r, t = np.maximum(ref, 0).astype(np.float32), np.maximum(test, 0).astype(np.float32)
        exposures = {}
        if not (r > 0).any():
            # HDR-FLIP takes its exposure range from the reference and aborts the
            # process on a black one: take the range from the test image instead.
            if not (t > 0).any():
                return 0.0, np.zeros(ref.shape[:2])          # both black: identical
            _, _, found = flip_evaluator.evaluate(t, t, "HDR", applyMagma=False)
            exposures = {k: found[k] for k in ("startExposure", "stopExposure")}
        error_map, mean, _ = flip_evaluator.evaluate(r, t, "HDR", applyMagma=False,
                                                     parameters=exposures)
    else:
        encode = lambda x: tonemap.srgb_encode(np.clip(x, 0, 1)).astype(np.float32)
        error_map, mean, _ = flip_evaluator.evaluate(encode(ref), encode(test), "LDR",
                                                     inputsRGB=True, applyMagma=False)
    return float(mean), np.asarray(error_map, dtype=np.float64).reshape(ref.shape[:2])


def metrics(ref: np.ndarray, test: np.ndarray, with_flip: bool = True, flip_mode: str = "hdr",
            peak: float | None = None, mask: np.ndarray | None = None) -> dict:
    """Every metric, overall and per channel (plain floats). ``mask`` (H, W):
    the pixels to leave out. ``peak``: the PSNR peak (default psnr_peak(ref))."""
    keep = np.ones(ref.shape[:2], bool) if mask is None else ~mask
    r, t = ref[keep].reshape(-1, 3), test[keep].reshape(-1, 3)
    if not len(r):
        raise CompareError("no pixel is left to compare (every pixel is masked)")
    peak = psnr_peak(r) if peak is None else peak
    per = _errors(r, t, axis=0, peak=peak)
    overall = {k: float(v) for k, v in _errors(r, t, axis=None, peak=peak).items()}
    channels = {c: {k: float(v[i]) for k, v in per.items()} for i, c in enumerate(CHANNELS)}
    result = {**overall, "psnr_peak": peak, "channels": channels,
              "masked_pixels": int((~keep).sum())}
    if with_flip:
        result["flip"], _ = masked_flip(ref, test, flip_mode, mask)
        result["flip_mode"] = flip_mode
    return result


def masked_flip(ref: np.ndarray, test: np.ndarray, mode: str,
                mask: np.ndarray | None) -> tuple[float, np.ndarray]:
    """FLIP with masked pixels set to 0 in both images and left out of the mean."""
    if mask is None or not mask.any():
        return flip(ref, test, mode)
    clean = lambda x: np.where(mask[..., None], 0.0, x)
    _, error_map = flip(clean(ref), clean(test), mode)
    return float(error_map[~mask].mean()), np.where(mask, 0.0, error_map)


def verdict(m: dict, thresholds: dict[str, float]) -> list[str]:
    """The failed thresholds as readable strings (empty: pass)."""
    failures = []
    for option, limit in thresholds.items():
        if limit is None:
            continue
        metric, op = THRESHOLDS[option]
        value = m[metric]
        ok = value <= limit if op == "<=" else value >= limit
        if not ok or (isinstance(value, float) and math.isnan(value)):
            failures.append(f"{metric} = {value:.6g} (limit {op} {limit:g})")
    return failures


# ----------------------------------------------------------------------------
#  Pictures
# ----------------------------------------------------------------------------

def robust_span(values: np.ndarray, percentile: float = PERCENTILE) -> float:
    """The scale of an error picture: the given percentile of ``|values|`` (not the
    single largest error, which would make every other pixel look black)."""
    finite = np.abs(values[np.isfinite(values)])
    if not finite.size:
        return 1.0
    span = float(np.percentile(finite, percentile))
    return span if span > 0 else (float(finite.max()) or 1.0)


def _save_map(path: str, data: np.ndarray, cmap: str, vmin: float, vmax: float, label: str,
              over: str | None = None, under: str | None = None) -> None:
    """An error map with a colour bar; values beyond [vmin, vmax] drawn in the
    ``over``/``under`` colours, shown as the colour bar's end triangles."""
    import matplotlib                   # optional: the reports extra
    from matplotlib.figure import Figure    # no pyplot: no global backend change

    colours = matplotlib.colormaps[cmap].with_extremes(over=over, under=under)
    extend = {(True, True): "both", (True, False): "max", (False, True): "min"}.get(
        (bool(over), bool(under)), "neither")
    h, w = data.shape
    fig = Figure(figsize=(4.2, 4.2 * h / w + 0.5), dpi=100)
    ax = fig.subplots()
    im = ax.imshow(data, cmap=colours, vmin=vmin, vmax=vmax, interpolation="nearest")
    ax.set_axis_off()
    bar = fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04, extend=extend)
    bar.set_label(label, fontsize=9)
    bar.ax.tick_params(labelsize=8)
    fig.savefig(path, bbox_inches="tight")


def pictures(directory: str, prefix: str, ref: np.ndarray, test: np.ndarray,
             operator: str, flip_map: np.ndarray | None,
             ref_name: str = "reference.png") -> dict[str, str]:
    """Write the report's PNGs (the reference once, as ref_name); returns {kind: file name}.
    Difference and relative error are scaled to their 99th percentile; larger
    values are drawn in yellow (positive) and cyan (negative), and counted in
    the colour bar's label."""
    files = {"reference": ref_name, "test": f"{prefix}_test.png"}
    if not os.path.exists(os.path.join(directory, files["reference"])):
        tonemap.write_png(os.path.join(directory, files["reference"]), ref, operator)
    tonemap.write_png(os.path.join(directory, files["test"]), test, operator)
    diff = finite((test - ref).mean(axis=-1))
    span = robust_span(diff)
    clipped = int((np.abs(diff) > span).sum())
    files["difference"] = f"{prefix}_difference.png"
    _save_map(os.path.join(directory, files["difference"]), diff, "RdBu_r", -span, span,
              f"test − reference (channel mean); {clipped} px beyond ±{span:.3g}",
              over="yellow", under="cyan")
    rel = finite((np.abs(test - ref) / (np.abs(ref) + 0.01)).mean(axis=-1))
    rspan = robust_span(rel)
    files["relative"] = f"{prefix}_relative.png"
    _save_map(os.path.join(directory, files["relative"]), rel, "viridis", 0.0, rspan,
              f"|t − r| / (r + 0.01); {int((rel > rspan).sum())} px beyond {rspan:.3g}",
              over="magenta")
    if flip_map is not None:
        files["flip"] = f"{prefix}_flip.png"
        _save_map(os.path.join(directory, files["flip"]), flip_map, "magma", 0.0, 1.0, "FLIP")
    return files


def write_layers(path: str, layers: dict[str, np.ndarray]) -> None:
    """Write {layer: (H, W, 3) or (H, W) image} as one multi-layer float32 EXR
    (channels ``layer.R/G/B`` or ``layer.Y``), atomically."""
    channels = {}
    for layer, image in layers.items():
        image = np.asarray(image, dtype=np.float32)
        if image.ndim == 2:
            channels[f"{layer}.Y"] = image
        else:
            channels.update({f"{layer}.{c}": image[..., i] for i, c in enumerate(CHANNELS)})
    exr.write_channels(path, channels)


# ----------------------------------------------------------------------------
#  The report
# ----------------------------------------------------------------------------

@dataclass
class Comparison:
    test_path: str
    metrics: dict
    failures: list[str]
    thresholds: bool = True       # were any thresholds given?
    files: dict[str, str] = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return not self.failures

    @property
    def verdict(self) -> str:
        """'PASS', 'FAIL', or 'no thresholds'."""
        if not self.thresholds:
            return "no thresholds"
        return "PASS" if self.passed else "FAIL"


METRIC_ORDER = ["mse", "rmse", "relmse", "mae", "smape", "max_abs", "psnr", "flip"]


def _html(ref_path: str, comparisons: list[Comparison], thresholds: dict, operator: str,
          region, flip_mode: str, masked: bool, layer: str | None = None) -> str:
    css = {"PASS": "pass", "FAIL": "fail", "no thresholds": "none"}
    summary = pages.table(["test image", *METRIC_ORDER, "verdict"],
                          [[c.test_path, *(float(c.metrics[k]) for k in METRIC_ORDER), c.verdict]
                           for c in comparisons],
                          classes=[css[c.verdict] for c in comparisons], digits=6)
    limits = ", ".join(f"{THRESHOLDS[k][0]} {THRESHOLDS[k][1]} {v:g}"
                       for k, v in thresholds.items() if v is not None) or "none"
    sections = []
    for c in comparisons:
        per = pages.table(["channel", *METRIC_ORDER[:-1]],
                          [[ch, *(float(c.metrics["channels"][ch][k]) for k in METRIC_ORDER[:-1])]
                           for ch in CHANNELS], digits=6)
        if c.verdict == "no thresholds":
            text = "<p class='none'>No thresholds given: no verdict.</p>"
        elif c.failures:
            text = "<p class='fail'>Failed: " + esc("; ".join(c.failures)) + "</p>"
        else:
            text = "<p class='pass'>Passed every threshold.</p>"
        left_out = (f" {c.metrics['masked_pixels']} non-finite pixels left out."
                    if masked else "")
        sections.append(
            f"<section><h2>{esc(c.test_path)}</h2>{text}{per}"
            f"<p>PSNR peak {c.metrics['psnr_peak']:.6g} (overall and every "
            f"channel).{left_out}</p>"
            + pages.figures([(name, kind) for kind, name in c.files.items()], cls="wide")
            + "</section>")
    crop_text = f"crop {','.join(map(str, region))}" if region else "whole image"
    layer_text = f"layer {esc(layer)} of the EXR inputs; " if layer else ""
    body = (f"<p>{layer_text}FLIP mode: {flip_mode.upper()}-FLIP; tone mapping for display: "
            f"{esc(operator)}; region: {crop_text}; thresholds: {esc(limits)}. All images and "
            f"error maps as layers of one EXR: <a href=\"maps.exr\">maps.exr</a>.</p>\n"
            f"{summary}\n{''.join(sections)}")
    return pages.page(f"Comparison against {ref_path}", body)


def _csv_rows(comparisons: list[Comparison]) -> Iterator[list]:
    yield ["test", "channel", *METRIC_ORDER, "verdict"]
    for c in comparisons:
        yield [c.test_path, "all", *[c.metrics[k] for k in METRIC_ORDER], c.verdict]
        for ch in CHANNELS:
            yield [c.test_path, ch, *[c.metrics["channels"][ch][k] for k in METRIC_ORDER[:-1]],
                   "", c.verdict]


def _write_text(path: str, write) -> None:
    with open(path, "w", newline="") as f:
        write(f)


def compare(reference: str, tests: list[str], out_dir: str, thresholds: dict | None = None,
            region: tuple[int, int, int, int] | None = None,
            operator: str = "clamp", flip_mode: str | None = None,
            mask_nonfinite: bool = False, layer: str | None = None) -> list[Comparison]:
    """Compare every test image with the reference and write the report to
    out_dir; ``layer`` picks a layer of the EXR inputs. Raises CompareError (bad input) or destinations.OutputError (a report
    folder that cannot be used) before comparing or writing anything."""
    thresholds = {k: v for k, v in (thresholds or {}).items() if v is not None}
    for key in thresholds:
        if key not in THRESHOLDS:
            raise CompareError(f"unknown threshold {key!r}; valid: {', '.join(THRESHOLDS)}")
    if operator not in tonemap.OPERATORS:
        raise CompareError(f"unknown tone-mapping operator {operator!r}")
    if flip_mode is not None and flip_mode not in FLIP_MODES:
        raise CompareError(f"unknown FLIP mode {flip_mode!r}; valid: {', '.join(FLIP_MODES)}")
    require_reports()
    inputs = [reference, *tests]
    for path in inputs:
        check_type(path)
    destinations.check_report_dir(out_dir, inputs)
    flip_mode = flip_mode or default_flip_mode(inputs)
    ldr = default_flip_mode(inputs) == "ldr"            # every input is PNG/JPEG

    full_ref = load(reference, layer)
    images = []
    for path in tests:
        image = load(path, layer)
        check_pair(full_ref, image, reference, path)
        images.append((path, image))
    if not mask_nonfinite:
        for path, image in [(reference, full_ref), *images]:
            refuse_nonfinite(image, path)
    ref = crop(full_ref, region)
    images = [(path, crop(image, region)) for path, image in images]

    comparisons, layers = [], {"reference": finite(ref)}
    ref_mask = nonfinite(ref)
    with destinations.report_dir(out_dir, "compare", inputs) as tmp:
        for i, (path, image) in enumerate(images):
            mask = (ref_mask | nonfinite(image)) if mask_nonfinite else None
            m = metrics(ref, image, with_flip=False, mask=mask,
                        peak=1.0 if ldr else psnr_peak(ref[~ref_mask]))
            m["flip"], flip_map = masked_flip(ref, image, flip_mode, mask)
            m["flip_mode"] = flip_mode
            c = Comparison(path, m, verdict(m, thresholds), thresholds=bool(thresholds))
            clean_ref, clean_test = finite(ref), finite(image)
            c.files = pictures(tmp, f"test{i}", clean_ref, clean_test, operator, flip_map)
            comparisons.append(c)
            layers[f"test{i}.image"] = clean_test
            layers[f"test{i}.difference"] = clean_test - clean_ref
            layers[f"test{i}.relative"] = np.abs(clean_test - clean_ref) / (np.abs(clean_ref) + 0.01)
            layers[f"test{i}.flip"] = flip_map
        write_layers(os.path.join(tmp, "maps.exr"), layers)
        _write_text(os.path.join(tmp, "metrics.json"), lambda f: json.dump(
            {"reference": reference, "layer": layer or "", "region": region,
             "thresholds": thresholds,
             "flip_mode": flip_mode, "psnr_peak": "1 (LDR inputs)" if ldr else "max(reference)",
             "mask_nonfinite": mask_nonfinite,
             "tests": [{"path": c.test_path, "verdict": c.verdict,
                        "passed": c.passed if thresholds else None,
                        "failures": c.failures, "metrics": c.metrics} for c in comparisons]},
            f, indent=2))
        _write_text(os.path.join(tmp, "metrics.csv"),
                    lambda f: csv.writer(f).writerows(_csv_rows(comparisons)))
        _write_text(os.path.join(tmp, "index.html"),
                    lambda f: f.write(_html(reference, comparisons, thresholds, operator, region,
                                            flip_mode, mask_nonfinite, layer)))
    return comparisons


def parse_region(text: str | None) -> tuple[int, int, int, int] | None:
    if not text:
        return None
    try:
        x, y, w, h = (int(v) for v in text.split(","))
    except ValueError:
        raise CompareError(f"--crop expects X,Y,W,H (integers), got {text!r}") from None
    return x, y, w, h
