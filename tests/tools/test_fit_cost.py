"""mi-brdfs fit's render cost and ranking (issue 26, points 2 and 3): the
interval is Student's t on the log ratios, two measurements of the same
models overlap (a loose bound: the bench shows the real spread), the counted
operations do not move between runs. (The ranking and the front:
test_fit_rank.py.) No timing is asserted."""
import math

import numpy as np
import pytest

from mi_brdfs.tools.fit import cost, rank, targets, task

SETTINGS = task.QUICK.replace(res=32, spp=4, cost_rounds=(4, 8), cost_tolerance=0.05, cost_spp=2)
T90_4 = 2.131847      # Student's t, 95th percentile, 4 degrees of freedom (tables)


def test_the_interval_is_students_t_on_the_log_ratios():
    ratios = [0.9, 1.1, 1.0, 0.95, 1.05]
    logs = np.log(ratios)
    half = T90_4 * np.std(logs, ddof=1) / math.sqrt(len(logs))
    mean, low, high = cost.interval(ratios)
    assert mean == pytest.approx(math.exp(np.mean(logs)))
    assert (low, high) == pytest.approx((math.exp(np.mean(logs) - half), math.exp(np.mean(logs) + half)))
    assert cost.interval([1.3])[1:] == (0.0, math.inf)         # one round: no interval


def measured(target: str, models: dict) -> dict:
    records = [{"target": target, "model": m, "parameters": p} for m, p in models.items()]
    cost.measure_costs(targets.parse([target])[0], records, SETTINGS)
    return {r["model"]: r for r in records}


MODELS = {"lambert": {"type": "lambert", "reflectance": [0.7, 0.5, 0.3]},
          "cook_torrance": {"type": "cook_torrance", "distribution": "ggx", "alpha": 0.2,
                            "diffuse_reflectance": [0.7, 0.5, 0.3]}}


def test_two_measurements_overlap_and_the_counts_repeat():
    first = measured("diffuse:reflectance=[0.7,0.5,0.3]", MODELS)
    second = measured("diffuse:reflectance=[0.7,0.5,0.3]", MODELS)
    loose = 1.5         # the intervals of a shared machine, widened by half
    for name in MODELS:
        a, b = first[name], second[name]
        assert "cost_error" not in a and "cost_error" not in b, (a, b)
        assert a["cost_low"] <= a["cost_ratio"] <= a["cost_high"]
        assert SETTINGS.cost_rounds[0] <= a["cost_rounds"] <= SETTINGS.cost_rounds[1]
        assert a["cost_low"] / loose <= b["cost_high"] * loose
        assert b["cost_low"] / loose <= a["cost_high"] * loose
        assert a["ops"] == b["ops"] and a["ops_ratio"] == b["ops_ratio"]
        assert a["cost_spp"] == 2                     # timed at cost_spp, not the views' spp
    # Cook-Torrance's traced eval and sample hold more operations than Lambert's.
    assert first["cook_torrance"]["ops"] > first["lambert"]["ops"]


def test_a_worker_that_fails_is_reported_not_raised():
    records = [{"target": "diffuse:", "model": "bad", "parameters": {"type": "lambert",
                                                                    "reflectance": -1.0}}]
    cost.measure_costs(targets.parse(["diffuse:"])[0], records, SETTINGS)
    assert records[0].get("cost_ratio") is None
    assert "reflectance" in records[0]["cost_error"]


def test_the_pairwise_cost_calls_that_changed_are_counted_by_cost_class():
    """cost.calls_changed over a remeasure's rows: classes round(log c / log
    1.05) before and again (a: 0 → 0, b: 1 → 1, c: −2 → 0), so only a
    against c changes (cheaper, then the same); a failed remeasure is left
    out and another target's models are not paired with these."""
    def row(target, model, before, again):
        return {"target": target, "model": model, "before": (before, None, None),
                "again": (again, None, None)}
    rows = [row("t", "a", 1.00, 1.00), row("t", "b", 1.03, 1.07), row("t", "c", 0.90, 1.00),
            row("t", "d", 0.50, None), row("u", "e", 5.0, 0.2), row("u", "f", 1.0, 1.0)]
    assert cost.calls_changed(rows) == (1 + 1, 3 + 1)      # u: e costlier, then cheaper


def fit(model, flip, c=None, lo=None, hi=None):
    return {"model": model, "image_flip": flip, "cost_ratio": c, "cost_low": lo, "cost_high": hi}


def test_compensation_is_counted_per_pair_fitted_both_ways():
    """trade.compensation_effect: a compensated fit is worse (or better) than
    the same model without compensation on the same material only beyond the
    ranking's tie; a model fitted one way only, or a failed fit, is no pair."""
    from mi_brdfs.tools.fit import trade
    rows = [("t:a", "phong", 0.10), ("t:a", "phong+ec", 0.20),      # worse
            ("t:a", "ward", 0.10), ("t:a", "ward+ec", 0.103),       # a tie
            ("t:b", "phong", 0.30), ("t:b", "phong+ec", 0.20),      # better
            ("t:b", "blinn+ec", 0.10)]                              # no pair
    records = [{**fit(m, flip), "target": t} for t, m, flip in rows]
    records.append({"target": "t:b", "model": "ward", "error": "boom"})
    records.append({**fit("ward+ec", 0.9), "target": "t:b"})
    assert trade.compensation_effect(records) == (1, 1, 3)
