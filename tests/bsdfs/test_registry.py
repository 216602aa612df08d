"""One plugin registry (``mi_brdfs.bsdfs.PLUGINS``) and what derives from it
and from each model's own module: the package's exports, the plugins Mitsuba
loads by name, its cases (the battery's, the validation report's, the lobe
plots, the bench's models), its lecture-transcription test. A model added to
the registry alone appears everywhere or fails here, saying where it is
missing. And the declarations every model is built from (``Param``,
``Option``) are checked when its class is defined.
"""
import json
import os
import subprocess
import sys
from pathlib import Path
from xml.etree import ElementTree

import mitsuba as mi
import pytest

import mi_brdfs
from mi_brdfs.bsdfs import BY_NAME, PLUGINS
from mi_brdfs.bsdfs.base import BRDF
from mi_brdfs.bsdfs.params import DeclarationError, Option, Param
from mi_brdfs.bsdfs import cases

TESTS = Path(__file__).parent
NAMES = [cls.name for cls in PLUGINS]


def test_names_are_unique():
    assert len(set(NAMES)) == len(NAMES) == len(BY_NAME)
    assert len({cls.__name__ for cls in PLUGINS}) == len(PLUGINS)


@pytest.mark.parametrize("name", NAMES)
def test_every_plugin_is_everywhere(name):
    cls = BY_NAME[name]
    assert getattr(mi_brdfs, cls.__name__) is cls, "not exported by mi_brdfs"
    assert cls.__name__ in mi_brdfs.__all__
    assert type(mi.load_dict({"type": name})).__name__ == cls.__name__, "not registered"
    assert isinstance(cases.of(name), cases.Cases), "no cases() in its module"
    assert cases.lobe_configs()[name]["type"] == name, "no lobe plot"
    assert cases.report_furnace(name) and cases.report_chi2()[name], \
        "not in the validation report"
    assert any(c["type"] == name for _, c in cases.costs()), "not in the bench's models"
    if cls.compensable:
        assert any(c["type"] == name for _, c in cases.of(name).energy), \
            "compensable, but its cases have no energy row for the bench"
    assert (TESTS / f"test_{name}.py").is_file(), \
        f"no lecture-transcription test tests/bsdfs/test_{name}.py (CONTRIBUTING.md)"


def test_cases_are_of_registered_plugins_only():
    assert list(cases.ALL) == NAMES
    with pytest.raises(KeyError):
        cases.of("nonesuch")


# ----------------------------------------------------------------------------
#  Declarations, checked when the class is defined
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, message", [
    ({"kind": "scaler"}, "kind 'scaler' is unknown; valid: spectrum, scalar, float"),
    ({"role": "color"}, "role 'color' is unknown; valid: colour, weight, shape"),
    ({"default": -0.5}, r"default -0.5 is outside its range \[0, 1e\+06\]"),
    ({"default": 2.0, "hi": 1.0}, r"default 2.0 is outside its range \[0, 1\]"),
    ({"default": float("nan")}, "default nan is outside"),
    ({"default": "0.5"}, "default '0.5' is outside"),
    ({"lo": 1.0, "hi": 1.0, "default": 1.0}, r"empty range \[1, 1\]"),
    ({"hi": 1.0, "upper": 2.0}, r"upper 2.0 is outside its range \[0, 1\]"),
])
def test_a_malformed_param_is_refused(kwargs, message):
    with pytest.raises(DeclarationError, match="Param 'x': " + message):
        Param("x", **{"default": 0.5, **kwargs})


@pytest.mark.parametrize("default, choices, message", [
    ("ggx", ("beckmann", "blinn"), "default 'ggx' is not one of its choices"),
    ("a", (), "choices must be a tuple of strings"),
    ("a", ["a", "b"], "choices must be a tuple of strings"),
    (True, ("a",), "a boolean has no choices"),
])
def test_a_malformed_option_is_refused(default, choices, message):
    with pytest.raises(DeclarationError, match="Option 'x': " + message):
        Option("x", default, choices)


def test_a_model_declaring_a_name_twice_is_refused():
    with pytest.raises(DeclarationError, match="Twice: 'mode' is declared twice"):
        type("Twice", (BRDF,), {"name": "twice", "PARAMS": (Param("mode", 0.5),)})
    with pytest.raises(DeclarationError, match=r"Loose.PARAMS: \('a', 0.5\) is not a Param"):
        type("Loose", (BRDF,), {"name": "loose", "PARAMS": (("a", 0.5),)})


# ----------------------------------------------------------------------------
#  Broken cases fail their own model's tests only
# ----------------------------------------------------------------------------

BREAKER = '''"""A pytest plugin (-p breaker), loaded before collection: breaks lambert's
cases (its cases() raises) and one of phong's configurations (a misspelt
parameter, which Mitsuba refuses at load time)."""
from mi_brdfs.bsdfs import Lambert, Phong


def no_cases(cls):
    raise KeyError("a misspelt key in the cases")


def misspelt(cls, build=Phong.cases.__func__):
    built = build(cls)
    built.interior.append({"type": cls.name, "exponant": 20.0})
    return built


Lambert.cases = classmethod(no_cases)
Phong.cases = classmethod(misspelt)
'''


