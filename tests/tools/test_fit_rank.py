"""mi-brdfs fit's one comparison rule (issue 37): cost classes are a total
order (transitive), the first-ranked fit is on the Pareto front and is the
plot's star, the verdict's cheaper model looks the same as the best or the
verdict says none does, ties are broken the same way every time, and the
verdict says what the cost figures can bear. The properties are checked on
random records against the rule's definitions written out here, not against
the module's own helpers."""
import itertools
import json
import math
import pathlib
import random
import shutil

import pytest

from mi_brdfs.tools.fit import rank, task


def fit(model, flip, c=None, lo=None, hi=None, **extra):
    return {"model": model, "image_flip": flip, "cost_ratio": c, "cost_low": lo,
            "cost_high": hi, **extra}


def random_records(rng, n):
    rows = []
    for i in range(n):
        c = math.exp(rng.uniform(-0.4, 0.4))
        flip = rng.choice([0.05, 0.0501, 0.1, 0.2]) if rng.random() < 0.3 else rng.uniform(0, 0.3)
        rows.append(fit(f"m{i:02d}", flip, c, c / 1.03, c * 1.03, image_noise_flip=0.02))
    return rows


def test_cost_classes_are_a_total_order_with_a_5_percent_band():
    """Class n holds costs within 1.05^(n ± ½): checked against that
    definition, and "cheaper" and "equal" are transitive on every triple
    (overlapping intervals were not)."""
    rng = random.Random(1)
    rows = random_records(rng, 40)
    for r in rows:
        n = rank.cost_class(r)
        assert 1.05 ** (n - 0.5) <= r["cost_ratio"] * (1 + 1e-12)
        assert r["cost_ratio"] <= 1.05 ** (n + 0.5) * (1 + 1e-12)
    for a, b, c in itertools.permutations(rows[:15], 3):
        if rank.equal_cost(a, b) and rank.equal_cost(b, c):
            assert rank.equal_cost(a, c)
        if rank.cheaper(a, b) and not rank.cheaper(c, b):
            assert rank.cheaper(a, c)
        assert sum([rank.cheaper(a, b), rank.cheaper(b, a), rank.equal_cost(a, b)]) == 1
    assert math.isinf(rank.cost_class(fit("x", 0.1)))
    assert task.FULL.cost_tolerance == task.QUICK.cost_tolerance           # the timing's aim
    assert rank.aim({}) == rank.EARLIER_AIM == 1.05                  # records naming no aim


def test_the_first_ranked_fit_is_on_the_front_and_the_alternative_too():
    """On random records: the first-ranked fit is within the tie of the best
    FLIP and no other fit beats it in (cost class, FLIP); the alternative, when
    there is one, is in a lower class, within the tolerance of the best FLIP,
    and no fit beats it either; when there is none, no cheaper fit is within
    the tolerance."""
    rng = random.Random(2)
    for trial in range(200):
        rows = random_records(rng, rng.randint(1, 12))
        order = rank.ranked(rows)
        best_flip = min(r["image_flip"] for r in rows)
        first = order[0]
        assert first["image_flip"] <= best_flip + 0.005
        klass = {id(r): math.floor(math.log(r["cost_ratio"]) / math.log(1.05) + 0.5) for r in rows}

        def beaten(x):
            return any(klass[id(o)] <= klass[id(x)] and o["image_flip"] <= x["image_flip"]
                       and (klass[id(o)] < klass[id(x)] or o["image_flip"] < x["image_flip"])
                       for o in rows if o is not x)
        assert not beaten(first)
        assert first in rank.front(rows)
        assert all(not beaten(r) for r in rank.front(rows))
        assert all(beaten(r) for r in rows if r not in rank.front(rows))
        alt = rank.cheaper_alternative(order)
        same = [r for r in rows if klass[id(r)] < klass[id(first)]
                and r["image_flip"] <= best_flip + 0.02]
        if alt is None:
            assert not same
            assert "no cheaper model looks the same" in rank.verdict(rows, "p")
        else:
            assert alt in same and not beaten(alt)
            assert min(klass[id(r)] for r in same) == klass[id(alt)]
            assert f"{alt['model']} looks the same" in rank.verdict(rows, "p")


