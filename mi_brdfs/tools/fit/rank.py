"""The answer per target: models ranked by what the image shows, the Pareto
front of image error against cost, and a verdict line a user can read — all
from one comparison rule, written here once.

**Image error** (:func:`quality`): ``image_flip``, the mean HDR-FLIP of the
model's renders against the target's over the standard views (:mod:`.scene`);
without renders the objective, then the BRDF error. FLIP runs from 0
(identical) to 1 (the largest difference it measures).

**Cost** (:func:`cost`): what a user waits for, the time to render the
material as clean as its own plugin renders it, over the target's: the time
per sample (``cost_ratio``, :mod:`.cost`) × the variance at equal samples
(``noise_ratio``, :func:`.scene.variance_ratio`: each render's variance
relative to its own image) — a model with twice the variance needs twice the
samples for the same noise. Its 90 % interval
(:func:`time_to_noise`) adds the two figures' log half-widths in quadrature
(independent measurements, each interval about normal in the log). Records
without the variance (fits made before it was measured) fall back on the
time per sample, and the verdict says so (:func:`cost_name`).

**Cost class** (:func:`cost_class`): the cost put on a total order in
classes of :data:`COST_BAND`: class n holds the costs within a factor
1.05^(n ± ½) of the target's own, so class 0 is "as costly as the target".
Two models cost the same when their classes are equal and one is cheaper
when its class is lower: an equivalence and a total order, so "cheaper" and "equal" are transitive
(overlapping intervals were not: a ≈ b and b ≈ c with a < c). 5 % is about
what a time per sample moves between two runs; the intervals are wider (the
timing closes at high/low 1.10, the variance's 1.03–1.29), and the
report prints each beside its class: a class apart is an order, not a claim
beyond the noise. Two costs either side of a class's edge
fall into neighbouring classes however close they are, the price of a
transitive rule. An unmeasured cost is in no class (after every class).

**Order** (:func:`key`): fits compare by (cost class, image error, model
name); the name breaks the last ties, so every comparison is deterministic.

**Ranking** (:func:`ranked`): the fits whose image error is within
:data:`TIE_FLIP` of the best are equally good and come first, by :func:`key`
(the cheaper class first); the others follow by image error, then
:func:`key`.

**Pareto front** (:func:`front`): a fit is on it unless another is in a cost
class no higher with an image error no higher, and better in one of the two
(:func:`dominates`). The first-ranked fit is always on it: a fit that
dominated it would be within the tie too, and before it by :func:`key`.

**Looks the same** (:func:`tolerance`): a fit whose image error is within the
tolerance of the best fit's looks like it. The tolerance is the target's seed
noise — the FLIP between two renders of the target itself at different
seeds (``image_noise_flip``, a few hundredths of FLIP's range): a model no
further from the best than that differs from it by less than rendering the
target again does. Without renders, :data:`LOOKS_SAME`.

**The cheaper model that looks the same** (:func:`cheaper_alternative`): of
the fits in a lower cost class than the first-ranked one that look the same
as the best, the first by :func:`key` (the cheapest, then the best). On the
front by the same argument as the first-ranked fit.

**Verdict** (:func:`verdict`): the first-ranked fit with its cost (the time
to the same noise, and the time per sample and the variance it is made of),
the cheaper model that looks the same with the tolerance, or "no cheaper
model looks the same" and the closest cheaper fit; then what the cost figures can bear
(:func:`cost_caveat`): the load average they were timed at, whether it
exceeded the cores, and which named fit's interval did not close; for
records without the variance, that their costs are time per sample.
"""
from __future__ import annotations

import math
import re

TIE_FLIP = 0.005           # FLIP differences below this count as equal in the ranking
SMALL_FLIP = 0.05          # a best FLIP above this: no model is close; say why
COST_BAND = 0.05           # the width of a cost class: a factor 1.05
LOOKS_SAME = 0.02          # the tolerance without renders (the sweep's seed noise: 0.014-0.030)
EARLIER_AIM = 1.05         # the aim of records that do not name theirs (timed before cost_aim)


def ok(records: list[dict]) -> list[dict]:
    return [r for r in records if "error" not in r]


def quality(r: dict) -> float:
    """The error the ranking reads: FLIP, else the objective, else the BRDF error."""
    for field in ("image_flip", "objective_error", "brdf_error"):
        v = r.get(field)
        if v is not None and math.isfinite(v):
            return float(v)
    return math.inf


def _finite(v) -> bool:
    return v is not None and math.isfinite(v) and v > 0


def time_to_noise(r: dict) -> tuple[float, float, float] | None:
    """(ratio, low, high): the time to the target's noise over the target's,
    ``cost_ratio`` × ``noise_ratio``, with the 90 % interval of the two
    combined (module docstring); None without both figures."""
    c, v = r.get("cost_ratio"), r.get("noise_ratio")
    if not (_finite(c) and _finite(v)):
        return None
    ratio = c * v
    low = math.hypot(_half(c, r.get("cost_low")), _half(v, r.get("noise_low")))
    high = math.hypot(_half(c, r.get("cost_high")), _half(v, r.get("noise_high")))
    return ratio, ratio * math.exp(-low), ratio * math.exp(high)


