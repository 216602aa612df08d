"""mi-brdfs bench --quick: every output, every group, finite numbers; a smoke
test that says so; the report-folder rule; the efficiency maths."""
import csv
import json
import math
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from mi_brdfs.bsdfs import BY_NAME
from mi_brdfs.bsdfs import cases
from mi_brdfs.bsdfs.compensation import AlbedoSpec
from mi_brdfs.tools import bench, cli
from mi_brdfs.tools.analysis import BSDF_METHODS, bsdf_inputs
from mi_brdfs.tools.bench import anatomy

# cook_torrance as roughconductor, GGX: the twin the tracing checks look into
GGX = next(t for t in cases.twins() if t.ours.get("distribution") == "ggx")


def test_efficiency_by_hand():
    assert bench.efficiency(0.5, 2.0) == pytest.approx(1.0)
    assert bench.efficiency(0.01, 0.1) == pytest.approx(1000.0)
    assert bench.efficiency(0.0, 1.0) == math.inf
    # Halving the error at equal time doubles the efficiency.
    assert bench.efficiency(0.1, 1.0) / bench.efficiency(0.2, 1.0) == pytest.approx(2.0)


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
    assert "smoke test" in run.stdout and "not measurements" in run.stdout
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
    assert all(f"## {bench.report.title(g)}" in readme for g in bench.GROUPS)
    assert "| name |" not in readme and "_s |" not in readme       # headers in words
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


def test_dead_lobes_are_not_traced(results):
    _, r, _ = results
    rows = {row["name"]: row for row in r["groups"]["lobes"]}
    assert rows["cook_torrance k=1 vs lambert"]["diffuse_lobe"]
    assert not rows["cook_torrance k=1 vs lambert"]["glossy_lobe"]
    assert not rows["phong m_S=0 vs lambert"]["glossy_lobe"]
    assert not rows["ward m_D=0 vs ward m_D=0.5"]["diffuse_lobe"]
    assert rows["ward m_D=0 vs ward m_D=0.5"]["glossy_lobe"]


def test_spheres_scene_has_one_material_per_sphere():
    import mitsuba as mi
    d = bench.spheres_scene(GGX.label, "plugin", 7, 8)
    spheres = [v for k, v in d.items() if k.startswith("sphere")]
    assert len(spheres) == 7
    assert len({s["bsdf"]["alpha"] for s in spheres}) == 7          # seven different materials
    assert len(mi.load_dict(d, parallel=False).shapes()) == 7


def test_materials_each_kind_and_count_in_its_own_process(results):
    _, r, _ = results
    rows = r["groups"]["materials"]
    spread = [t for t in cases.twins() if t.spread is not None]
    assert {(row["name"], row["materials"]) for row in rows} == {
        (f"{t.ours['type']} vs {t.builtin['type']}", n) for t in spread
        for n in bench.QUICK.materials}
    floors = {f"{t.ours['type']} vs {t.builtin['type']}": t.floor["type"] for t in spread}
    for row in rows:
        assert row["floor"] == floors[row["name"]]
        assert row["warm_vs_floor"] > 0 and row["floor_warm_ratio"] > 0
        for side in ("plugin", "builtin", "floor"):
            assert row[f"{side}_peak_mib"] > 10                     # measured by the child
            assert row[f"{side}_first_s"] >= row[f"{side}_first_codegen_s"] > 0
            assert row[f"{side}_execution_s"] > 0
            assert row[f"{side}_frozen_s"] > 0
            assert row[f"{side}_frozen_recordings"] == 1             # then replayed


def test_frozen_passes_replay(results):
    _, r, _ = results
    rows = r["groups"]["frozen"]
    assert {(row["passes"], row["frozen"]) for row in rows} == (
        {(1, False)} | {(p, f) for p in bench.QUICK.frozen_passes[1:] for f in (False, True)})
    for row in rows:
        if row["frozen"]:
            assert row["note"] == (f"{row['passes']} passes frozen: 1 traced, "
                                   f"{row['passes'] - 1} replayed")
    assert next(row for row in rows if row["passes"] == 1)["first_vs_1_pass"] == 1