def test_ties_are_broken_the_same_way_whatever_the_order():
    """The blend's case: oren_nayar 1.01× and lambert 0.95× at FLIP 0.3185953
    and 0.3185955: lambert is cheaper (a lower class) and first; two fits
    equal in class and FLIP go by name; shuffling the records changes nothing."""
    rows = [fit("oren_nayar", 0.3185953, 1.01, 0.99, 1.03, image_noise_flip=0.02),
            fit("lambert", 0.3185955, 0.95, 0.93, 0.97, image_noise_flip=0.02),
            fit("b", 0.3185953, 1.0, 0.98, 1.02, image_noise_flip=0.02),
            fit("a", 0.3185953, 1.0, 0.98, 1.02, image_noise_flip=0.02)]
    names = [r["model"] for r in rank.ranked(rows)]
    assert names == ["lambert", "a", "b", "oren_nayar"]
    rng = random.Random(3)
    for _ in range(10):
        rng.shuffle(rows)
        assert [r["model"] for r in rank.ranked(rows)] == names
        assert [r["model"] for r in rank.front(rows)] == ["lambert", "a", "b", "oren_nayar"]


def test_the_verdict_names_a_cheaper_model_only_if_it_looks_the_same():
    """Gold's case: lambert is far cheaper but at FLIP 0.7 — not named; the
    closest cheaper model is said instead, with the tolerance. A cheaper
    model within the target's seed noise (0.02) of the best is named."""
    gold = [fit("ct", 0.05, 1.0, 0.98, 1.02, image_noise_flip=0.02),
            fit("blinn_ct", 0.30, 0.85, 0.83, 0.87, image_noise_flip=0.02),
            fit("lambert", 0.70, 0.60, 0.58, 0.62, image_noise_flip=0.02)]
    line = rank.verdict(gold, "roughconductor")
    assert line.startswith("ct: FLIP 0.050, 1.00× (0.98–1.02) the time per sample of roughconductor; "
                           "no cheaper model looks the same (within FLIP 0.020 of the best, "
                           "the target's seed noise): the closest cheaper one, blinn_ct, is at "
                           "FLIP 0.300")
    assert line.endswith("The records have no pixel variance (made before it was measured): "
                         "costs are time per sample, blind to a model's noisier sampling.")
    assert rank.cheaper_alternative(rank.ranked(gold)) is None
    plastic = gold + [fit("ggx_ct", 0.068, 0.80, 0.78, 0.82, image_noise_flip=0.02),
                      fit("phong", 0.071, 0.70, 0.68, 0.72, image_noise_flip=0.02)]
    assert rank.cheaper_alternative(rank.ranked(plastic))["model"] == "ggx_ct"   # 0.071 > 0.07
    assert "ggx_ct looks the same at 0.80× (0.78–0.82) the time per sample: FLIP 0.068, within " \
        "FLIP 0.020" in rank.verdict(plastic, "roughplastic")
    alone = [fit("lambert", 0.0, 1.0, 0.98, 1.02)]
    assert "none costs less" in rank.verdict(alone, "diffuse")
    assert rank.tolerance(alone) == rank.LOOKS_SAME