def _half(mid: float, end) -> float:
    """An interval end's distance from its figure in the log; inf if unknown."""
    return abs(math.log(end / mid)) if end is not None and 0 < end < math.inf else math.inf


def cost_name(r: dict) -> str:
    """What :func:`cost` reads for r: "time to the same noise", or "time per
    sample" when the record has no variance."""
    return "time to the same noise" if time_to_noise(r) is not None else "time per sample"


def cost(r: dict) -> float:
    """The cost the verdict compares: the time to the same noise, else the
    time per sample (module docstring); inf when neither was measured."""
    t = time_to_noise(r)
    if t is not None:
        return t[0]
    c = r.get("cost_ratio")
    return c if _finite(c) else math.inf


def cost_interval(r: dict) -> tuple[float, float | None, float | None]:
    """:func:`cost` with its 90 % interval (the ends None when unknown)."""
    t = time_to_noise(r)
    return t if t is not None else (cost(r), r.get("cost_low"), r.get("cost_high"))


def cost_class(r: dict) -> float:
    """The fit's cost class (module docstring): round(log(cost) / log(1.05));
    inf when the cost was not measured."""
    c = cost(r)
    return math.inf if math.isinf(c) else float(round(math.log(c) / math.log(1.0 + COST_BAND)))


def key(r: dict) -> tuple:
    """The one order every comparison uses: cost class, image error, name."""
    return (cost_class(r), quality(r), r.get("model", ""))


def cheaper(a: dict, b: dict) -> bool:
    """a is in a lower cost class than b."""
    return cost_class(a) < cost_class(b)


def equal_cost(a: dict, b: dict) -> bool:
    """a and b are in the same cost class."""
    return cost_class(a) == cost_class(b)


def ranked(records: list[dict]) -> list[dict]:
    """The successful fits, best first (module docstring)."""
    fits = ok(records)
    if not fits:
        return []
    best = min(quality(r) for r in fits)
    tie = [r for r in fits if quality(r) <= best + TIE_FLIP]
    rest = [r for r in fits if quality(r) > best + TIE_FLIP]
    return sorted(tie, key=key) + sorted(rest, key=lambda r: (quality(r),) + key(r))


def dominates(a: dict, b: dict) -> bool:
    """a is in a cost class no higher than b's with an image error no higher,
    and better in one of the two."""
    ca, cb, qa, qb = cost_class(a), cost_class(b), quality(a), quality(b)
    return ca <= cb and qa <= qb and (ca < cb or qa < qb)


def front(records: list[dict]) -> list[dict]:
    """The fits with a measured cost on the Pareto front of (cost class,
    image error), by :func:`key`."""
    fits = [r for r in ok(records) if not math.isinf(cost_class(r))]
    return sorted((b for b in fits if not any(dominates(a, b) for a in fits if a is not b)),
                  key=key)


def tolerance(records: list[dict]) -> float:
    """How far from the best FLIP a fit still looks the same: the target's
    seed noise, else :data:`LOOKS_SAME` (module docstring)."""
    noise = [r["image_noise_flip"] for r in ok(records) if r.get("image_noise_flip") is not None]
    return float(noise[0]) if noise else LOOKS_SAME


def tolerance_text(records: list[dict]) -> str:
    """The tolerance and where it comes from, as the reports state it."""
    seeded = any(r.get("image_noise_flip") is not None for r in ok(records))
    return (f"FLIP {tolerance(records):.3f} of the best"
            + (", the target's seed noise" if seeded else ""))


def looks_the_same(r: dict, records: list[dict]) -> bool:
    """r's image error is within :func:`tolerance` of the best fit's."""
    fits = ok(records)
    return bool(fits) and quality(r) <= min(map(quality, fits)) + tolerance(records)


def target_plugin(spec: str) -> str:
    """The target's plugin name, from its shorthand or from the XML file it names."""
    if spec.lower().endswith(".xml"):
        try:
            with open(spec, encoding="utf-8") as f:
                found = re.search(r'<bsdf[^>]*type="([^"]+)"', f.read())
        except OSError:
            found = None
        return found.group(1) if found else "the target"
    return spec.split(":", 1)[0]


def cheaper_alternative(order: list[dict]) -> dict | None:
    """The cheapest fit in a lower cost class than the first-ranked one whose
    image looks the same as the best's (module docstring); None if there is none."""
    if not order:
        return None
    same = [r for r in order if cheaper(r, order[0]) and looks_the_same(r, order)]
    return min(same, key=key) if same else None


