"""Measurements in processes of their own.

At every render Dr.Jit traces every BSDF instance alive in the process, so a
measurement that depends on the number of instances (and on nothing else)
runs in a fresh Python process: ``python -m mi_brdfs.tools.bench --worker
TASK OPTIONS_JSON`` runs the task of :data:`TASKS` with those keyword
arguments and prints one result line, with the process's peak memory.
"""
from __future__ import annotations

import gc
import json
import statistics
import subprocess
import sys
import time

import drjit as dr
import mitsuba as mi

from ...bsdfs import cases
from ...render.frozen import FrozenRender
from ...render.passes import render_passes
from ..analysis import BSDF_METHODS, bsdf_call, bsdf_inputs, variables_created
from ..measures import render_waited
from . import floor
from .anatomy import call_anatomy, calls_in_a_render
from .measure import measured, peak_mib, spheres_scene

RESULT = "mi-brdfs-bench-result "       # the mark of the result line


def in_subprocess(task: str, **options) -> dict:
    """Run a worker task in a fresh Python process; its result (with peak_mib)."""
    run = subprocess.run([sys.executable, "-m", "mi_brdfs.tools.bench", "--worker", task,
                          json.dumps(options)], capture_output=True, text=True)
    lines = [line for line in run.stdout.splitlines() if line.startswith(RESULT)]
    if run.returncode != 0 or not lines:
        raise RuntimeError(f"bench worker {task} {options} failed:\n{run.stderr[-3000:]}")
    return json.loads(lines[-1][len(RESULT):])


def main(task: str, options: str) -> int:
    """``python -m mi_brdfs.tools.bench --worker TASK OPTIONS_JSON``: one result line."""
    floor.register()                 # the bare Python BSDFs measured beside the plugins
    result = TASKS[task](**json.loads(options))
    result["peak_mib"] = peak_mib()
    print(RESULT + json.dumps(result), flush=True)
    return 0


# ----------------------------------------------------------------------------
#  The tasks
# ----------------------------------------------------------------------------

def materials(twin: str, side: str, n: int, res: int, spp: int, repeats: int) -> dict:
    """First render of the spheres scene (each sphere the ``side`` of ``twin``:
    "plugin", "builtin" or "floor") and the medians of ``repeats`` warm
    renders, each split into tracing, code generation and kernel execution (s),
    and the median of ``repeats`` replays of a frozen render."""
    start = time.perf_counter()
    # parallel=False as in the render command (see its comment in tools/render.py)
    scene = mi.load_dict(spheres_scene(twin, side, n, res), parallel=False)
    result = {"load_s": time.perf_counter() - start}
    first = measured(lambda: render_waited(scene, spp, seed=0))
    warm = [measured(lambda: render_waited(scene, spp, seed=r + 1)) for r in range(repeats)]
    for part in ("wall", "tracing", "codegen", "execution"):
        result[f"first_{part}_s"] = first[f"{part}_s"]
        result[f"{part}_s"] = statistics.median(m[f"{part}_s"] for m in warm)
    # The same renders through a frozen function (as render passes and
    # GradientStep do): recorded once, then replayed without tracing.
    frozen = FrozenRender()
    evaluated = lambda image: (dr.eval(image), dr.sync_thread())
    measured(lambda: evaluated(frozen(scene, spp, seed=0)))    # (Jit flags key the recording)
    replays = [measured(lambda: evaluated(frozen(scene, spp, seed=r + 1)))
               for r in range(repeats)]
    result["frozen_s"] = statistics.median(m["wall_s"] for m in replays)
    result["frozen_recordings"] = frozen.recordings
    return result


def passes(n: int, res: int, spp: int, passes: int, freeze: bool, repeats: int) -> dict:
    """``render_passes`` of the spheres scene of the first twin with a spread
    (cook_torrance as roughconductor): the first call in the process (what
    ``mi-brdfs render`` does) and the median of the next."""
    twin = next(t for t in cases.twins() if t.spread is not None)
    scene = mi.load_dict(spheres_scene(twin.label, "plugin", n, res), parallel=False)
    messages: list[str] = []
    times = []
    for r in range(repeats + 1):
        messages.clear()
        start = time.perf_counter()
        render_passes(scene, spp, passes, seed=r, freeze=freeze, log=messages.append)
        times.append(time.perf_counter() - start)
    return {"first_s": times[0], "warm_s": statistics.median(times[1:]),
            "note": "; ".join(messages)}