def test_broken_cases_fail_their_own_tests_only(tmp_path):
    """The battery, collected with lambert's cases and a phong configuration
    broken: no collection error; lambert's and phong's tests fail (those that
    use what is broken), every other model's pass."""
    (tmp_path / "breaker.py").write_text(BREAKER)
    report = tmp_path / "report.xml"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(tmp_path), *filter(None, [os.environ.get("PYTHONPATH")])])}
    run = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "breaker", "-p", "no:cacheprovider",
         f"--junitxml={report}", str(TESTS / "test_battery.py"),
         "-k", "cases_cover or update_matches or traverse_exposes or lambert"],
        capture_output=True, text=True, env=env, cwd=TESTS.parent.parent, timeout=600)
    assert run.returncode == 1, run.stdout[-3000:] + run.stderr[-3000:]   # 1: tests failed
    cases = ElementTree.parse(report).getroot().iter("testcase")
    failed, passed = set(), set()
    for case in cases:
        name = case.get("name")
        if case.find("error") is not None:
            pytest.fail(f"{name}: an error, not a failure")
        (failed if case.find("failure") is not None else passed).add(name)
    assert all("lambert" in n or "exponant" in n for n in failed), sorted(failed)
    broken = {n for n in failed | passed if "lambert-cases" in n}
    assert broken and broken <= failed
    assert "test_cases_cover_the_plugin[lambert]" in failed
    assert any("exponant" in n for n in failed)
    others = {n for n in passed if not ("lambert" in n or "exponant" in n)}
    assert {n.split("[")[1].split("-")[0] for n in others if "[" in n} >= set(NAMES) - {"lambert"}
    assert any(n.startswith("test_load_eval_pdf_sample[lambert") for n in passed)  # its class


def test_what_is_made_from_the_modules_is_up_to_date():
    """The README's tables (the plugins; which model for which material, from
    the committed trade sweep) and the shipped albedo tables are what
    ``python -m mi_brdfs.tools.regenerate`` makes from the models' modules."""
    from mi_brdfs.tools import regenerate
    with open(regenerate.README, encoding="utf-8") as f:
        readme = f.read()
    assert regenerate.readme_with_tables(readme) == readme, \
        "README.md's tables are stale: python -m mi_brdfs.tools.regenerate"
    assert regenerate.missing_tables() == []
    assert regenerate.stale_report() == [], "python -m mi_brdfs.tools.regenerate"
    for cls in PLUGINS:
        assert f"[`{cls.name}`]" in readme


def test_a_stale_validation_report_is_noticed(tmp_path, monkeypatch):
    """``regenerate --check`` names what the committed report lacks (a model
    added since: here one removed from a copy of the report) and what it ran
    that no case declares any more."""
    from mi_brdfs.tools import regenerate
    with open(regenerate.REPORT, encoding="utf-8") as f:
        report = json.load(f)
    for section in ("lobes", "furnace", "sampling"):
        report[section] = [r for r in report[section] if r["model"] != "ward"]
    report["sampling"].append({**report["sampling"][0], "config": "a retired case"})
    copy = tmp_path / "results.json"
    copy.write_text(json.dumps(report), encoding="utf-8")
    monkeypatch.setattr(regenerate, "REPORT", str(copy))
    stale = regenerate.stale_report()
    assert "the validation report lacks lobes ward" in stale
    assert any(line.startswith("the validation report lacks furnace ward ") for line in stale)
    assert any(line.startswith("the validation report lacks sampling ward ") for line in stale)
    assert any("a retired case" in line and "which no case declares" in line for line in stale)
    assert all("ward" in line or "a retired case" in line for line in stale)
    assert regenerate.main(["--check"]) == 1


# ----------------------------------------------------------------------------
#  A plugin is freed when its last reference goes
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("name", NAMES)
def test_a_plugin_is_freed_by_reference_counting(name):
    """No plugin sits in a reference cycle (e.g. its compensation holding a
    lambda over ``self``): a cycle keeps the plugin's Dr.Jit arrays alive until
    the cyclic collector runs, at a moment nobody chose, and when that is
    inside a differentiable render Dr.Jit's AD raises. Each of the model's
    configurations (compensated ones too) is loaded, traversed, updated and
    dropped with the collector off; the collector then finds none of it."""
    import gc
    configs = list(cases.of(name).interior) + [{**c, "energy_compensation": True}
                                               for _, c in cases.of(name).energy]
    assert any(c.get("energy_compensation") for c in configs) == BY_NAME[name].compensable
    gc.collect()
    gc.disable()
    try:
        for config in configs:
            bsdf = mi.load_dict(dict(config))
            params = mi.traverse(bsdf)
            params.update()            # parameters_changed decides the lobes again
            del bsdf, params
        gc.set_debug(gc.DEBUG_SAVEALL)
        gc.collect()
        left = [type(o).__name__ for o in gc.garbage if isinstance(o, (BRDF, mi.Object))]
    finally:
        gc.set_debug(0)
        gc.garbage.clear()
        gc.enable()
    assert left == [], f"{name}: freed only by the cyclic garbage collector: {left}"


def test_plugins_are_made_without_calling_the_scene_loader(monkeypatch):
    """A plugin's constructor never calls ``mi.load_dict`` (or load_string):
    Mitsuba constructs a scene's objects in worker threads, and a loader
    called from one of them corrupted another's object now and then (see
    ``mi_brdfs._binding.create``). Every plugin with its defaults, and the
    course scene (its ``course`` integrator makes the one its mode names)."""
    calls = []
    for name in ("load_dict", "load_string"):
        original = getattr(mi, name)
        monkeypatch.setattr(mi, name, lambda *a, _f=original, _n=name, **k:
                            (calls.append((_n, a[0])), _f(*a, **k))[1])
    scene = Path(mi_brdfs.scenes.path("course"))
    for cls in PLUGINS:
        calls.clear()
        plugin = mi.PluginManager.instance().create_object(mi.Properties(cls.name))
        assert type(plugin).__name__ == cls.__name__
        assert calls == [], f"{cls.name}'s constructor called the loader: {calls}"
    for mode in ("scanline", "hdr"):
        mi.load_file(str(scene), mode=mode, res=8)
    assert calls == [], f"the course scene's plugins called the loader: {calls}"