def closest_cheaper(order: list[dict]) -> dict | None:
    """Of the fits in a lower cost class than the first-ranked one, the one
    with the lowest image error (then by :func:`key`); None if none costs less."""
    cheap = [r for r in order[1:] if cheaper(r, order[0])]
    return min(cheap, key=lambda r: (quality(r),) + key(r)) if cheap else None


def times(x: float) -> str:
    """A ratio to two decimals, or to two significant digits below 0.1
    (a time to noise can be a hundredth of the target's)."""
    return f"{x:.2f}" if x >= 0.095 or x == 0 else f"{x:.2g}"


def _interval_text(ratio: float, low, high) -> str:
    text = f"{times(ratio)}×"
    if low is not None and high is not None:
        text += f" ({times(low)}–{times(high)})"
    return text


def sample_text(r: dict) -> str:
    """A fit's time per sample with its interval: ``0.96× (0.93–0.99)``."""
    if r.get("cost_ratio") is None:
        return "cost not measured"
    return _interval_text(r["cost_ratio"], r.get("cost_low"), r.get("cost_high"))


def cost_text(r: dict) -> str:
    """A fit's :func:`cost` as the verdict and the README's table write it:
    the time to the same noise with its interval, ``1.32× (1.20–1.45)``, else
    the time per sample's."""
    t = time_to_noise(r)
    return sample_text(r) if t is None else _interval_text(*t)


def aim(r: dict) -> float:
    """The high/low the record's timing aimed at: its ``cost_aim``, else
    :data:`EARLIER_AIM` (the aim when records did not name it)."""
    return r.get("cost_aim") or EARLIER_AIM


def closed(r: dict) -> bool:
    """The timing's interval reached high/low ≤ :func:`aim` (the record's
    ``cost_closed`` where the run wrote it)."""
    if r.get("cost_closed") is not None:
        return bool(r["cost_closed"])
    low, high = r.get("cost_low"), r.get("cost_high")
    return low is not None and high is not None and low > 0 and high / low <= aim(r) + 1e-9


def cost_caveat(records: list[dict], named: list[dict]) -> str:
    """What the cost figures can bear, in words: the load average the fits
    were timed at (and whether it exceeded the cores), and which of the
    ``named`` fits' intervals did not close; empty if nothing was timed."""
    timed = [r for r in ok(records) if r.get("cost_load") is not None]
    if not timed:
        return ""
    loads = [r["cost_load"] for r in timed]
    span = f"{min(loads):.1f}" if max(loads) - min(loads) < 0.05 else \
        f"{min(loads):.1f}–{max(loads):.1f}"
    text = f"costs timed at load average {span}"
    cores = next((r["cost_cores"] for r in timed if r.get("cost_cores")), None)
    if cores:
        text += f" on {cores} cores"
        if max(loads) > cores:
            text += " (the machine was loaded: the costs are less sure than their intervals say)"
    open_ = [r for r in named if r.get("cost_low") is not None and not closed(r)]
    if open_:
        text += "; " + "; ".join(
            f"{r['model']}'s interval did not close (high/low {r['cost_high'] / r['cost_low']:.3f}"
            f" after {r.get('cost_rounds', '?')} rounds, aim ≤ {aim(r):g})" for r in open_)
    return text


def verdict(records: list[dict], plugin: str) -> str:
    """The first-ranked model, its FLIP and cost against the target's plugin;
    the cheaper model that looks the same, or that none does and the closest
    cheaper one; what the cost figures can bear (:func:`cost_caveat`)."""
    order = ranked(records)
    if not order:
        return "every fit failed"
    best = order[0]
    if best.get("cost_ratio") is None:
        return f"{best['model']}: FLIP {quality(best):.3f} (render cost not measured)"
    what = cost_name(best)
    line = f"{best['model']}: FLIP {quality(best):.3f}, {cost_text(best)} the {what} of {plugin}"
    if time_to_noise(best) is not None:
        line += (f" ({sample_text(best)} per sample, {times(best['noise_ratio'])}× the variance "
                 "at equal samples)")
    tol = tolerance_text(order)
    alt = cheaper_alternative(order)
    named = [best]
    if alt is not None:
        named.append(alt)
        line += (f"; {alt['model']} looks the same at {cost_text(alt)} the {cost_name(alt)}: "
                 f"FLIP {quality(alt):.3f}, within {tol}")
    else:
        closest = closest_cheaper(order)
        line += f"; no cheaper model looks the same (within {tol})"
        if closest is not None:
            line += (f": the closest cheaper one, {closest['model']}, is at FLIP "
                     f"{quality(closest):.3f}")
        else:
            line += ": none costs less"
    caveat = cost_caveat(order, named)
    if what == "time per sample":
        caveat = ("the records have no pixel variance (made before it was measured): costs are "
                  "time per sample, blind to a model's noisier sampling"
                  + (f"; {caveat}" if caveat else ""))
    return line + (f". {caveat[0].upper()}{caveat[1:]}." if caveat else "")
