"""Compare linear EXR renders: metrics, pictures, a verdict, an HTML report.

    mi-brdfs compare REFERENCE.exr TEST.exr [TEST.exr ...] -o REPORT_DIR
                     [--max-rmse X] [--max-relmse X] [--max-mae X] [--max-flip X]
                     [--max-abs X] [--min-psnr DB] [--crop X,Y,W,H] [--tonemap NAME]

Metrics (r the reference, t the test, means over pixels and channels; each is
also given per channel):

=========  ===============================================================
mse        mean((t - r)²)
rmse       sqrt(mse)
relmse     mean((t - r)² / (r + 0.01)²)              (pbrt's relative MSE)
mae        mean(|t - r|)
smape      mean(2 |t - r| / (|t| + |r|)), 0 where both are 0
max_abs    max(|t - r|)
psnr       10 log10(peak² / mse), peak = max(r) (1 for an all-black r); inf if mse = 0
flip       mean FLIP error (NVIDIA flip-evaluator; HDR mode when r or t exceeds 1,
           else LDR mode on sRGB-encoded values)
=========  ===============================================================

The report directory holds ``index.html``, ``metrics.json``, ``metrics.csv`` and
the pictures as PNG files: both images tone-mapped the same way, the signed
difference (with a colour bar), the relative error and the FLIP error map. It
is written into a temporary directory beside REPORT_DIR and moved into place
only when complete. Exit status: 0 when every test image passes the thresholds,
3 when one fails, 1 on an error.
"""
from __future__ import annotations

import csv
import html
import json
import math
import os
import shutil
import tempfile
from dataclasses import dataclass, field

import numpy as np

from ..render import exr, tonemap

CHANNELS = "RGB"
THRESHOLDS = {            # option name -> (metric, comparison)
    "max_rmse": ("rmse", "<="),
    "max_relmse": ("relmse", "<="),
    "max_mae": ("mae", "<="),
    "max_abs": ("max_abs", "<="),
    "max_flip": ("flip", "<="),
    "min_psnr": ("psnr", ">="),
}


class CompareError(ValueError):
    """Bad input for a comparison (reported on one line)."""


# ----------------------------------------------------------------------------
#  Loading and checking
# ----------------------------------------------------------------------------

def load(path: str) -> np.ndarray:
    """An EXR as (H, W, 3) float64, refusing non-finite pixels."""
    if not os.path.exists(path):
        raise CompareError(f"no such file: {path}")
    try:
        image = exr.read_exr(path).astype(np.float64)
    except (ValueError, OSError) as error:
        raise CompareError(f"{path}: not a readable EXR file") from error
    bad = ~np.isfinite(image).all(axis=-1)
    if bad.any():
        nan = int(np.isnan(image).any(axis=-1).sum())
        raise CompareError(f"{path}: {int(bad.sum())} pixels are not finite "
                           f"({nan} NaN, {int(bad.sum()) - nan} Inf)")
    return image


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

def _errors(r: np.ndarray, t: np.ndarray, axis) -> dict:
    d = t - r
    mse = np.mean(d * d, axis=axis)
    denom = np.abs(t) + np.abs(r)
    smape_terms = np.where(denom > 0, 2 * np.abs(d) / np.where(denom > 0, denom, 1.0), 0.0)
    peak = np.max(r, axis=axis)
    peak = np.where(peak > 0, peak, 1.0)
    with np.errstate(divide="ignore"):
        psnr = np.where(mse > 0, 10 * np.log10(peak * peak / np.where(mse > 0, mse, 1.0)), np.inf)
    return {
        "mse": mse,
        "rmse": np.sqrt(mse),
        "relmse": np.mean(d * d / (r + 0.01) ** 2, axis=axis),
        "mae": np.mean(np.abs(d), axis=axis),
        "smape": np.mean(smape_terms, axis=axis),
        "max_abs": np.max(np.abs(d), axis=axis),
        "psnr": psnr,
    }


def flip(ref: np.ndarray, test: np.ndarray) -> tuple[float, np.ndarray, str]:
    """Mean FLIP error, the error map (H, W) and the mode used."""
    import flip_evaluator

    hdr = max(ref.max(), test.max()) > 1.0
    if hdr:
        error_map, mean, _ = flip_evaluator.evaluate(
            np.maximum(ref, 0).astype(np.float32), np.maximum(test, 0).astype(np.float32),
            "HDR", applyMagma=False)
    else:
        encode = lambda x: tonemap.srgb_encode(np.clip(x, 0, 1)).astype(np.float32)
        error_map, mean, _ = flip_evaluator.evaluate(encode(ref), encode(test), "LDR",
                                                     inputsRGB=True, applyMagma=False)
    return float(mean), np.asarray(error_map).reshape(ref.shape[:2]), "HDR" if hdr else "LDR"