def test_the_verdict_says_when_the_timing_did_not_close_or_the_machine_was_loaded():
    """An interval wider than 1.10 after the round cap, and a load average
    above the cores, are said in words with the load; a quiet, closed timing
    gets only its load."""
    same = {"noise_ratio": 1.0, "noise_low": 1.0, "noise_high": 1.0}      # time per sample alone
    quiet = [fit("a", 0.05, 1.0, 0.98, 1.02, cost_load=0.4, cost_cores=2, cost_rounds=8, **same),
             fit("b", 0.30, 0.5, 0.49, 0.51, cost_load=0.6, cost_cores=2, cost_rounds=6, **same)]
    line = rank.verdict(quiet, "p")
    assert line.endswith(". Costs timed at load average 0.4–0.6 on 2 cores.")
    loaded = [fit("a", 0.05, 1.0, 0.90, 1.12, cost_load=5.2, cost_cores=2, cost_rounds=12,
                  cost_aim=1.1, **same),
              fit("b", 0.30, 0.5, 0.49, 0.51, cost_load=4.0, cost_cores=2, cost_rounds=6, **same)]
    line = rank.verdict(loaded, "p")
    assert "load average 4.0–5.2 on 2 cores (the machine was loaded" in line
    assert "a's interval did not close (high/low 1.244 after 12 rounds, aim ≤ 1.1)" in line
    assert rank.closed(fit("x", 0.1, 1.0, 0.99, 1.01)) and not rank.closed(
        fit("x", 0.1, 1.0, 0.96, 1.05))            # 1.094: above the aim of a record naming none
    assert rank.closed(fit("x", 0.1, 1.0, 0.96, 1.05, cost_aim=1.1))
    assert not rank.closed(fit("x", 0.1, 1.0, 0.95, 1.05, cost_aim=1.1))         # 1.105


@pytest.mark.parametrize("flips, expected", [((0.200, 0.102, 0.100), ["y", "z", "x"])])
def test_the_ranking_follows_flip_and_prefers_the_cheaper_of_a_tie(flips, expected):
    rows = [fit("x", flips[0], 1.0, 0.9, 1.05), fit("y", flips[1], 1.2, 1.1, 1.3),
            fit("z", flips[2], 2.0, 1.9, 2.1), {"model": "failed", "error": "boom"}]
    assert [r["model"] for r in rank.ranked(rows)] == expected     # 0.102 ties 0.100


def test_the_readme_table_names_the_first_model_and_a_cheaper_one_that_looks_the_same():
    """trade.summary, the README's table: per material the first-ranked model
    and the cheaper model that looks the same, or "none" with the closest
    cheaper one's FLIP; a material every fit of which failed says so."""
    from mi_brdfs.tools.fit import trade
    rows = [fit("x", 0.200, 1.0, 0.9, 1.05), fit("y", 0.102, 1.2, 1.1, 1.3),
            fit("z", 0.100, 2.0, 1.9, 2.1), fit("w", 0.115, 1.12, 1.08, 1.15),
            fit("v", 0.180, 0.5, 0.45, 0.55)]
    rows = [{**r, "target": "t:a", "image_noise_flip": 0.02} for r in rows]
    rows += [{**r, "target": "t:c", "model": r["model"], "image_flip": r["image_flip"] + 0.5
              if r["model"] != "y" else r["image_flip"]} for r in rows]
    rows += [{"target": "t:b", "model": "u", "error": "boom"}]
    lines = trade.summary(rows, {"t:a": "A"}).splitlines()
    assert lines[2] == ("| A | `y` | 0.102 | 1.20× (1.10–1.30) | "
                        "`w`: FLIP 0.115 at 1.12× (1.08–1.15) |")
    assert lines[3] == "| t:c | `y` | 0.102 | 1.20× (1.10–1.30) | none (closest: `w`, FLIP 0.615) |"
    assert lines[4] == "| t:b | every fit failed | – | – | – |"
    assert len(lines) == 5


COMMITTED = pathlib.Path(__file__).resolve().parents[2] / "docs" / "benchmarks" / "trade"


def test_on_the_committed_sweep_every_cheaper_model_looks_the_same_or_none_is_named():
    """Issue 37's "done": no cheaper suggestion beyond the tolerance (the
    material's seed noise, read here from the records), and every material
    has one or says why not."""
    from mi_brdfs.tools.fit import trade
    records = json.loads((COMMITTED / "fits.json").read_text())
    lines = trade.summary(records).splitlines()[2:]
    assert len(lines) == len({r["target"] for r in records})
    for line in lines:
        spec, cheaper = line.split(" | ")[0][2:], line.split(" | ")[-1][:-2]
        mine = {r["model"]: r for r in records if r["target"] == spec}
        best = min(r["image_flip"] for r in mine.values())
        noise = next(iter(mine.values()))["image_noise_flip"]
        if cheaper.startswith("none"):
            continue
        model = cheaper.split("`")[1]
        assert mine[model]["image_flip"] <= best + noise