def test_kernels_and_tracing_every_pair_and_method(results):
    _, r, _ = results
    pairs = {t.label for t in cases.twins()}
    related = {label for label, _, _ in cases.every("related")}
    for group, names in (("kernels", pairs), ("tracing", pairs | related)):
        rows = r["groups"][group]
        assert {(row["name"], row["method"]) for row in rows} == {
            (n, m) for n in names for m in BSDF_METHODS}
        assert all(row["ratio"] > 0 for row in rows)
    assert all(row["plugin_ops"] > 0 and row["builtin_ops"] > 0 for row in r["groups"]["kernels"])
    tracing = {(row["name"], row["method"]): row for row in r["groups"]["tracing"]}
    ggx = GGX.label
    sample = tracing[(ggx, "sample")]
    # The path tracer calls sample and eval_pdf; the plugin's sample evaluates
    # its lobes at the sampled direction without calling eval or pdf again, and
    # each texture once (GGX conductor: specular_reflectance and alpha).
    assert sample["render_calls"] >= 1
    assert tracing[(ggx, "eval_pdf")]["render_calls"] >= 1
    assert sample["inner_calls"] == "" and sample["texture_evals"] == 2
    # The floor (a bare Python BSDF) beside the pairs that have one, and the
    # Dr.Jit variables every call creates, plugin and built-in alike.
    for (name, method), row in tracing.items():
        assert ("floor_ms" in row) == (name in {t.label for t in cases.twins() if t.floor})
        assert row["plugin_vars"] > 0 and row["builtin_vars"] > 0
        if "floor_ms" in row:
            assert row["floor_ms"] > 0 and row["floor_vars"] > 0 and row["ms_vs_floor"] > 0


def test_energy_compensation_costed_per_model(results):
    """Every compensated model, on against off, and the build of each table it uses."""
    import mitsuba as mi
    _, r, _ = results
    rows = {row["name"]: row for row in r["groups"]["energy"]}
    energy = cases.every("energy")
    assert set(rows) == {name for name, _ in energy}
    assert {config["type"] for _, config in energy} == {
        name for name, cls in BY_NAME.items() if cls.compensable}
    for name, config in energy:
        row = rows[name]
        assert row["on_s"] > 0 and row["off_s"] > 0
        compensation = mi.load_dict(config).compensation()
        table = getattr(compensation, "table", None)
        spec = next(t for t in table.specs if isinstance(t, AlbedoSpec)) if table else None
        if getattr(compensation, "directional", False):   # the pair table, not built here
            assert row["table"] == compensation.pairs.specs[0].name
            assert row["table_build_s"] == 0 and row["separable_s"] > 0
        elif spec is None:                            # EON: analytic albedo
            assert row["table"] == "(analytic)" and row["table_build_s"] == 0
        else:
            assert row["table"] == spec.name and row["table_build_s"] > 0
            assert row["table_nodes"] == np.prod([a.n for a in spec.axes])


@pytest.mark.parametrize("floor, builtin", [
    ({"type": "bench_floor_ggx", "alpha": 0.3},
     {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3}),
    ({"type": "bench_floor_diffuse", "reflectance": 0.6}, {"type": "diffuse", "reflectance": 0.6})])
def test_the_floor_is_the_builtins_bsdf(floor, builtin):
    """The floor measured beside the plugins is the built-in's BSDF in bare
    Python: the same eval and pdf, and samples whose weight is eval / pdf."""
    import mitsuba as mi

    from mi_brdfs.tools.bench import floor as floors
    floors.register()
    x = bsdf_inputs(4096)
    ours, ref = mi.load_dict(floor), mi.load_dict(builtin)
    for a, b in zip(ours.eval_pdf(x["ctx"], x["si"], x["wo"]),
                    ref.eval_pdf(x["ctx"], x["si"], x["wo"])):
        np.testing.assert_allclose(np.array(a), np.array(b), rtol=1e-5, atol=1e-6)
    bs, weight = ours.sample(x["ctx"], x["si"], x["sample1"], x["sample2"])
    value, pdf = ours.eval_pdf(x["ctx"], x["si"], bs.wo)
    ok = np.array(weight)[0] > 0
    assert ok.mean() > 0.8
    np.testing.assert_allclose(np.array(bs.pdf)[ok], np.array(pdf)[ok], rtol=1e-4)
    np.testing.assert_allclose(np.array(weight)[:, ok] * np.array(pdf)[ok],
                               np.array(value)[:, ok], rtol=1e-4, atol=1e-7)