def metrics(ref: np.ndarray, test: np.ndarray, with_flip: bool = True) -> dict:
    """Every metric, overall and per channel (plain floats)."""
    overall = {k: float(v) for k, v in _errors(ref, test, axis=None).items()}
    per = _errors(ref.reshape(-1, 3), test.reshape(-1, 3), axis=0)
    channels = {c: {k: float(v[i]) for k, v in per.items()} for i, c in enumerate(CHANNELS)}
    result = {**overall, "channels": channels}
    if with_flip:
        result["flip"], _, result["flip_mode"] = flip(ref, test)
    return result


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

def _save_map(path: str, data: np.ndarray, cmap: str, vmin: float, vmax: float, label: str) -> None:
    from matplotlib.figure import Figure    # no pyplot: no global backend change

    h, w = data.shape
    fig = Figure(figsize=(4.8, 4.8 * h / w + 0.3), dpi=100)
    ax = fig.subplots()
    im = ax.imshow(data, cmap=cmap, vmin=vmin, vmax=vmax, interpolation="nearest")
    ax.set_axis_off()
    fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04, label=label)
    fig.savefig(path, bbox_inches="tight")


def pictures(directory: str, prefix: str, ref: np.ndarray, test: np.ndarray,
             operator: str, flip_map: np.ndarray | None,
             ref_name: str = "reference.png") -> dict[str, str]:
    """Write the report's PNGs (the reference once, as ref_name); returns {kind: file name}."""
    files = {"reference": ref_name, "test": f"{prefix}_test.png"}
    if not os.path.exists(os.path.join(directory, files["reference"])):
        tonemap.write_png(os.path.join(directory, files["reference"]), ref, operator)
    tonemap.write_png(os.path.join(directory, files["test"]), test, operator)
    diff = (test - ref).mean(axis=-1)
    span = float(np.max(np.abs(diff))) or 1.0
    files["difference"] = f"{prefix}_difference.png"
    _save_map(os.path.join(directory, files["difference"]), diff, "RdBu_r", -span, span,
              "test − reference (channel mean)")
    rel = (np.abs(test - ref) / (np.abs(ref) + 0.01)).mean(axis=-1)
    files["relative"] = f"{prefix}_relative.png"
    _save_map(os.path.join(directory, files["relative"]), rel, "viridis", 0.0,
              float(rel.max()) or 1.0, "|t − r| / (r + 0.01)")
    if flip_map is not None:
        files["flip"] = f"{prefix}_flip.png"
        _save_map(os.path.join(directory, files["flip"]), flip_map, "magma", 0.0, 1.0, "FLIP")
    return files


# ----------------------------------------------------------------------------
#  The report
# ----------------------------------------------------------------------------

@dataclass
class Comparison:
    test_path: str
    metrics: dict
    failures: list[str]
    files: dict[str, str] = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return not self.failures


METRIC_ORDER = ["mse", "rmse", "relmse", "mae", "smape", "max_abs", "psnr", "flip"]


