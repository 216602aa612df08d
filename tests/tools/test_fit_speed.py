"""The fit's speed-ups keep what it measures: the per-target work is done once
and handed to every task (counted), the tasks given it record what they
record without it, the progress lines read as documented."""
import io

import numpy as np
import pytest

from mi_brdfs.tools.fit import models, scene, targets, task, work

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
