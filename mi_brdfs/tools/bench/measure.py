"""How the bench measures: its settings, its scenes, timed renders and their
split from Dr.Jit's kernel history, errors against cached references, BSDF
peak memory and the machine (the BSDF calls on direction pairs it times are
:mod:`mi_brdfs.tools.analysis`'s).

Every timing is the median of ``repeats`` renders after a warm-up render that
compiles the kernels (the warm-up's extra time is reported as compile time).
Every error is the relative MSE (pbrt's form, mean((t - r)²/(r + 0.01)²))
against a converged reference rendered once at high spp and cached on disk,
keyed by the scene and the settings. Efficiency is 1 / (relMSE × seconds).
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import platform
import resource
import statistics
import time
from dataclasses import dataclass

import numpy as np

import drjit as dr
import mitsuba as mi

from ...bsdfs import cases
from ...render import exr
from .. import settings
from ..analysis import camera
from ..measures import render_waited


@dataclass(frozen=True)
class Settings(settings.Settings):
    """How much work each bench group does."""
    res: int
    spp: int
    repeats: int
    ref_spp: int
    spp_ladder: tuple[int, ...]
    resolutions: tuple[int, ...]
    light_counts: tuple[int, ...]
    table_resolutions: tuple[int, ...]
    # The many-materials scene (materials, frozen): sphere counts, pixels, spp.
    materials: tuple[int, ...]
    materials_res: int
    materials_spp: int
    frozen_passes: tuple[int, ...]
    rounds: int                       # processes per (kind, N) in materials
    kernel_lanes: int                 # direction pairs per BSDF kernel (kernels)
    table_samples: int                # quadrature samples per axis of a table build (energy)
    trade_targets: int                # materials of the fit sweep (trade; 0: every one)
    trade_models: tuple[str, ...]     # models it fits (empty: every course model)
    ladder_res: int                   # pixels across the ladder's sphere renders (ladder)


# --quick: a smoke test that every group runs (tiny scene, few repeats): its
# numbers are not measurements.
QUICK = Settings(res=24, spp=4, repeats=3, ref_spp=64, spp_ladder=(1, 2, 4, 8),
                 resolutions=(16, 32), light_counts=(1, 2, 4), table_resolutions=(8, 32),
                 materials=(1, 3), materials_res=16, materials_spp=4, frozen_passes=(1, 2, 4),
                 rounds=1, kernel_lanes=2**14, table_samples=8, trade_targets=1,
                 trade_models=("lambert", "cook_torrance/ggx/smith"), ladder_res=24)
FULL = Settings(res=192, spp=16, repeats=7, ref_spp=4096, spp_ladder=(1, 2, 4, 8, 16, 32, 64, 128),
                resolutions=(64, 128, 256, 512), light_counts=(1, 2, 4, 8, 16, 32),
                table_resolutions=(4, 8, 16, 32, 64, 128, 256),
                materials=(1, 10, 50, 200), materials_res=128, materials_spp=64,
                frozen_passes=(1, 8, 32), rounds=3, kernel_lanes=2**22, table_samples=128,
                trade_targets=0, trade_models=(), ladder_res=128)


# ----------------------------------------------------------------------------
#  Errors
# ----------------------------------------------------------------------------

def efficiency(relmse: float, seconds: float) -> float:
    """1 / (relMSE × time); inf for an exact result."""
    if relmse <= 0:
        return math.inf
    return 1.0 / (relmse * seconds)


# ----------------------------------------------------------------------------
#  Scenes
# ----------------------------------------------------------------------------

# The floor under the sphere of the in-process groups' scene.
FLOOR = {"type": "lambert", "reflectance": 0.5}


def scene_dict(bsdf: dict, res: int, integrator: dict | None = None, lights: int = 1,
               env: float = 0.3, plane: bool = True) -> dict:
    """A sphere on a plane, point lights and a dim constant environment."""
    T = mi.ScalarTransform4f
    d = {
        "type": "scene",
        "integrator": integrator or {"type": "path", "max_depth": 3},
        "sensor": camera(res, 36, origin=(0.0, 1.2, 4.0)),
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": env}},
    }
    if plane:
        d["plane"] = {"type": "rectangle", "bsdf": dict(FLOOR),
                      "to_world": T().translate([0, -1, 0]) @ T().rotate([1, 0, 0], -90)
                      @ T().scale(4)}
    for i in range(lights):
        angle = 2 * math.pi * i / max(lights, 1)
        d[f"light{i}"] = {"type": "point",
                          "position": [3 * math.cos(angle), 3.0, 3 * math.sin(angle) + 1.5],
                          "intensity": {"type": "rgb", "value": 12.0 / lights}}
    return d


def spheres_scene(twin: str, side: str, n: int, res: int, max_depth: int = 3) -> dict:
    """``n`` unit spheres in a square grid, each with its own material: the
    ``side`` ("plugin", "builtin" or "floor") of the model's twin ``twin``
    (:class:`mi_brdfs.bsdfs.cases.Twin`) with the parameters of its spread at
    the sphere's place; in a constant environment, path traced (the full run:
    200 spheres, depth 3, 128², 64 spp)."""
    t = cases.twin(twin)
    base = {"plugin": t.ours, "builtin": t.builtin, "floor": t.floor}[side]
    side = math.ceil(math.sqrt(n))
    spacing, fov = 2.5, 40.0
    distance = 1.2 * side * spacing / (2 * math.tan(math.radians(fov / 2))) + 2
    d = {"type": "scene", "integrator": {"type": "path", "max_depth": max_depth},
         "sensor": camera(res, fov, origin=(0.0, 0.0, distance)),
         "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}}}
    for i in range(n):
        x, y = (i % side - (side - 1) / 2) * spacing, (i // side - (side - 1) / 2) * spacing
        d[f"sphere{i}"] = {"type": "sphere", "center": [x, y, 0.0], "radius": 1.0,
                           "bsdf": {**base, **t.spread(i / max(n - 1, 1))}}
    return d


# ----------------------------------------------------------------------------
#  Timing
# ----------------------------------------------------------------------------

def image(scene, spp: int, seed: int) -> np.ndarray:
    """A render's RGB as a NumPy array."""
    return np.array(render_waited(scene, spp, seed))[..., :3]