def _html(ref_path: str, comparisons: list[Comparison], thresholds: dict, operator: str,
          region) -> str:
    esc = html.escape
    rows = []
    for c in comparisons:
        status = "PASS" if c.passed else "FAIL"
        cells = "".join(f"<td>{c.metrics[k]:.6g}</td>" for k in METRIC_ORDER)
        rows.append(f"<tr class='{status.lower()}'><td>{esc(c.test_path)}</td>{cells}"
                    f"<td>{status}</td></tr>")
    header = "".join(f"<th>{k}</th>" for k in METRIC_ORDER)
    limits = ", ".join(f"{THRESHOLDS[k][0]} {THRESHOLDS[k][1]} {v:g}"
                       for k, v in thresholds.items() if v is not None) or "none"
    sections = []
    for c in comparisons:
        per = "".join(
            f"<tr><td>{ch}</td>" + "".join(f"<td>{c.metrics['channels'][ch][k]:.6g}</td>"
                                           for k in METRIC_ORDER[:-1]) + "</tr>"
            for ch in CHANNELS)
        figures = "".join(
            f"<figure><img src='{esc(name)}' alt='{kind}'><figcaption>{kind}</figcaption></figure>"
            for kind, name in c.files.items())
        failures = ("<p class='fail'>Failed: " + esc("; ".join(c.failures)) + "</p>"
                    if c.failures else "<p class='pass'>Passed every threshold.</p>")
        sections.append(
            f"<section><h2>{esc(c.test_path)}</h2>{failures}"
            f"<table><tr><th>channel</th>{''.join(f'<th>{k}</th>' for k in METRIC_ORDER[:-1])}</tr>"
            f"{per}</table><p>FLIP mode: {c.metrics['flip_mode']}</p>"
            f"<div class='figs'>{figures}</div></section>")
    crop_text = f"crop {','.join(map(str, region))}" if region else "whole image"
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>mi-brdfs compare</title>
<style>
body {{ font-family: sans-serif; margin: 2em; }}
table {{ border-collapse: collapse; margin: 1em 0; }}
td, th {{ border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: right; }}
tr.fail td:last-child, p.fail {{ color: #b00; font-weight: bold; }}
tr.pass td:last-child, p.pass {{ color: #070; }}
.figs {{ display: flex; flex-wrap: wrap; gap: 1em; }}
figure {{ margin: 0; }} figure img {{ width: 320px; image-rendering: pixelated; }}
</style></head><body>
<h1>Comparison against {esc(ref_path)}</h1>
<p>Tone mapping for display: {esc(operator)}; region: {crop_text}; thresholds: {esc(limits)}.</p>
<table><tr><th>test image</th>{header}<th>verdict</th></tr>{''.join(rows)}</table>
{''.join(sections)}
</body></html>
"""


def _csv_rows(comparisons: list[Comparison]):
    yield ["test", "channel", *METRIC_ORDER, "verdict"]
    for c in comparisons:
        status = "pass" if c.passed else "fail"
        yield [c.test_path, "all", *[c.metrics[k] for k in METRIC_ORDER], status]
        for ch in CHANNELS:
            yield [c.test_path, ch, *[c.metrics["channels"][ch][k] for k in METRIC_ORDER[:-1]],
                   "", status]


def compare(reference: str, tests: list[str], out_dir: str, thresholds: dict | None = None,
            region: tuple[int, int, int, int] | None = None,
            operator: str = "clamp") -> list[Comparison]:
    """Compare every test EXR with the reference and write the report to out_dir
    (atomically). Raises CompareError on bad input, before writing anything."""
    thresholds = {k: v for k, v in (thresholds or {}).items() if v is not None}
    for key in thresholds:
        if key not in THRESHOLDS:
            raise CompareError(f"unknown threshold {key!r}; valid: {', '.join(THRESHOLDS)}")
    if operator not in tonemap.OPERATORS:
        raise CompareError(f"unknown tone-mapping operator {operator!r}")
    full_ref = load(reference)
    ref = crop(full_ref, region)
    images = []
    for path in tests:
        image = load(path)
        check_pair(full_ref, image, reference, path)
        images.append((path, crop(image, region)))

    parent = os.path.dirname(os.path.abspath(out_dir)) or "."
    if not os.path.isdir(parent):
        raise CompareError(f"cannot write {out_dir}: directory {parent} does not exist")
    tmp = tempfile.mkdtemp(prefix=".tmp-report-", dir=parent)
    try:
        comparisons = []
        for i, (path, image) in enumerate(images):
            m = metrics(ref, image, with_flip=False)
            m["flip"], flip_map, m["flip_mode"] = flip(ref, image)
            c = Comparison(path, m, verdict(m, thresholds))
            c.files = pictures(tmp, f"test{i}", ref, image, operator, flip_map)
            comparisons.append(c)
        with open(os.path.join(tmp, "metrics.json"), "w") as f:
            json.dump({"reference": reference, "region": region, "thresholds": thresholds,
                       "tests": [{"path": c.test_path, "passed": c.passed,
                                  "failures": c.failures, "metrics": c.metrics}
                                 for c in comparisons]}, f, indent=2)
        with open(os.path.join(tmp, "metrics.csv"), "w", newline="") as f:
            csv.writer(f).writerows(_csv_rows(comparisons))
        with open(os.path.join(tmp, "index.html"), "w") as f:
            f.write(_html(reference, comparisons, thresholds, operator, region))
        _replace_dir(tmp, out_dir)
    finally:
        if os.path.isdir(tmp):
            shutil.rmtree(tmp)
    return comparisons


def _replace_dir(src: str, dst: str) -> None:
    """Move the finished report into place, replacing an older one."""
    if os.path.exists(dst):
        old = dst.rstrip("/") + ".old-" + os.path.basename(src)
        os.rename(dst, old)
        os.rename(src, dst)
        shutil.rmtree(old)
    else:
        os.rename(src, dst)


def parse_region(text: str | None):
    if not text:
        return None
    try:
        x, y, w, h = (int(v) for v in text.split(","))
    except ValueError:
        raise CompareError(f"--crop expects X,Y,W,H (integers), got {text!r}") from None
    return x, y, w, h