def test_the_committed_trade_report_is_written_from_its_records(tmp_path):
    """trade.md, index.html and the ranks in fits.json are what the current
    ranking writes from the committed records
    (``python -m mi_brdfs.tools.fit.trade -o docs/benchmarks/trade --from-records``)."""
    from mi_brdfs.tools.fit import trade
    for path in [COMMITTED / "fits.json", *COMMITTED.glob("walk.json"),     # the run's own
                 *COMMITTED.glob("*__slices.png")]:
        shutil.copy(path, tmp_path / path.name)
    trade.rebuild(str(tmp_path))
    for name in ("trade.md", "index.html", "fits.json"):
        assert (tmp_path / name).read_text() == (COMMITTED / name).read_text(), (
            f"{name} is stale: python -m mi_brdfs.tools.fit.trade -o docs/benchmarks/trade "
            "--from-records")


def noisy(model, flip, per_sample, variance, spread=1.03, **extra):
    """A record with a time per sample and a variance, each with a 90 % interval."""
    return fit(model, flip, per_sample, per_sample / spread, per_sample * spread,
               noise_ratio=variance, noise_low=variance / 1.1, noise_high=variance * 1.1,
               image_noise_flip=0.02, **extra)


def test_the_time_to_noise_is_time_per_sample_times_variance_with_both_intervals():
    """Its interval: the two log half-widths added in quadrature (worked by hand)."""
    r = fit("a", 0.1, 1.0, 0.9, 1.2, noise_ratio=2.0, noise_low=1.6, noise_high=2.4)
    ratio, low, high = rank.time_to_noise(r)
    assert ratio == pytest.approx(2.0)
    assert low == pytest.approx(2.0 * math.exp(-math.sqrt(math.log(1 / 0.9) ** 2
                                                          + math.log(2 / 1.6) ** 2)))
    assert high == pytest.approx(2.0 * math.exp(math.sqrt(math.log(1.2) ** 2
                                                          + math.log(1.2) ** 2)))
    assert rank.time_to_noise(fit("b", 0.1, 1.0, 0.9, 1.2)) is None      # an old record
    assert rank.cost(fit("b", 0.1, 1.0, 0.9, 1.2)) == 1.0                # time per sample


def test_the_verdict_compares_time_to_noise_where_time_per_sample_disagrees():
    """'fast' renders a sample in 0.8× the target's time but with 3× its
    variance (2.4× the time to the same noise); 'own' takes 1.0× per sample
    at 1.0× the variance. They look the same (a FLIP tie): by time per sample
    'fast' would be first, the front's only point and the cheaper model; by
    time to noise 'own' is first, on the front with the ★, and 'fast' is
    neither cheaper nor on the front. 'lean' (0.9× per sample, 0.8× the
    variance: 0.72×) is the cheaper model that looks the same."""
    rows = [noisy("fast", 0.051, 0.8, 3.0), noisy("own", 0.050, 1.0, 1.0)]
    by_sample = [{k: v for k, v in r.items() if not k.startswith("noise")} for r in rows]
    assert [r["model"] for r in rank.ranked(by_sample)] == ["fast", "own"]
    assert [r["model"] for r in rank.ranked(rows)] == ["own", "fast"]
    assert [r["model"] for r in rank.front(rows)] == ["own"]
    assert rank.cheaper_alternative(rank.ranked(rows)) is None
    line = rank.verdict(rows, "p")
    assert line.startswith("own: FLIP 0.050, 1.00× (0.91–1.10) the time to the same noise of p "
                           "(1.00× (0.97–1.03) per sample, 1.00× the variance at equal samples)")
    assert "no cheaper model looks the same" in line and "pixel variance" not in line
    lean = rows + [noisy("lean", 0.060, 0.9, 0.8)]
    assert rank.cheaper_alternative(rank.ranked(lean))["model"] == "lean"
    assert "lean looks the same at 0.72× (0.65–0.80) the time to the same noise" in \
        rank.verdict(lean, "p")
