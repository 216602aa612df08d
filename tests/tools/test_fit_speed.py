"""The fit's speed-ups keep what it measures: the per-target work is done once
and handed to every task (counted), the tasks given it record what they
record without it, the progress lines read as documented."""
import io
import tempfile
from pathlib import Path

import numpy as np
import pytest

from mi_brdfs.tools.fit import models, scene, sweep, targets, task, work
from support import fresh_python

TINY = task.QUICK.replace(viewers=(4, 2), uniform=(4, 4), lobe=4, scan=2, starts=1, steps=0,
                          res=24, spp=4, cost=False)
TARGET = "roughconductor:material=Au,alpha=0.3"


def counting(monkeypatch, module, name, calls):
    real = getattr(module, name)

    def counted(*args, **kwargs):
        calls[name] = calls.get(name, 0) + 1
        return real(*args, **kwargs)
    monkeypatch.setattr(module, name, counted)


def test_per_target_work_is_computed_once_and_gives_the_same_records(monkeypatch):
    t = targets.parse([TARGET])[0]
    chosen = models.select(["lambert", "phong"])
    alone = [task.fit_and_measure(t, m, TINY) for m in chosen]     # each computes its own
    scene._TARGET_IMAGES.clear()
    calls = {}
    for name in ("pairs_of", "noise_floor"):
        counting(monkeypatch, work, name, calls)
    counting(monkeypatch, work.effective, "albedo", calls)
    counting(monkeypatch, scene, "render_views", calls)
    shared = work.prepare(t, TINY)
    assert calls == {"pairs_of": 1, "noise_floor": 1, "albedo": 1, "render_views": 2}
    records = [task.fit_and_measure(t, m, TINY, shared) for m in chosen]
    # the tasks computed none of it again: one albedo and one set of renders per model
    assert calls == {"pairs_of": 1, "noise_floor": 1, "albedo": 3, "render_views": 4}
    for a, b in zip(alone, records):
        assert "error" not in b, b.get("error")
        for key in ("brdf_error", "image_flip", "image_relmse", "image_noise_flip",
                    "image_noise_relmse", "target_albedo"):
            assert np.allclose(a[key], b[key], rtol=1e-6), key
        assert a["slices"]["target"] == b["slices"]["target"]
        assert a["parameters"] == b["parameters"]


SCENES = Path(__file__).resolve().parents[2] / "scenes"


def test_parallel_loading_gives_the_same_render_as_serial_loading():
    """Mitsuba loads a scene's objects in worker threads by default (a user's
    script does); the course plugins make their parts without the loader
    (_binding.create). The course scene (every plugin, the largest) renders
    the same either way, in fresh processes (a corrupted object shows as an
    error or another image). The project's commands still load serially: see
    the comment in tools/render.py."""
    script = ("import sys, numpy as np;"
              f"s = mi.load_file({str(SCENES / 'course.xml')!r}, parallel=sys.argv[1] == '1',"
              " mode='hdr', res='24');"
              "np.save(sys.argv[2], np.array(mi.render(s, spp=4, seed=3)))")
    images = []
    for i, parallel in enumerate(("1", "0", "1")):
        out = Path(tempfile.mkdtemp()) / f"{i}.npy"
        fresh_python(script, parallel, str(out))
        images.append(np.load(out))
    assert images[0].shape == (24, 24, 3) and images[0].max() > 0
    np.testing.assert_array_equal(images[0], images[1])
    np.testing.assert_array_equal(images[2], images[1])


def test_a_settled_worker_still_frees_what_its_tasks_leave_behind():
    """scene.settle (a fit worker's first task) puts the imports out of the
    collector's reach, so its collections walk a small heap; a BSDF held in a
    reference cycle made afterwards is still freed by scene.release (else
    every fitted model would stay alive and be traced at every render). In a
    fresh process: the freeze is for the life of the process."""
    script = ("import gc, weakref;"
              "from mi_brdfs.tools.fit import scene;"
              "scene.settle();"
              "Cycle = type('Cycle', (), {});"
              "c = Cycle(); c.me = c; c.bsdf = mi.load_dict({'type': 'phong'});"
              "gone = weakref.ref(c); del c;"
              "before = gone() is not None; scene.release();"
              "print(gc.get_freeze_count(), len(gc.get_objects()), before, gone() is None)")
    frozen, tracked, alive_before, freed = fresh_python(script).stdout.split()
    assert int(frozen) > 10 * int(tracked), (frozen, tracked)
    assert (alive_before, freed) == ("True", "True")


def test_progress_lines_count_models_per_phase_with_the_time_left():
    """In a log (not a terminal): one line per finished model with its
    summary, then "LABEL (fitted): done/total models, elapsed, ETA left";
    the cost phase counts from 1 again and its time from its own start; the
    time left comes from the models after the first."""
    out = io.StringIO()
    show = sweep.progress_printer("mi-brdfs fit", stream=out)
    fit = {"target": "t", "model": "m", "brdf_error": 0.1, "seconds": 2.0}
    for done, elapsed in ((1, 10.0), (2, 12.0), (3, 14.0)):
        show(done, 3, elapsed, fit)
    cost = {**fit, "cost_ratio": 1.0, "cost_low": 0.9, "cost_high": 1.1, "cost_rounds": 4,
            "ops_ratio": 1.0}
    for done, elapsed in ((1, 20.0), (2, 23.0)):
        show(done, 3, elapsed, cost)
    show.close()
    lines = out.getvalue().splitlines()
    progress = [line for line in lines if " models, " in line]
    assert progress == [
        "mi-brdfs fit (fitted): 1/3 models, 10.0 s, ETA ?",
        "mi-brdfs fit (fitted): 2/3 models, 12.0 s, ETA 2.0 s",
        "mi-brdfs fit (fitted): 3/3 models, 14.0 s, ETA 0.0 s",
        "mi-brdfs fit (cost timed): 1/3 models, 6.0 s, ETA ?",
        "mi-brdfs fit (cost timed): 2/3 models, 9.0 s, ETA 3.0 s"]
    assert lines[0] == "mi-brdfs fit: t × m: brdf error 0.1, 2.0 s"
    assert "cost 1.00x (0.90-1.10, 4 rounds)" in lines[-2]
    quiet = io.StringIO()
    show = sweep.progress_printer("mi-brdfs fit", stream=quiet, enabled=False)
    show(1, 3, 1.0, fit)
    assert quiet.getvalue() == ""


def test_the_bench_fit_group_runs_quick():
    from mi_brdfs.tools import bench
    from mi_brdfs.tools.bench import groups, report
    rows = groups.fit_time(bench.QUICK, None)
    assert [(r["fit"], r["models"], r["failed"], r["runs"]) for r in rows] == [("quick", 1, 0, 1)]
    r = rows[0]
    assert r["median_s"] >= r["fits_s"] > 0 and r["costs_s"] > 0
    assert "quick settings" in report.fit_time(rows)