def test_peak_memory_is_the_workers_own():
    """A worker forked from a large process reports its own peak resident
    memory, not its parent's (ru_maxrss inherits the parent's at fork: a full
    bench run once reported 397 MiB for every kind and count)."""
    ballast = np.ones(64 * 1024 * 1024 // 8 * 8)          # 512 MiB resident in this process
    own = bench.in_subprocess("materials", twin="lambert vs diffuse", side="builtin", n=1,
                              res=8, spp=1, repeats=1)
    assert ballast.sum() > 0 and own["peak_mib"] < 400, own["peak_mib"]


# ----------------------------------------------------------------------------
#  A smoke test that says so; every group's finding and plots
# ----------------------------------------------------------------------------

def test_quick_is_a_smoke_test_without_findings(results):
    """Quick numbers flip between runs ("every model within 1.10x of lambert",
    then 3.72x): a quick run draws no conclusions and says why."""
    out, r, _ = results
    assert r["smoke_test"] is True and r["findings"] == []
    readme = (out / "README.md").read_text()
    assert "smoke test" in readme and "not measurements" in readme
    assert "## Findings" not in readme and "within" not in readme


def test_every_group_has_its_finding_and_plots(results, tmp_path):
    """What a full run writes, from the quick run's rows (the same columns):
    a finding per group that has one, each plot a PNG file."""
    _, r, _ = results
    for name, group in bench.GROUPS.items():
        rows = r["groups"][name]
        if group.finding:
            finding = group.finding(rows)
            assert isinstance(finding, str) and len(finding) > 40, name
        if group.plots:
            for png in bench.plots.save(str(tmp_path), group.plots(rows)):
                assert (tmp_path / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert group.about, f"{name}: its runner says what it measures"


def test_trade_fits_into_a_subfolder_the_marker_lists(results):
    """The trade group runs mi-brdfs fit (quick: one material, two models) into
    trade/, a fit report of its own, and the bench's marker lists its files."""
    out, r, _ = results
    rows = r["groups"]["trade"]
    assert {row["model"] for row in rows} == set(bench.QUICK.trade_models)
    assert all(not row["failed"] and 0 <= row["brdf_error"] <= 1.5 for row in rows)
    fits = json.loads((out / "trade" / "fits.json").read_text())
    assert [f["model"] for f in fits] == [row["model"] for row in rows]
    listed = json.loads((out / ".mi-brdfs-report").read_text())["files"]
    assert "trade/fits.json" in listed and "trade/index.html" in listed
    assert all((out / name).is_file() for name in listed)


# ----------------------------------------------------------------------------
#  The report folder, the dependencies: refused before any work
# ----------------------------------------------------------------------------

def refused(args, capsys) -> str:
    """Run mi-brdfs bench in this process; its one error line (exit status 1)."""
    assert cli.main(["bench", "--quick", *args]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mi-brdfs bench: error: "), err
    assert "bench: builtin" not in "".join(err)                   # no group started
    return err[0]


def test_a_folder_of_the_users_is_refused_and_untouched(tmp_path, capsys, monkeypatch):
    """``bench -o .`` in a folder holding a README.md and a results.csv (which a
    bench report would write) is refused before any work; nothing is touched."""
    (tmp_path / "README.md").write_text("mine")
    (tmp_path / "results.csv").write_text("a,b\n")
    cache = tmp_path.parent / f"{tmp_path.name}-cache"
    monkeypatch.chdir(tmp_path)
    line = refused(["-o", ".", "--cache", str(cache)], capsys)
    assert "holding other files (README.md, results.csv)" in line and "nothing was written" in line
    assert sorted(os.listdir(tmp_path)) == ["README.md", "results.csv"] and not cache.exists()
    assert (tmp_path / "README.md").read_text() == "mine"


def test_a_cache_inside_the_report_folder_is_refused(tmp_path, capsys):
    line = refused(["-o", str(tmp_path / "out"), "--cache", str(tmp_path / "out" / "cache")], capsys)
    assert "holds the input" in line
    assert not (tmp_path / "out").exists()


def test_an_unknown_group_is_refused(tmp_path, capsys):
    line = refused(["--only", "builtin,nonesuch", "-o", str(tmp_path / "out")], capsys)
    assert "unknown bench group 'nonesuch'; valid: builtin, models," in line
    assert not (tmp_path / "out").exists()


def bench_quick(*args) -> None:
    assert cli.main(["bench", "--quick", "-q", *args]) == 0


def read_report(folder):
    """A bench report's results, its marker's files, README and csv groups."""
    results = json.loads((folder / "results.json").read_text())
    listed = json.loads((folder / ".mi-brdfs-report").read_text())["files"]
    groups = {row[0] for row in list(csv.reader(open(folder / "results.csv")))[1:]}
    return results, listed, (folder / "README.md").read_text(), groups


def test_a_partial_run_keeps_the_other_groups(tmp_path):
    """bench --only GROUP into a previous bench report replaces that group and
    keeps every other one: rows, plots, the files of a group's folder (the
    trade sweep's trade/) and the findings' source rows; results.csv and
    README.md are written again from the merged rows. (``--only explore``
    into docs/benchmarks once deleted every other group and trade/.)"""
    out, cache = tmp_path / "report", str(tmp_path / "cache")
    bench_quick("--only", "convergence", "-o", str(out), "--cache", cache)
    first, _, _, _ = read_report(out)
    png = (out / "convergence.png").read_bytes()
    (out / "trade").mkdir()                        # a group's folder the marker lists
    (out / "trade" / "fits.json").write_text("[]")
    marker = json.loads((out / ".mi-brdfs-report").read_text())
    marker["files"].append("trade/fits.json")
    (out / ".mi-brdfs-report").write_text(json.dumps(marker))

    bench_quick("--only", "scaling", "-o", str(out), "--cache", cache)
    r, listed, readme, csv_groups = read_report(out)
    assert list(r["groups"]) == ["convergence", "scaling"] == sorted(csv_groups)
    assert r["groups"]["convergence"] == first["groups"]["convergence"]
    assert (out / "convergence.png").read_bytes() == png
    assert (out / "trade" / "fits.json").read_text() == "[]"
    assert {"convergence.png", "scaling.png", "trade/fits.json"} <= set(listed)
    assert all((out / name).is_file() for name in listed)
    assert [list(run["group_seconds"]) for run in r["runs"]] == [["convergence"], ["scaling"]]
    assert all(f"## {bench.report.title(g)}" in readme for g in ("convergence", "scaling"))
    assert "from 2 runs" in readme and r["smoke_test"] and r["findings"] == []

    # the group run again: its rows replaced, its old run gone, the other kept
    bench_quick("--only", "convergence", "-o", str(out), "--cache", cache)
    r, listed, _, _ = read_report(out)
    assert [list(run["group_seconds"]) for run in r["runs"]] == [["scaling"], ["convergence"]]
    assert list(r["groups"]) == ["convergence", "scaling"] and "trade/fits.json" in listed


def test_merge_brings_another_reports_groups(tmp_path, capsys):
    """bench --merge REPORT runs nothing: it brings REPORT's groups (rows,
    plots, runs) into -o's report, which keeps its own other groups; a report
    written before runs were recorded (no "runs") is one run."""
    a, b, cache = tmp_path / "a", tmp_path / "b", str(tmp_path / "cache")
    bench_quick("--only", "convergence", "-o", str(a), "--cache", cache)
    bench_quick("--only", "scaling", "-o", str(b), "--cache", cache)
    old = json.loads((a / "results.json").read_text())
    del old["runs"]                                # as the committed report was written
    (a / "results.json").write_text(json.dumps(old))
    brought = json.loads((b / "results.json").read_text())
    assert cli.main(["bench", "--merge", str(b), "-o", str(a)]) == 0
    assert "1 group taken from" in capsys.readouterr().out
    r, listed, readme, _ = read_report(a)
    assert r["groups"] == {"convergence": old["groups"]["convergence"],
                           "scaling": brought["groups"]["scaling"]}
    assert r["runs"][-1] == brought["runs"][0] and len(r["runs"]) == 2
    assert (a / "scaling.png").read_bytes() == (b / "scaling.png").read_bytes()
    assert "scaling.png" in listed and "convergence.png" in listed
    line = refused(["--merge", str(b), "--only", "models", "-o", str(a)], capsys)
    assert f"--merge {b} has no group 'models'; it has: scaling" in line
    line = refused(["--merge", str(tmp_path), "-o", str(a)], capsys)
    assert "cannot read the bench report's results.json" in line


def test_a_missing_dependency_stops_it_before_any_group(tmp_path, capsys, monkeypatch):
    """Without matplotlib (a plain install without the reports extra) bench
    says what to install before it runs a group, and writes nothing."""
    monkeypatch.setitem(sys.modules, "matplotlib", None)        # import matplotlib fails
    monkeypatch.setitem(sys.modules, "matplotlib.figure", None)
    line = refused(["-o", str(tmp_path / "out")], capsys)
    assert line.endswith("matplotlib is not installed; bench needs the report dependencies: "
                         "pip install 'mi_brdfs[reports]'")
    assert os.listdir(tmp_path) == []


# ----------------------------------------------------------------------------
#  Traced calls are the plugins' wherever the environment lives
# ----------------------------------------------------------------------------

def test_plugin_code_is_told_by_place_not_by_name(tmp_path):
    """The tracing group counts the calls Mitsuba makes into a plugin (from
    mitsuba/python/util.py): with the virtual environment inside a checkout
    called mi_brdfs, Mitsuba's files have "mi_brdfs" in their path too, and
    a filter on that name counted 0 calls."""
    import mitsuba as mi
    import mi_brdfs.bsdfs.base as base
    import mi_brdfs.bsdfs.mixture as mixture
    util = os.path.join(os.path.dirname(mi.__file__), "python", "util.py")
    venv = tmp_path / "mi_brdfs" / ".venv" / "lib" / "python3.11" / "site-packages"
    assert anatomy.plugin_code(base.__file__)
    assert not anatomy.plugin_code(util)
    assert not anatomy.plugin_code(str(venv / "mitsuba" / "python" / "util.py"))
    assert not anatomy.plugin_code(str(venv / "mi_brdfs" / "bsdfs" / "base.py"))  # another copy
    assert not anatomy.plugin_code(anatomy.__file__)             # the bench's own code
    assert not anatomy.plugin_code("~")                          # cProfile's built-ins
    assert anatomy.bsdf_method((mixture.__file__, 1, "sample"))
    assert not anatomy.bsdf_method((base.__file__, 1, "sample"))     # not where it is defined
    assert not anatomy.bsdf_method((util, 1, "sample"))


def test_calls_by_mitsuba_are_counted_in_a_render():
    counts = anatomy.calls_in_a_render(GGX.ours)
    assert counts["sample"][0] >= 1 and counts["eval_pdf"][0] >= 1
    assert counts["sample"][1] == counts["sample"][0]      # sample calls no other method


def test_report_headers_and_titles_are_words():
    """Every column the committed run has reads as words with its unit
    (builtin_compile_s: "built-in compile (s)"), every group has a title."""
    from mi_brdfs.tools.bench import report
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    with open(os.path.join(root, "docs", "benchmarks", "results.json")) as f:
        committed = json.load(f)
    keys = {k for rows in committed["groups"].values() for row in rows for k in row}
    assert {k: report.header(k) for k in keys if "_" in report.header(k)} == {}
    assert report.header("builtin_compile_s") == "built-in compile (s)"
    assert report.header("plugin_peak_mib") == "plugin peak memory (MiB)"
    assert set(report.TITLES) == set(bench.GROUPS)


def test_the_committed_benchmarks_folder_takes_a_new_run():
    """docs/benchmarks holds the bench's report only (another command's report
    in it, such as fit --scene's, made `bench -o docs/benchmarks`, the
    command the benchmarks guide gives, refuse the folder)."""
    from mi_brdfs.tools import destinations
    folder = os.path.join(os.path.dirname(__file__), "..", "..", "docs", "benchmarks")
    destinations.check_report_dir(folder)


def test_the_trade_finding_names_the_verdicts_cheaper_model_only():
    """The trade finding's cheaper model is the one the fit report's verdict
    chose (a lower cost class and a FLIP within the seed noise), not merely
    the best one timed cheaper beyond its interval: here lambert is cheaper
    beyond the interval but looks nothing like gold."""
    from mi_brdfs.tools.bench import report as bench_report

    def row(model, rank, flip, cost, chosen=False):
        return {"material": "Au", "model": model, "rank": rank, "image_flip": flip,
                "brdf_error": 0.1, "cost_ratio": cost, "cost_low": cost * 0.97,
                "cost_high": cost * 1.03, "time_to_noise": [cost, cost - 0.05, cost + 0.05],
                "looks_same_cheaper": chosen, "failed": ""}
    rows = [row("conductor", 1, 0.003, 1.0), row("lambert", 2, 0.7, 0.7)]
    text = bench_report.trade(rows)
    assert "no cheaper model looks the same" in text and "lambert" not in text
    rows.append(row("f82", 3, 0.01, 0.9, chosen=True))
    text = bench_report.trade(rows)
    assert "cheaper and looking the same f82" in text and "lambert" not in text
    assert "time to the same noise 0.90x (0.85-0.95)" in text