def kernels(lanes: int, repeats: int) -> dict:
    """Kernel execution time of each BSDF call, plugin and built-in alternating,
    medians over ``repeats`` rounds after a compiling one.

    On one thread: on cores shared with other processes, Dr.Jit's thread pool
    makes a kernel of a few ms take 1.9 or 5.8 ms as one of its threads is
    descheduled or not (whichever kind runs first in a round, per process);
    on one thread both take 1.8-1.9 ms in every round."""
    dr.set_thread_count(1)
    x = bsdf_inputs(lanes)
    pairs = [(t.label, mi.load_dict(t.ours), mi.load_dict(t.builtin)) for t in cases.twins()]
    samples: dict[tuple, list[dict]] = {}
    for r in range(repeats + 1):                      # round 0 compiles
        for name, plugin, builtin in pairs:
            for method in BSDF_METHODS:
                for side, bsdf in (("plugin", plugin), ("builtin", builtin)):
                    m = measured(lambda: dr.eval(bsdf_call(bsdf, method, x)))
                    if r:
                        samples.setdefault((name, method, side), []).append(m)
    rows = []
    for name, _, _ in pairs:
        for method in BSDF_METHODS:
            row = {"name": name, "method": method, "lanes": lanes}
            for side in ("plugin", "builtin"):
                ms = samples[(name, method, side)]
                row[f"{side}_ms"] = 1e3 * statistics.median(m["execution_s"] for m in ms)
                row[f"{side}_wall_ms"] = 1e3 * statistics.median(m["wall_s"] for m in ms)
                row[f"{side}_ops"] = ms[0]["operations"]        # in the kernel, after CSE
            row["ratio"] = row["plugin_ms"] / row["builtin_ms"]
            row["wall_ratio"] = row["plugin_wall_ms"] / row["builtin_wall_ms"]
            rows.append(row)
    return {"rows": rows}


def tracing(lanes: int, calls: int) -> dict:
    """Tracing time of each BSDF call (no evaluation), plugin vs built-in (and
    the floor, where there is one), the Dr.Jit variables each call creates, and
    the anatomy of the plugin's call."""
    pairs = [(t.label, t.ours, t.builtin) for t in cases.twins()] + cases.every("related")
    floors = {t.label: t.floor for t in cases.twins() if t.floor is not None}
    # First, while no other BSDF is alive: a render traces every live instance.
    in_render = {}
    for name, p, _ in pairs:
        in_render[name] = calls_in_a_render(p)
        gc.collect()
    x = bsdf_inputs(lanes)
    rows = []
    for name, p, b in pairs:
        sides = {"plugin": mi.load_dict(p), "builtin": mi.load_dict(b)}
        if name in floors:
            sides["floor"] = mi.load_dict(floors[name])
        for method in BSDF_METHODS:
            row = {"name": name, "method": method}
            times: dict[str, list[float]] = {side: [] for side in sides}
            for bsdf in sides.values():
                bsdf_call(bsdf, method, x)
            for _ in range(calls):                    # the sides alternating
                for side, bsdf in sides.items():
                    start = time.perf_counter()
                    out = bsdf_call(bsdf, method, x)
                    times[side].append(time.perf_counter() - start)
                    del out
            for side, bsdf in sides.items():
                row[f"{side}_ms"] = 1e3 * statistics.median(times[side])
                row[f"{side}_vars"] = variables_created(lambda: bsdf_call(bsdf, method, x))
            row["ratio"] = row["plugin_ms"] / row["builtin_ms"]
            if "floor" in sides:
                row["ms_vs_floor"] = row["plugin_ms"] / row["floor_ms"]
            row["render_calls"], row["render_calls_all"] = in_render[name][method]
            row.update(call_anatomy(sides["plugin"], method, x))
            rows.append(row)
    return {"rows": rows}


TASKS = {"materials": materials, "passes": passes, "kernels": kernels, "tracing": tracing}
