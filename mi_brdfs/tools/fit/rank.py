"""The answer per target: models ranked by what the image shows, the Pareto
front of image error against cost with the cost's interval, and a verdict
line a user can read.

**Ranking.** By ``image_flip``, the mean HDR-FLIP of the model's renders
against the target's over the standard views (:mod:`.scene`); fits within
``TIE_FLIP`` of the best FLIP count as equally good, and among those the
cheaper comes first (by ``cost_ratio``). Without renders, by the objective,
then the BRDF error.

**Cost** comparisons use the 90 % interval of each model's cost
(:mod:`.cost`): two models whose intervals overlap are equal in cost.

**Pareto front.** A model is on it unless another is at least as cheap
(cheaper: its interval entirely below; or equal in cost) with a lower image
error, or cheaper with an equal one.
"""
from __future__ import annotations

import math
import re

TIE_FLIP = 0.005           # FLIP differences below this count as equal
SMALL_FLIP = 0.05          # a best FLIP above this: no model is close; say why


def ok(records: list[dict]) -> list[dict]:
    return [r for r in records if "error" not in r]


def quality(r: dict) -> float:
    """The error the ranking reads: FLIP, else the objective, else the BRDF error."""
    for key in ("image_flip", "objective_error", "brdf_error"):
        v = r.get(key)
        if v is not None and math.isfinite(v):
            return float(v)
    return math.inf


def _cost(r: dict) -> float:
    c = r.get("cost_ratio")
    return c if c is not None and math.isfinite(c) else math.inf


def ranked(records: list[dict]) -> list[dict]:
    """The successful fits, best first (module docstring)."""
    fits = sorted(ok(records), key=quality)
    if not fits:
        return []
    best = quality(fits[0])
    ties = sorted((r for r in fits if quality(r) <= best + TIE_FLIP), key=lambda r: (_cost(r), quality(r)))
    return ties + [r for r in fits if quality(r) > best + TIE_FLIP]


def cheaper(a: dict, b: dict) -> bool:
    """a costs less than b beyond their intervals."""
    if a.get("cost_high") is None or b.get("cost_low") is None:
        return _cost(a) < _cost(b)
    return a["cost_high"] < b["cost_low"]


def equal_cost(a: dict, b: dict) -> bool:
    return not cheaper(a, b) and not cheaper(b, a)


def front(records: list[dict]) -> list[dict]:
    """The fits on the Pareto front of (cost, image error)."""
    fits = [r for r in ok(records) if r.get("cost_ratio") is not None]

    def dominates(a, b):
        qa, qb = quality(a), quality(b)
        return ((cheaper(a, b) and qa <= qb) or (equal_cost(a, b) and qa < qb))
    return [b for b in fits if not any(dominates(a, b) for a in fits if a is not b)]


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
    """Of the fits that cost less than the first-ranked one beyond the
    timing's noise, the best; None if there is none."""
    cheap = [r for r in order[1:] if cheaper(r, order[0])]
    return min(cheap, key=quality) if cheap else None


def cost_text(r: dict) -> str:
    """A fit's cost as the verdict and the README's table write it:
    ``0.96× (0.93–0.99)``."""
    if r.get("cost_ratio") is None:
        return "cost not measured"
    text = f"{r['cost_ratio']:.2f}×"
    if r.get("cost_low") is not None:
        text += f" ({r['cost_low']:.2f}–{r['cost_high']:.2f})"
    return text


def verdict(records: list[dict], plugin: str) -> str:
    """One line: the first-ranked model, its FLIP and cost against the
    target's plugin, and the best model that costs less beyond the noise."""
    order = ranked(records)
    if not order:
        return "every fit failed"
    best = order[0]
    if best.get("cost_ratio") is None:
        return f"{best['model']}: FLIP {quality(best):.3f} (render cost not measured)"
    line = (f"{best['model']}: FLIP {quality(best):.3f}, {cost_text(best)} the cost of {plugin}")
    alt = cheaper_alternative(order)
    if alt is not None:
        line += f"; {alt['model']} is {cost_text(alt)} the cost at FLIP {quality(alt):.3f}"
    elif best.get("cost_low") is not None:
        line += "; no model costs less beyond the noise of the timing"
    return line