def timed(scene, spp: int, repeats: int) -> dict:
    """Warm-up render (compiles), then the median of `repeats` renders, with the
    kernel history's split of the last one: tracing, codegen, execution (s)."""
    start = time.perf_counter()
    render_waited(scene, spp, seed=0)
    first = time.perf_counter() - start
    times = []
    for r in range(repeats):
        start = time.perf_counter()
        render_waited(scene, spp, seed=r + 1)
        times.append(time.perf_counter() - start)
    median = statistics.median(times)
    split = measured(lambda: render_waited(scene, spp, seed=repeats + 1))    # where the time goes
    return {"median_s": median, "compile_s": max(first - median, 0.0), "times_s": times,
            "kernels": split["kernels"], "execution_s": split["execution_s"],
            "codegen_s": split["codegen_s"], "tracing_s": split["tracing_s"]}


def alternating(scenes: dict, spp: int, repeats: int) -> dict[str, dict]:
    """Per scene (name -> scene): the median wall and kernel execution time of
    ``repeats`` renders, the scenes taking turns after a warm-up render each,
    so that a change of the machine's load hits them alike."""
    for scene in scenes.values():
        render_waited(scene, spp, seed=0)
    runs: dict[str, list[dict]] = {name: [] for name in scenes}
    for r in range(repeats):
        for name, scene in scenes.items():
            runs[name].append(measured(lambda: render_waited(scene, spp, seed=r + 1)))
    return {name: {"median_s": statistics.median(m["wall_s"] for m in ms),
                   "execution_s": statistics.median(m["execution_s"] for m in ms)}
            for name, ms in runs.items()}


def measured(run) -> dict:
    """Wall time of ``run()`` (which must evaluate its result) and its split from
    Dr.Jit's kernel history (s): code generation (codegen and LLVM), kernel
    execution, and tracing (the rest: Python and Dr.Jit building the kernels)."""
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()                              # clear
    start = time.perf_counter()
    run()
    dr.sync_thread()
    wall = time.perf_counter() - start
    history = dr.kernel_history()
    dr.set_flag(dr.JitFlag.KernelHistory, False)
    execution = sum(k.get("execution_time", 0.0) for k in history) / 1000
    codegen = sum(k.get("codegen_time", 0.0) + k.get("backend_time", 0.0) for k in history) / 1000
    return {"wall_s": wall, "kernels": len(history), "execution_s": execution,
            "codegen_s": codegen, "tracing_s": max(wall - execution - codegen, 0.0),
            "operations": sum(k.get("operation_count", 0) for k in history)}


class References:
    """Converged references, rendered once and cached on disk."""

    def __init__(self, directory: str, spp: int):
        self.directory, self.spp = directory, spp

    def key(self, d: dict) -> str:
        text = json.dumps(d, sort_keys=True, default=str) + f"|{self.spp}|{mi.__version__}"
        return hashlib.sha1(text.encode()).hexdigest()[:16]

    def get(self, d: dict) -> np.ndarray:
        path = os.path.join(self.directory, f"ref-{self.key(d)}.exr")
        if os.path.exists(path):
            return exr.read_exr(path).astype(np.float64)
        scene = mi.load_dict(d)
        passes = max(1, self.spp // 256)
        reference = sum(image(scene, self.spp // passes, seed=10_000 + i)
                        for i in range(passes)) / passes
        os.makedirs(self.directory, exist_ok=True)
        exr.write_exr(path, reference)
        return np.asarray(reference, dtype=np.float64)


# ----------------------------------------------------------------------------
#  The process and the machine
# ----------------------------------------------------------------------------

def peak_mib() -> float:
    """This process's peak resident memory in MiB: Linux's VmHWM, the high-water
    mark of this program's own memory, else ru_maxrss (which also counts the
    parent's resident memory at fork time: every worker of a large bench
    process would read as large as its parent)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def machine() -> dict:
    cpu = platform.processor()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return {"cpu": cpu, "cores": os.cpu_count(), "variant": mi.variant(),
            "mitsuba": mi.__version__, "drjit": dr.__version__,
            "llvm": ".".join(map(str, dr.detail.llvm_version())),
            "python": platform.python_version()}
