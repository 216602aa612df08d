"""mi-brdfs bench --quick: every output, every group, finite numbers; the efficiency maths."""
import csv
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from mi_brdfs.tools import bench


def test_efficiency_by_hand():
    assert bench.efficiency(0.5, 2.0) == pytest.approx(1.0)
    assert bench.efficiency(0.01, 0.1) == pytest.approx(1000.0)
    assert bench.efficiency(0.0, 1.0) == math.inf
    # Halving the error at equal time doubles the efficiency.
    assert bench.efficiency(0.1, 1.0) / bench.efficiency(0.2, 1.0) == pytest.approx(2.0)


def test_relmse_by_hand():
    r = np.array([0.0, 1.0])
    t = np.array([0.01, 1.5])
    assert bench.relmse(t, r) == pytest.approx((0.01**2 / 0.01**2 + 0.25 / 1.01**2) / 2)
    assert bench.relmse(r, r) == 0


def test_split_of_spp_ladder_slope():
    # relMSE proportional to 1/spp has slope -1 in log-log.
    spp = np.array([1, 2, 4, 8])
    assert np.polyfit(np.log(spp), np.log(3.0 / spp), 1)[0] == pytest.approx(-1)


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench") / "out"
    cache = tmp_path_factory.mktemp("cache")
    run = subprocess.run([sys.executable, "-m", "mi_brdfs", "bench", "--quick", "-o", str(out),
                          "--cache", str(cache)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return out, json.loads((out / "results.json").read_text()), cache


def finite_numbers(rows):
    for row in rows:
        for k, v in row.items():
            if isinstance(v, float) and k != "efficiency":
                assert math.isfinite(v), (k, row)


def test_every_group_and_file(results):
    out, r, cache = results
    assert set(r["groups"]) == set(bench.GROUPS)
    for group, rows in r["groups"].items():
        assert rows, group
        finite_numbers(rows)
    for key in ("cpu", "cores", "variant", "mitsuba", "drjit"):
        assert r["machine"][key]
    for name in ("results.json", "results.csv", "README.md"):
        assert (out / name).stat().st_size > 0
    for plots in r["plots"].values():
        for p in plots:
            assert (out / p).exists()
    readme = (out / "README.md").read_text()
    assert all(f"## {g}" in readme for g in bench.GROUPS)
    rows = list(csv.reader(open(out / "results.csv")))
    assert rows[0] == ["group", "row", "key", "value"] and len(rows) > 50
    assert list(cache.glob("ref-*.exr"))              # references are cached


def test_self_comparisons_have_zero_error(results):
    _, r, _ = results
    exact = r["groups"]["oren_nayar"][0]
    assert exact["name"] == "exact" and exact["relmse_vs_exact"] == 0 and exact["max_abs_vs_exact"] == 0


def test_relations(results):
    _, r, _ = results
    g = r["groups"]
    assert next(m for m in g["models"] if m["name"] == "lambert")["relative_to_lambert"] == 1
    assert all(b["ratio"] > 0 for b in g["builtin"])
    assert g["convergence"][0]["slope"] < -0.5                 # error falls with spp
    tables = [o for o in g["oren_nayar"] if o["table_resolution"]]
    assert tables[-1]["relmse_vs_exact"] <= tables[0]["relmse_vs_exact"]   # finer table, less error


def test_pareto_by_hand():
    # (time, error): b is dominated by a (slower and worse); c and d trade off; e duplicates a.
    points = [(1.0, 0.1), (2.0, 0.2), (0.5, 0.5), (3.0, 0.01), (1.0, 0.1)]
    assert bench.pareto(points) == [True, False, True, True, True]


def test_dead_lobes_are_not_traced(results):
    _, r, _ = results
    rows = {row["name"]: row for row in r["groups"]["lobes"]}
    assert rows["cook_torrance k=1 vs lambert"]["diffuse_lobe"]
    assert not rows["cook_torrance k=1 vs lambert"]["glossy_lobe"]
    assert not rows["phong m_S=0 vs lambert"]["glossy_lobe"]
    assert not rows["ward m_D=0 vs ward m_D=0.5"]["diffuse_lobe"]
    assert rows["ward m_D=0 vs ward m_D=0.5"]["glossy_lobe"]
