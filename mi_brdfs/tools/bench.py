"""The speed/accuracy benchmark: ``mi-brdfs bench [--quick] [--only GROUP] -o OUT_DIR``.

Every timing is the median of ``repeats`` renders after a warm-up render that
compiles the kernels (the warm-up's extra time is reported as compile time),
all in one process so that ratios are meaningful on a noisy machine — except
where the number of BSDF instances alive matters (Dr.Jit traces every live
instance at every render): ``materials``, ``frozen``, ``kernels`` and
``tracing`` run in fresh processes (``python -m mi_brdfs.tools.bench --worker``). Every
error is the relative MSE (pbrt's form, mean((t - r)²/(r + 0.01)²)) against a
converged reference rendered once at high spp and cached on disk, keyed by the
scene and the settings. Efficiency is 1 / (relMSE × seconds).

Groups:

builtin      Python plugin vs Mitsuba's C++ built-in, same scene and spp; the
             time ratio, and where the time goes (Python tracing, LLVM codegen,
             kernel execution, from Dr.Jit's kernel history).
models       render time per spp of every model and variant, relative to lambert.
oren_nayar   the Oren-Nayar table at several resolutions vs the exact formulas:
             time and error against the exact render (same seed: no noise).
sampling     glossy lobes: cosine-hemisphere vs the lobe's importance sampling
             (and full-distribution vs visible-normal microfacet sampling),
             error at equal spp and efficiency.
integrators  scan-line direct lighting, Mitsuba's ``direct``, ``path`` with max
             depth 2, 3 and 8, against a converged path-traced reference.
convergence  error vs spp (log-log) and its slope (about -1 for relMSE).
scaling      render time vs resolution and vs number of lights (scan-line).
lobes        model only what the scene requires: a plugin with a lobe switched
             off renders at the cost of the model without that lobe.
energy       energy compensation: render time of each compensated model with
             energy_compensation on vs off (same scene and spp), and the time
             to build its albedo table (python -m mi_brdfs.tools.tables) at
             the shipped resolution.
materials    N spheres, each with its own material (N up to 200; path depth 3,
             constant environment), plugin vs built-in (cook_torrance vs
             roughconductor, lambert vs diffuse): first and warm render split
             into tracing, code generation and kernel execution, a frozen
             render's replay (render/frozen.py), and peak memory; each (kind, N) in processes of its own (``rounds`` of
             them, alternating kinds; medians). The first render loads its
             kernels from Dr.Jit's disk cache when an earlier run compiled them.
frozen       render_passes at the largest N in 1, 8 and 32 passes (the same
             spp in all), traced and frozen, each in a process of its own.
kernels      eval, pdf, eval_pdf and sample of 2^22 direction pairs: kernel
             execution time, plugin and built-in alternating in one process,
             on one thread (stable on shared cores).
tracing      tracing time of one call of each method, plugin vs built-in, and
             what the plugin's call does: texture evaluations, Mitsuba objects
             built, BSDF methods it calls again, helpers called more than once,
             and how often a path-traced render calls each method.

Outputs in OUT_DIR: results.json, results.csv, README.md (tables) and plots.
"""
from __future__ import annotations

import csv
import hashlib
import json
import math
import os
import platform
import statistics
import time
from dataclasses import dataclass

import numpy as np

from .analysis import camera

GROUPS = ("builtin", "models", "oren_nayar", "sampling", "integrators", "convergence", "scaling",
          "lobes", "energy", "materials", "frozen", "kernels", "tracing")


@dataclass
class Settings:
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


QUICK = Settings(res=24, spp=4, repeats=3, ref_spp=64, spp_ladder=(1, 2, 4, 8),
                 resolutions=(16, 32), light_counts=(1, 2, 4), table_resolutions=(8, 32),
                 materials=(1, 3), materials_res=16, materials_spp=4, frozen_passes=(1, 2, 4),
                 rounds=1, kernel_lanes=2**14, table_samples=8)
FULL = Settings(res=192, spp=16, repeats=7, ref_spp=4096, spp_ladder=(1, 2, 4, 8, 16, 32, 64, 128),
                resolutions=(64, 128, 256, 512), light_counts=(1, 2, 4, 8, 16, 32),
                table_resolutions=(4, 8, 16, 32, 64, 128, 256),
                materials=(1, 10, 50, 200), materials_res=128, materials_spp=64,
                frozen_passes=(1, 8, 32), rounds=3, kernel_lanes=2**22, table_samples=128)


def efficiency(relmse: float, seconds: float) -> float:
    """1 / (relMSE × time); inf for an exact result."""
    if relmse <= 0:
        return math.inf
    return 1.0 / (relmse * seconds)


def pareto(points: list[tuple[float, float]]) -> list[bool]:
    """For (time, error) points: True where no other point is at least as fast
    and as accurate and strictly better in one of the two."""
    front = []
    for i, (t, e) in enumerate(points):
        dominated = any(t2 <= t and e2 <= e and (t2 < t or e2 < e)
                        for j, (t2, e2) in enumerate(points) if j != i)
        front.append(not dominated)
    return front


def relmse(test: np.ndarray, ref: np.ndarray) -> float:
    return float(np.mean((test - ref) ** 2 / (ref + 0.01) ** 2))


# ----------------------------------------------------------------------------
#  Scenes
# ----------------------------------------------------------------------------

def scene_dict(bsdf: dict, res: int, integrator: dict | None = None, lights: int = 1,
               env: float = 0.3, plane: bool = True) -> dict:
    """A sphere on a plane, point lights and a dim constant environment."""
    import mitsuba as mi
    T = mi.ScalarTransform4f
    d = {
        "type": "scene",
        "integrator": integrator or {"type": "path", "max_depth": 3},
        "sensor": camera(res, 36, origin=(0.0, 1.2, 4.0)),
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": env}},
    }
    if plane:
        d["plane"] = {"type": "rectangle", "bsdf": {"type": "lambert", "reflectance": 0.5},
                      "to_world": T().translate([0, -1, 0]) @ T().rotate([1, 0, 0], -90)
                      @ T().scale(4)}
    for i in range(lights):
        angle = 2 * math.pi * i / max(lights, 1)
        d[f"light{i}"] = {"type": "point",
                          "position": [3 * math.cos(angle), 3.0, 3 * math.sin(angle) + 1.5],
                          "intensity": {"type": "rgb", "value": 12.0 / lights}}
    return d


# ----------------------------------------------------------------------------
#  Measuring
# ----------------------------------------------------------------------------

def _render(scene, spp: int, seed: int) -> np.ndarray:
    import drjit as dr
    import mitsuba as mi
    image = mi.render(scene, spp=spp, seed=seed)
    dr.eval(image)
    dr.sync_thread()
    return image


def timed(scene, spp: int, repeats: int) -> dict:
    """Warm-up render (compiles), then the median of `repeats` renders, with the
    kernel history's split of the last one: tracing, codegen, execution (s)."""

    start = time.perf_counter()
    _render(scene, spp, seed=0)
    first = time.perf_counter() - start
    times = []
    for r in range(repeats):
        start = time.perf_counter()
        _render(scene, spp, seed=r + 1)
        times.append(time.perf_counter() - start)
    median = statistics.median(times)
    split = measured(lambda: _render(scene, spp, seed=repeats + 1))    # where the time goes
    return {"median_s": median, "compile_s": max(first - median, 0.0), "times_s": times,
            "kernels": split["kernels"], "execution_s": split["execution_s"],
            "codegen_s": split["codegen_s"], "tracing_s": split["tracing_s"]}


def measured(run) -> dict:
    """Wall time of ``run()`` (which must evaluate its result) and its split from
    Dr.Jit's kernel history (s): code generation (codegen and LLVM), kernel
    execution, and tracing (the rest: Python and Dr.Jit building the kernels)."""
    import drjit as dr
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
        os.makedirs(directory, exist_ok=True)

    def key(self, d: dict) -> str:
        import mitsuba as mi
        text = json.dumps(d, sort_keys=True, default=str) + f"|{self.spp}|{mi.__version__}"
        return hashlib.sha1(text.encode()).hexdigest()[:16]

    def get(self, d: dict) -> np.ndarray:
        import mitsuba as mi

        from ..render import exr
        path = os.path.join(self.directory, f"ref-{self.key(d)}.exr")
        if os.path.exists(path):
            return exr.read_exr(path).astype(np.float64)
        scene = mi.load_dict(d)
        passes = max(1, self.spp // 256)
        image = sum(np.array(_render(scene, self.spp // passes, seed=10_000 + i))[..., :3]
                    for i in range(passes)) / passes
        exr.write_exr(path, image)
        return np.asarray(image, dtype=np.float64)


# ----------------------------------------------------------------------------
#  The groups
# ----------------------------------------------------------------------------

BUILTIN_PAIRS = [
    ("lambert vs diffuse", {"type": "lambert", "reflectance": 0.6},
     {"type": "diffuse", "reflectance": 0.6}),
    ("cook_torrance (ggx, smith, f0=1, k=0) vs roughconductor",
     {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith", "f0": 1.0, "k": 0.0,
      "alpha": 0.3},
     {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3}),
]


def group_builtin(s: Settings, refs) -> list[dict]:
    import mitsuba as mi
    rows = []
    for name, ours, builtin in BUILTIN_PAIRS:
        t_ours = timed(mi.load_dict(scene_dict(ours, s.res)), s.spp, s.repeats)
        t_builtin = timed(mi.load_dict(scene_dict(builtin, s.res)), s.spp, s.repeats)
        rows.append({"name": name, "plugin_s": t_ours["median_s"],
                     "builtin_s": t_builtin["median_s"],
                     "ratio": t_ours["median_s"] / t_builtin["median_s"],
                     "plugin_compile_s": t_ours["compile_s"],
                     "builtin_compile_s": t_builtin["compile_s"],
                     "plugin_tracing_s": t_ours["tracing_s"],
                     "builtin_tracing_s": t_builtin["tracing_s"],
                     "plugin_execution_s": t_ours["execution_s"],
                     "builtin_execution_s": t_builtin["execution_s"],
                     "plugin_codegen_s": t_ours["codegen_s"],
                     "builtin_codegen_s": t_builtin["codegen_s"]})
    return rows


def group_models(s: Settings, refs) -> list[dict]:
    import mitsuba as mi

    from . import catalog
    rows = []
    for name, config in catalog.bench_models():
        t = timed(mi.load_dict(scene_dict(config, s.res)), s.spp, s.repeats)
        rows.append({"name": name, "median_s": t["median_s"], "per_spp_s": t["median_s"] / s.spp,
                     "compile_s": t["compile_s"]})
    base = next(r["median_s"] for r in rows if r["name"] == "lambert")
    for r in rows:
        r["relative_to_lambert"] = r["median_s"] / base
    return rows


def group_oren_nayar(s: Settings, refs) -> list[dict]:
    import mitsuba as mi
    base = {"type": "oren_nayar", "sigma": 0.5, "reflectance": 0.8}
    exact_scene = mi.load_dict(scene_dict({**base, "method": "exact"}, s.res))
    exact = timed(exact_scene, s.spp, s.repeats)
    exact_img = np.array(_render(exact_scene, s.spp, seed=99))[..., :3]
    again = np.array(_render(exact_scene, s.spp, seed=99))[..., :3]     # same seed: no noise
    rows = [{"name": "exact", "table_resolution": 0, "median_s": exact["median_s"],
             "speedup": 1.0, "relmse_vs_exact": relmse(again, exact_img),
             "max_abs_vs_exact": float(np.max(np.abs(again - exact_img)))}]
    for n in s.table_resolutions:
        scene = mi.load_dict(scene_dict({**base, "method": "table", "table_resolution": n}, s.res))
        t = timed(scene, s.spp, s.repeats)
        img = np.array(_render(scene, s.spp, seed=99))[..., :3]
        rows.append({"name": f"table {n}", "table_resolution": n, "median_s": t["median_s"],
                     "speedup": exact["median_s"] / t["median_s"],
                     "relmse_vs_exact": relmse(img, exact_img),
                     "max_abs_vs_exact": float(np.max(np.abs(img - exact_img)))})
    return rows


def group_sampling(s: Settings, refs) -> list[dict]:
    import mitsuba as mi

    from . import catalog
    rows = []
    for name, config, strategies in catalog.BENCH_SAMPLING:
        reference = refs.get(scene_dict({**config, **strategies[0][1]}, s.res))
        for label, options in strategies:
            d = scene_dict({**config, **options}, s.res)
            scene = mi.load_dict(d)
            t = timed(scene, s.spp, s.repeats)
            img = np.array(_render(scene, s.spp, seed=7))[..., :3]
            err = relmse(img, reference)
            rows.append({"name": name, "strategy": label, "spp": s.spp,
                         "median_s": t["median_s"], "relmse": err,
                         "efficiency": efficiency(err, t["median_s"])})
        best = rows[-len(strategies)]["efficiency"]
        for r in rows[-len(strategies):]:
            r["efficiency_vs_first"] = r["efficiency"] / best if best else float("nan")
    return rows


INTEGRATORS = [
    ("scanline", {"type": "scanline", "clamp": False, "shadows": True}),
    ("direct", {"type": "direct"}),
    ("path depth 2", {"type": "path", "max_depth": 2}),
    ("path depth 3", {"type": "path", "max_depth": 3}),
    ("path depth 8", {"type": "path", "max_depth": 8}),
]


def group_integrators(s: Settings, refs) -> list[dict]:
    import mitsuba as mi
    bsdf = {"type": "cook_torrance", "distribution": "ggx", "alpha": 0.3, "k": 0.5}
    reference = refs.get(scene_dict(bsdf, s.res, {"type": "path", "max_depth": 16}))
    rows = []
    for name, integrator in INTEGRATORS:
        scene = mi.load_dict(scene_dict(bsdf, s.res, integrator))
        t = timed(scene, s.spp, s.repeats)
        img = np.array(_render(scene, s.spp, seed=5))[..., :3]
        err = relmse(img, reference)
        rows.append({"name": name, "median_s": t["median_s"], "relmse": err,
                     "efficiency": efficiency(err, t["median_s"])})
    return rows


def group_convergence(s: Settings, refs) -> list[dict]:
    import mitsuba as mi
    d = scene_dict({"type": "cook_torrance", "distribution": "ggx", "alpha": 0.3, "k": 0.5}, s.res)
    reference = refs.get(d)
    scene = mi.load_dict(d)
    rows = []
    for spp in s.spp_ladder:
        errors = [relmse(np.array(_render(scene, spp, seed=100 + i))[..., :3], reference)
                  for i in range(3)]
        rows.append({"spp": spp, "relmse": float(np.mean(errors))})
    x = np.log([r["spp"] for r in rows])
    y = np.log([r["relmse"] for r in rows])
    slope = float(np.polyfit(x, y, 1)[0])
    for r in rows:
        r["slope"] = slope
    return rows


def group_scaling(s: Settings, refs) -> list[dict]:
    import mitsuba as mi
    bsdf = {"type": "lambert", "mode": "scanline"}
    rows = []
    for res in s.resolutions:
        t = timed(mi.load_dict(scene_dict(bsdf, res, {"type": "scanline"})), s.spp, s.repeats)
        rows.append({"axis": "resolution", "value": res, "median_s": t["median_s"]})
    for n in s.light_counts:
        t = timed(mi.load_dict(scene_dict(bsdf, s.res, {"type": "scanline"}, lights=n)),
                  s.spp, s.repeats)
        rows.append({"axis": "lights", "value": n, "median_s": t["median_s"]})
    return rows


LOBES_OFF = [
    ("cook_torrance k=1 vs lambert",
     {"type": "cook_torrance", "k": 1.0, "diffuse_reflectance": 0.6},
     {"type": "lambert", "reflectance": 0.6}),
    ("phong m_S=0 vs lambert",
     {"type": "phong", "specular_reflectance": 0.0, "diffuse_reflectance": 0.6},
     {"type": "lambert", "reflectance": 0.6}),
    ("ward m_D=0 vs ward m_D=0.5",
     {"type": "ward", "diffuse_reflectance": 0.0, "alpha_u": 0.1, "alpha_v": 0.3},
     {"type": "ward", "diffuse_reflectance": 0.5, "alpha_u": 0.1, "alpha_v": 0.3}),
]


def group_lobes(s: Settings, refs) -> list[dict]:
    import mitsuba as mi
    rows = []
    for name, off, reference in LOBES_OFF:
        flags = mi.load_dict(off).flags()
        t_off = timed(mi.load_dict(scene_dict(off, s.res)), s.spp, s.repeats)
        t_ref = timed(mi.load_dict(scene_dict(reference, s.res)), s.spp, s.repeats)
        rows.append({"name": name, "lobe_off_s": t_off["median_s"],
                     "reference_s": t_ref["median_s"],
                     "ratio": t_off["median_s"] / t_ref["median_s"],
                     "diffuse_lobe": bool(flags & mi.BSDFFlags.Diffuse),
                     "glossy_lobe": bool(flags & mi.BSDFFlags.Glossy)})
    return rows


ENERGY_MODELS = [    # (name, configuration without energy_compensation)
    ("cook_torrance ggx smith", {"type": "cook_torrance", "distribution": "ggx",
                                 "geometry": "smith", "alpha": 0.5, "k": 0.3}),
    ("cook_torrance beckmann cook_torrance", {"type": "cook_torrance", "alpha": 0.5, "k": 0.3}),
    ("cook_torrance blinn smith", {"type": "cook_torrance", "distribution": "blinn",
                                   "geometry": "smith", "alpha": 0.5, "k": 0.3}),
    ("phong", {"type": "phong", "exponent": 10.0}),
    ("blinn", {"type": "blinn", "exponent": 10.0}),
    ("ward", {"type": "ward", "alpha": 0.3}),
    ("ward anisotropic", {"type": "ward", "alpha_u": 0.05, "alpha_v": 0.3}),
    ("oren_nayar (EON)", {"type": "oren_nayar", "sigma": 0.8}),
]


def group_energy(s: Settings, refs) -> list[dict]:
    import mitsuba as mi

    from ..bsdfs import energy
    built: dict[str, float] = {}
    rows = []
    for name, config in ENERGY_MODELS:
        t_off = timed(mi.load_dict(scene_dict(config, s.res)), s.spp, s.repeats)
        t_on = timed(mi.load_dict(scene_dict({**config, "energy_compensation": True}, s.res)),
                     s.spp, s.repeats)
        spec = mi.load_dict(config).albedo_spec()
        if spec is not None and spec.name not in built:
            start = time.perf_counter()
            energy.build(spec, s.table_samples)
            built[spec.name] = time.perf_counter() - start
        rows.append({"name": name, "off_s": t_off["median_s"], "on_s": t_on["median_s"],
                     "ratio": t_on["median_s"] / t_off["median_s"],
                     "table": spec.name if spec else "(analytic)",
                     "table_nodes": int(np.prod([a.n for a in spec.axes])) if spec else 0,
                     "table_samples": s.table_samples if spec else 0,
                     "table_build_s": built[spec.name] if spec else 0.0})
    return rows


# ----------------------------------------------------------------------------
#  Many materials, frozen passes, BSDF kernels, tracing: in processes of their own
# ----------------------------------------------------------------------------
#
# At every render Dr.Jit traces every BSDF instance alive in the process, so a
# measurement that depends on the number of instances (and on nothing else)
# runs in a fresh Python process: ``python -m mi_brdfs.tools.bench --worker
# TASK OPTIONS_JSON`` prints one result line, with the process's peak memory.

WORKER_MARK = "mi-brdfs-bench-result "

MATERIALS = {     # one material per sphere; t in [0, 1] is the sphere's place in the grid
    "cook_torrance": lambda t: {"type": "cook_torrance", "distribution": "ggx",
                                "geometry": "smith", "f0": 1.0, "k": 0.0,
                                "alpha": 0.05 + 0.5 * t},
    "roughconductor": lambda t: {"type": "roughconductor", "distribution": "ggx",
                                 "alpha": 0.05 + 0.5 * t},
    "lambert": lambda t: {"type": "lambert",
                          "reflectance": {"type": "rgb", "value": [0.2 + 0.6 * t, 0.5, 0.8 - 0.6 * t]}},
    "diffuse": lambda t: {"type": "diffuse",
                          "reflectance": {"type": "rgb", "value": [0.2 + 0.6 * t, 0.5, 0.8 - 0.6 * t]}},
}
MATERIAL_PAIRS = [("cook_torrance", "roughconductor"), ("lambert", "diffuse")]


def spheres_scene(kind: str, n: int, res: int, max_depth: int = 3) -> dict:
    """``n`` unit spheres in a square grid, each with its own ``kind`` material,
    in a constant environment, path traced (the issue's scene: 200 spheres,
    depth 3, 128², 64 spp)."""
    side = math.ceil(math.sqrt(n))
    spacing, fov = 2.5, 40.0
    distance = 1.2 * side * spacing / (2 * math.tan(math.radians(fov / 2))) + 2
    d = {"type": "scene", "integrator": {"type": "path", "max_depth": max_depth},
         "sensor": camera(res, fov, origin=(0.0, 0.0, distance)),
         "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}}}
    for i in range(n):
        x, y = (i % side - (side - 1) / 2) * spacing, (i // side - (side - 1) / 2) * spacing
        d[f"sphere{i}"] = {"type": "sphere", "center": [x, y, 0.0], "radius": 1.0,
                           "bsdf": MATERIALS[kind](i / max(n - 1, 1))}
    return d


def in_subprocess(task: str, **options) -> dict:
    """Run a worker task in a fresh Python process; its result (with peak_mib)."""
    import subprocess
    import sys
    run = subprocess.run([sys.executable, "-m", "mi_brdfs.tools.bench", "--worker", task,
                          json.dumps(options)], capture_output=True, text=True)
    lines = [line for line in run.stdout.splitlines() if line.startswith(WORKER_MARK)]
    if run.returncode != 0 or not lines:
        raise RuntimeError(f"bench worker {task} {options} failed:\n{run.stderr[-3000:]}")
    return json.loads(lines[-1][len(WORKER_MARK):])


def peak_mib() -> float:
    """This process's peak resident memory in MiB: Linux's VmHWM, the high-water
    mark of this program's own memory (ru_maxrss would also count the parent's
    resident memory at fork time: a worker of a large bench process reported
    the parent's 397 MiB for every kind), else ru_maxrss."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def worker_materials(kind: str, n: int, res: int, spp: int, repeats: int) -> dict:
    """First render of the spheres scene and the medians of ``repeats`` warm
    renders, each split into tracing, code generation and kernel execution (s),
    and the median of ``repeats`` replays of a frozen render."""
    import drjit as dr
    import mitsuba as mi
    start = time.perf_counter()
    # parallel=False as in the CLI: Python plugins loaded in worker threads failed
    # intermittently (bad_alloc).
    scene = mi.load_dict(spheres_scene(kind, n, res), parallel=False)
    result = {"load_s": time.perf_counter() - start}
    first = measured(lambda: _render(scene, spp, seed=0))
    warm = [measured(lambda: _render(scene, spp, seed=r + 1)) for r in range(repeats)]
    for part in ("wall", "tracing", "codegen", "execution"):
        result[f"first_{part}_s"] = first[f"{part}_s"]
        result[f"{part}_s"] = statistics.median(m[f"{part}_s"] for m in warm)
    # The same renders through a frozen function (as render passes and
    # GradientStep do): recorded once, then replayed without tracing.
    from ..render.frozen import FrozenRender
    frozen = FrozenRender()
    evaluated = lambda image: (dr.eval(image), dr.sync_thread())
    measured(lambda: evaluated(frozen(scene, spp, seed=0)))    # (Jit flags key the recording)
    replays = [measured(lambda: evaluated(frozen(scene, spp, seed=r + 1)))
               for r in range(repeats)]
    result["frozen_s"] = statistics.median(m["wall_s"] for m in replays)
    result["frozen_recordings"] = frozen.recordings
    return result


def worker_passes(n: int, res: int, spp: int, passes: int, freeze: bool, repeats: int) -> dict:
    """``render_passes`` of the cook_torrance spheres scene: the first call in
    the process (what ``mi-brdfs render`` does) and the median of the next."""
    import mitsuba as mi

    from ..render.passes import render_passes
    scene = mi.load_dict(spheres_scene("cook_torrance", n, res), parallel=False)
    messages: list[str] = []
    times = []
    for r in range(repeats + 1):
        messages.clear()
        start = time.perf_counter()
        render_passes(scene, spp, passes, seed=r, freeze=freeze, log=messages.append)
        times.append(time.perf_counter() - start)
    return {"first_s": times[0], "warm_s": statistics.median(times[1:]),
            "note": "; ".join(messages)}


MATERIALS_COLUMNS = {     # column: the worker's figure
    "first_s": "first_wall_s", "first_tracing_s": "first_tracing_s",
    "first_codegen_s": "first_codegen_s", "warm_s": "wall_s", "tracing_s": "tracing_s",
    "codegen_s": "codegen_s", "execution_s": "execution_s", "frozen_s": "frozen_s",
    "frozen_recordings": "frozen_recordings", "peak_mib": "peak_mib"}


def group_materials(s: Settings, refs) -> list[dict]:
    rows = []
    for plugin, builtin in MATERIAL_PAIRS:
        for n in s.materials:
            # Each (kind, n) in processes of its own, the kinds alternating; the
            # median over the rounds of each process's figures.
            runs: dict[str, list[dict]] = {plugin: [], builtin: []}
            for _ in range(s.rounds):
                for kind in (plugin, builtin):
                    runs[kind].append(in_subprocess("materials", kind=kind, n=n,
                                                    res=s.materials_res, spp=s.materials_spp,
                                                    repeats=s.repeats))
            row = {"name": f"{plugin} vs {builtin}", "materials": n}
            for side, kind in (("plugin", plugin), ("builtin", builtin)):
                for column, key in MATERIALS_COLUMNS.items():
                    row[f"{side}_{column}"] = statistics.median(r[key] for r in runs[kind])
            row["first_ratio"] = row["plugin_first_s"] / row["builtin_first_s"]
            row["warm_ratio"] = row["plugin_warm_s"] / row["builtin_warm_s"]
            row["execution_ratio"] = row["plugin_execution_s"] / row["builtin_execution_s"]
            row["frozen_ratio"] = row["plugin_frozen_s"] / row["builtin_frozen_s"]
            row["memory_ratio"] = row["plugin_peak_mib"] / row["builtin_peak_mib"]
            rows.append(row)
    return rows


def group_frozen(s: Settings, refs) -> list[dict]:
    n = s.materials[-1]
    rows = []
    for passes in s.frozen_passes:
        for freeze in ((False,) if passes == 1 else (False, True)):
            r = in_subprocess("passes", n=n, res=s.materials_res, spp=s.materials_spp,
                              passes=passes, freeze=freeze, repeats=3)
            rows.append({"materials": n, "spp": s.materials_spp, "passes": passes,
                         "frozen": freeze, "first_s": r["first_s"], "warm_s": r["warm_s"],
                         "peak_mib": r["peak_mib"], "note": r["note"]})
    one = next(r for r in rows if r["passes"] == 1)
    for r in rows:
        r["first_vs_1_pass"] = r["first_s"] / one["first_s"]
        r["warm_vs_1_pass"] = r["warm_s"] / one["warm_s"]
    return rows


# --- BSDF calls on direction pairs ---------------------------------------------

BSDF_PAIRS = [     # (name, plugin, built-in): the same BSDF (up to float error, or the G1 fit)
    ("cook_torrance ggx vs roughconductor ggx",
     {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith", "f0": 1.0, "k": 0.0,
      "alpha": 0.3},
     {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3}),
    ("cook_torrance beckmann vs roughconductor beckmann",
     {"type": "cook_torrance", "distribution": "beckmann", "geometry": "smith", "f0": 1.0,
      "k": 0.0, "alpha": 0.3},
     {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.3}),
    ("lambert vs diffuse", {"type": "lambert", "reflectance": 0.6},
     {"type": "diffuse", "reflectance": 0.6}),
]
TWO_LOBES = ("cook_torrance ggx k=0.5 vs roughplastic ggx",
             {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith", "k": 0.5,
              "alpha": 0.3},
             {"type": "roughplastic", "distribution": "ggx", "alpha": 0.3})
BSDF_METHODS = ("eval", "pdf", "eval_pdf", "sample")


def bsdf_inputs(lanes: int, seed: int = 1) -> dict:
    """Random viewer and light directions above the surface and random samples,
    evaluated (a kernel then holds the BSDF alone)."""
    import drjit as dr
    import mitsuba as mi
    rng = np.random.default_rng(seed)

    def hemisphere():
        v = rng.normal(size=(3, lanes))
        v /= np.linalg.norm(v, axis=0)
        v[2] = np.abs(v[2])
        return mi.Vector3f(*v.astype(np.float32))
    si = dr.zeros(mi.SurfaceInteraction3f, lanes)
    si.wi = hemisphere()
    si.uv = mi.Point2f(*rng.random((2, lanes), dtype=np.float32))
    x = {"ctx": mi.BSDFContext(), "si": si, "wo": hemisphere(),
         "sample1": mi.Float(rng.random(lanes, dtype=np.float32)),
         "sample2": mi.Point2f(*rng.random((2, lanes), dtype=np.float32))}
    dr.eval(x["si"].wi, x["si"].uv, x["wo"], x["sample1"], x["sample2"])
    return x


def bsdf_call(bsdf, method: str, x: dict):
    if method == "sample":
        return bsdf.sample(x["ctx"], x["si"], x["sample1"], x["sample2"])
    return getattr(bsdf, method)(x["ctx"], x["si"], x["wo"])


def worker_kernels(lanes: int, repeats: int) -> dict:
    """Kernel execution time of each BSDF call, plugin and built-in alternating,
    medians over ``repeats`` rounds after a compiling one.

    On one thread: with Dr.Jit's thread pool on cores shared with other
    processes, a kernel of a few ms took 1.9 or 5.8 ms depending on whether a
    worker thread was descheduled (whichever kind ran first in a round, per
    process); single-threaded, both took 1.8-1.9 ms in every round."""
    import drjit as dr
    import mitsuba as mi
    dr.set_thread_count(1)
    x = bsdf_inputs(lanes)
    pairs = [(name, mi.load_dict(p), mi.load_dict(b)) for name, p, b in BSDF_PAIRS]
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


class _CountingTexture:
    """Forwards to a texture and counts its evaluations (the tracing group)."""

    def __init__(self, texture, counter: list[int]):
        self._texture, self._counter = texture, counter

    def __getattr__(self, name):
        value = getattr(self._texture, name)
        if not name.startswith("eval"):
            return value

        def counted(*args, **kwargs):
            self._counter[0] += 1
            return value(*args, **kwargs)
        return counted


def _profile(run):
    import cProfile
    import pstats
    profile = cProfile.Profile()
    profile.enable()
    run()
    profile.disable()
    return pstats.Stats(profile).stats   # {(file, line, name): (cc, nc, tt, ct, callers)}


def _is_bsdf_method(key) -> bool:
    return key[0].replace(os.sep, "/").endswith("bsdfs/base.py") and key[2] in BSDF_METHODS


def call_anatomy(bsdf, method: str, x: dict) -> dict:
    """What one traced call of a plugin method does: Python function calls,
    texture evaluations, MicrofacetDistribution objects built, the BSDF
    methods it calls again, and the helpers called more than once."""
    import mitsuba as mi
    textures = {k: v for k, v in vars(bsdf).items() if isinstance(v, mi.Texture)}
    evals, built = [0], [0]
    original = mi.MicrofacetDistribution

    def counting(*args, **kwargs):
        built[0] += 1
        return original(*args, **kwargs)
    for k, v in textures.items():
        setattr(bsdf, k, _CountingTexture(v, evals))
    mi.MicrofacetDistribution = counting
    try:
        stats = _profile(lambda: bsdf_call(bsdf, method, x))
    finally:
        mi.MicrofacetDistribution = original
        for k, v in textures.items():
            setattr(bsdf, k, v)
    ours = {k: v[1] for k, v in stats.items() if "mi_brdfs" in k[0] and k[0] != __file__}
    inner = {k[2]: n - (k[2] == method) for k, n in ours.items() if _is_bsdf_method(k)}
    return {"python_calls": sum(ours.values()), "texture_evals": evals[0],
            "microfacet_objects": built[0],
            "inner_calls": ", ".join(f"{m} x{n}" for m, n in sorted(inner.items()) if n),
            "repeated": ", ".join(f"{k[2]} x{n}" for k, n in sorted(ours.items(), key=lambda kv: -kv[1])
                                  if n > 1 and not _is_bsdf_method(k))}


def calls_in_a_render(config: dict) -> dict[str, list[int]]:
    """Per BSDF method: [calls by Mitsuba, all calls] of one plugin instance
    while one path-traced render (depth 3) is traced."""
    import mitsuba as mi
    scene = mi.load_dict(scene_dict(config, 8, plane=False), parallel=False)
    stats = _profile(lambda: _render(scene, 1, seed=0))
    counts = {m: [0, 0] for m in BSDF_METHODS}
    for key, (_, nc, _, _, callers) in stats.items():
        if _is_bsdf_method(key):
            counts[key[2]][0] += sum(c[1] for k, c in callers.items() if "mi_brdfs" not in k[0])
            counts[key[2]][1] += nc
    return counts


def worker_tracing(lanes: int, calls: int) -> dict:
    """Tracing time of each BSDF call (no evaluation), plugin vs built-in, and
    the anatomy of the plugin's call."""
    import gc

    import mitsuba as mi
    pairs = [*BSDF_PAIRS, TWO_LOBES]
    # First, while no other BSDF is alive: a render traces every live instance.
    in_render = {}
    for name, p, _ in pairs:
        in_render[name] = calls_in_a_render(p)
        gc.collect()
    x = bsdf_inputs(lanes)
    rows = []
    for name, p, b in pairs:
        plugin, builtin = mi.load_dict(p), mi.load_dict(b)
        for method in BSDF_METHODS:
            row = {"name": name, "method": method}
            for side, bsdf in (("plugin", plugin), ("builtin", builtin)):
                bsdf_call(bsdf, method, x)
                times = []
                for _ in range(calls):
                    start = time.perf_counter()
                    out = bsdf_call(bsdf, method, x)
                    times.append(time.perf_counter() - start)
                    del out
                row[f"{side}_ms"] = 1e3 * statistics.median(times)
            row["ratio"] = row["plugin_ms"] / row["builtin_ms"]
            row["render_calls"], row["render_calls_all"] = in_render[name][method]
            row.update(call_anatomy(plugin, method, x))
            rows.append(row)
    return {"rows": rows}


def group_kernels(s: Settings, refs) -> list[dict]:
    return in_subprocess("kernels", lanes=s.kernel_lanes, repeats=s.repeats)["rows"]


def group_tracing(s: Settings, refs) -> list[dict]:
    return in_subprocess("tracing", lanes=1024, calls=25 * s.repeats)["rows"]


WORKERS = {"materials": worker_materials, "passes": worker_passes, "kernels": worker_kernels,
           "tracing": worker_tracing}


def worker_main(task: str, options: str) -> int:
    """``python -m mi_brdfs.tools.bench --worker TASK OPTIONS_JSON``: one result line."""
    import mi_brdfs  # noqa: F401  (LLVM set-up, plugins registered)
    result = WORKERS[task](**json.loads(options))
    result["peak_mib"] = peak_mib()
    print(WORKER_MARK + json.dumps(result), flush=True)
    return 0


RUNNERS = {"builtin": group_builtin, "models": group_models, "oren_nayar": group_oren_nayar,
           "sampling": group_sampling, "integrators": group_integrators,
           "convergence": group_convergence, "scaling": group_scaling, "lobes": group_lobes,
           "energy": group_energy,
           "materials": group_materials, "frozen": group_frozen, "kernels": group_kernels,
           "tracing": group_tracing}


# ----------------------------------------------------------------------------
#  Outputs
# ----------------------------------------------------------------------------

def machine() -> dict:
    import drjit as dr
    import mitsuba as mi
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


def findings(results: dict) -> list[str]:
    """Plain-language answers, computed from the numbers of this run."""
    g, out = results["groups"], []
    if g.get("builtin"):
        ratios = ", ".join(f"{r['name'].split(' vs ')[0]} {r['ratio']:.3f}" for r in g["builtin"])
        out.append(f"Python plugin / C++ built-in time ratio: {ratios} (parity is <= 1.05). "
                   "Tracing the Python code takes "
                   + ", ".join(f"{1e3 * r['plugin_tracing_s']:.2f} ms" for r in g["builtin"])
                   + " per render; kernel execution time ratios: "
                   + ", ".join(f"{r['plugin_execution_s'] / r['builtin_execution_s']:.3f}"
                               for r in g["builtin"]) + ".")
    if g.get("models"):
        worst = max(g["models"], key=lambda r: r["relative_to_lambert"])
        out.append(f"Model cost: every model renders within {worst['relative_to_lambert']:.2f}x "
                   f"of lambert on this scene (slowest: {worst['name']}); the BSDF is a small "
                   "part of a path-traced sample's cost.")
    if g.get("oren_nayar"):
        tables = [r for r in g["oren_nayar"] if r["table_resolution"]]
        best = max(tables, key=lambda r: r["speedup"])
        out.append(f"Oren-Nayar table: best speed-up {best['speedup']:.3f}x (resolution "
                   f"{best['table_resolution']}); relMSE vs exact from "
                   f"{tables[0]['relmse_vs_exact']:.2g} (resolution {tables[0]['table_resolution']}) "
                   f"to {tables[-1]['relmse_vs_exact']:.2g} ({tables[-1]['table_resolution']})."
                   + (" The table buys no measurable time here (< 5 %): on this CPU the "
                      "trigonometry is not the bottleneck." if best["speedup"] < 1.05 else ""))
    if g.get("sampling"):
        cos = [r for r in g["sampling"] if r["strategy"] == "cosine"]
        gains = ", ".join(f"{r['name']} {1 / r['efficiency_vs_first']:.0f}x" for r in cos)
        out.append(f"Importance sampling vs cosine sampling, efficiency gain: {gains}.")
    if g.get("integrators"):
        rows = {r["name"]: r for r in g["integrators"]}
        if "scanline" in rows and "path depth 8" in rows:
            s_, p_ = rows["scanline"], rows["path depth 8"]
            out.append(f"Scan-line direct lighting takes {s_['median_s'] / p_['median_s']:.2f}x the "
                       f"time of path tracing (depth 8) and has {s_['relmse'] / p_['relmse']:.1f}x its "
                       "relMSE against converged path tracing (it has no indirect light and no "
                       "environment light).")
    if g.get("convergence"):
        out.append(f"Convergence: relMSE vs spp has log-log slope {g['convergence'][0]['slope']:.2f}.")
    if g.get("scaling"):
        lights = [r for r in g["scaling"] if r["axis"] == "lights"]
        if len(lights) > 1:
            slope = np.polyfit([r["value"] for r in lights], [r["median_s"] for r in lights], 1)[0]
            out.append(f"Scan-line cost per extra light: {1e3 * slope:.2f} ms "
                       f"(on {lights[0]['median_s'] * 1e3:.1f} ms for one light).")
    if g.get("lobes"):
        ratios = ", ".join(f"{r['name']} {r['ratio']:.3f}" for r in g["lobes"])
        verdict = ("within 5 %: a lobe that is off is not traced" if
                   all(r["ratio"] < 1.05 for r in g["lobes"]) else
                   "above 1.05 somewhere: a dead lobe may still be traced (a bug)")
        out.append(f"Lobes switched off, time against the model without them: {ratios} ({verdict}).")
    if g.get("energy"):
        rows = g["energy"]
        ratios = ", ".join(f"{r['name']} {r['ratio']:.2f}x" for r in rows)
        tables = [r for r in rows if r["table_build_s"] > 0]
        out.append(f"Energy compensation, render time on / off: {ratios} (goal <= 1.10: "
                   f"{'met' if all(r['ratio'] <= 1.10 for r in rows) else 'not met'}). "
                   f"Building a table ({tables[0]['table_samples']}² samples per node): "
                   + ", ".join(f"{r['table']} {r['table_build_s']:.2f} s" for r in tables) + ".")
    if g.get("materials"):
        out.append(materials_finding(g["materials"]))
    if g.get("frozen"):
        rows = g["frozen"]
        traced = {r["passes"]: r for r in rows if not r["frozen"]}
        frozen = {r["passes"]: r for r in rows if r["frozen"]}
        parts = ", ".join(f"{p} passes {traced[p]['first_vs_1_pass']:.2f}x traced and "
                          f"{r['first_vs_1_pass']:.2f}x frozen" for p, r in frozen.items())
        out.append(f"Rendering in passes ({rows[0]['materials']} cook_torrance materials, "
                   f"{rows[0]['spp']} spp in all, the first render_passes call of a fresh process "
                   f"as in mi-brdfs render), time against one pass: {parts}.")
    if g.get("kernels"):
        rows = g["kernels"]
        parts = "; ".join(
            f"{name}: " + ", ".join(f"{r['method']} {r['ratio']:.2f}" for r in rows
                                    if r["name"] == name)
            for name in dict.fromkeys(r["name"] for r in rows))
        out.append(f"BSDF kernels ({rows[0]['lanes']} direction pairs), plugin / built-in kernel "
                   f"execution time: {parts}.")
    if g.get("tracing"):
        rows = g["tracing"]
        name = rows[0]["name"]
        r = {row["method"]: row for row in rows if row["name"] == name}
        out.append(
            f"Tracing one call ({name}): sample {r['sample']['plugin_ms']:.3f} ms vs "
            f"{r['sample']['builtin_ms']:.3f} ms ({r['sample']['ratio']:.1f}x), eval_pdf "
            f"{r['eval_pdf']['plugin_ms']:.3f} vs {r['eval_pdf']['builtin_ms']:.3f} ms "
            f"({r['eval_pdf']['ratio']:.1f}x). Tracing a path-traced render calls each "
            f"instance's sample {r['sample']['render_calls']} and eval_pdf "
            f"{r['eval_pdf']['render_calls']} times (eval and pdf "
            f"{r['eval']['render_calls_all']} times); one sample call makes "
            f"{r['sample']['texture_evals']} texture evaluations and builds "
            f"{r['sample']['microfacet_objects']} MicrofacetDistribution objects.")
    return out


def materials_finding(rows: list[dict]) -> str:
    """Plugin vs built-in at the largest number of materials, and the tracing
    cost per material (slope of the warm render's tracing time over N)."""
    most = max(r["materials"] for r in rows)
    ratios = ", ".join(
        f"{r['name'].split(' vs ')[0]} {r['warm_ratio']:.2f}x (first render "
        f"{r['first_ratio']:.2f}x, kernel execution {r['execution_ratio']:.2f}x, frozen replay "
        f"{r['frozen_ratio']:.2f}x, peak memory "
        f"{r['plugin_peak_mib']:.0f} vs {r['builtin_peak_mib']:.0f} MiB)"
        for r in rows if r["materials"] == most)
    slopes = []
    for name in dict.fromkeys(r["name"] for r in rows):
        pair = [r for r in rows if r["name"] == name]
        if len(pair) > 1:
            n = [r["materials"] for r in pair]
            per = [1e3 * np.polyfit(n, [r[f"{side}_tracing_s"] for r in pair], 1)[0]
                   for side in ("plugin", "builtin")]
            slopes.append(f"{name} {per[0]:.2f} vs {per[1]:.2f} ms")
    return (f"{most} spheres, each with its own material: plugin / built-in warm render time "
            f"{ratios}. Tracing per material (plugin vs built-in): {', '.join(slopes)}.")


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def write_outputs(out_dir: str, results: dict) -> None:
    from ..render.exr import write_atomically
    os.makedirs(out_dir, exist_ok=True)
    write_atomically(os.path.join(out_dir, "results.json"),
                     lambda p: open(p, "w").write(json.dumps(results, indent=1)))

    def write_csv(path):
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["group", "row", "key", "value"])
            for group, rows in results["groups"].items():
                for i, row in enumerate(rows):
                    for k, v in row.items():
                        if not isinstance(v, list):
                            w.writerow([group, i, k, v])
    write_atomically(os.path.join(out_dir, "results.csv"), write_csv)

    lines = ["# mi-brdfs bench results", "",
             f"{results['settings_name']} run, {results['seconds']:.0f} s ("
             + ", ".join(f"{g} {t:.0f} s" for g, t in results.get("group_seconds", {}).items())
             + "). Machine: "
             + ", ".join(f"{k} {v}" for k, v in results["machine"].items()) + ".", "",
             "Timings are medians of repeated renders after a warm-up (compile) render, "
             "in one process (materials, frozen, kernels, tracing: in processes of their own, "
             "as Dr.Jit traces every BSDF instance alive in the process); errors are relative "
             "MSE against a converged reference.", "",
             "## Findings", "", *(f"- {line}" for line in findings(results)), ""]
    for group, rows in results["groups"].items():
        if not rows:
            continue
        keys = [k for k in rows[0] if not isinstance(rows[0][k], list)]
        lines += [f"## {group}", "", "| " + " | ".join(keys) + " |",
                  "|" + "---|" * len(keys)]
        lines += ["| " + " | ".join(_fmt(r[k]) for k in keys) + " |" for r in rows]
        lines += ["", *(f"![{p}]({p})" for p in results["plots"].get(group, [])), ""]
    write_atomically(os.path.join(out_dir, "README.md"),
                     lambda p: open(p, "w").write("\n".join(lines)))


def plots(out_dir: str, results: dict) -> dict[str, list[str]]:
    from matplotlib.figure import Figure    # no pyplot: no global backend change

    made: dict[str, list[str]] = {}
    g = results["groups"]

    def save(fig, group, name):
        fig.tight_layout()
        fig.savefig(os.path.join(out_dir, name), dpi=90)
        made.setdefault(group, []).append(name)

    if g.get("convergence"):
        rows = g["convergence"]
        fig = Figure(figsize=(4.5, 3.2))
        ax = fig.subplots()
        ax.loglog([r["spp"] for r in rows], [r["relmse"] for r in rows], "o-")
        ax.set_xlabel("spp")
        ax.set_ylabel("relMSE")
        ax.set_title(f"convergence, slope {rows[0]['slope']:.2f}")
        save(fig, "convergence", "convergence.png")
    if g.get("scaling"):
        fig = Figure(figsize=(8, 3.2))
        axes = fig.subplots(1, 2)
        for ax, axis in zip(axes, ("resolution", "lights")):
            rows = [r for r in g["scaling"] if r["axis"] == axis]
            ax.plot([r["value"] for r in rows], [r["median_s"] for r in rows], "o-")
            ax.set_xlabel(axis)
            ax.set_ylabel("seconds")
        save(fig, "scaling", "scaling.png")
    def scatter(group, rows, label, time_key, error_key, title, name):
        """Error against time, the Pareto front marked."""
        points = [(r[time_key], max(r[error_key], 1e-12)) for r in rows]
        front = pareto(points)
        fig = Figure(figsize=(5, 3.6))
        ax = fig.subplots()
        for (t, e), r, on in zip(points, rows, front):
            ax.semilogy(t, e, "o", color="C3" if on else "C0")
            ax.annotate(label(r), (t, e), fontsize=6)
        xs, ys = zip(*sorted(p for p, on in zip(points, front) if on))
        ax.plot(xs, ys, "-", color="C3", lw=0.8, label="Pareto front")
        ax.set_xlabel("seconds")
        ax.set_ylabel(error_key)
        ax.set_title(title, fontsize=9)
        ax.legend(fontsize=7)
        save(fig, group, name)

    def bars(group, rows, key, title, name, ref=1.0):
        fig = Figure(figsize=(6, 0.35 * len(rows) + 1.2))
        ax = fig.subplots()
        ax.barh([r["name"] for r in rows], [r[key] for r in rows])
        ax.axvline(ref, color="k", lw=0.6)
        ax.invert_yaxis()
        ax.tick_params(labelsize=7)
        ax.set_xlabel(key)
        ax.set_title(title, fontsize=9)
        save(fig, group, name)

    if g.get("builtin"):
        bars("builtin", g["builtin"], "ratio", "plugin time / built-in time (parity: 1)",
             "builtin.png")
    if g.get("models"):
        bars("models", g["models"], "relative_to_lambert", "render time / lambert's", "models.png")
    if g.get("lobes"):
        bars("lobes", g["lobes"], "ratio", "lobe switched off / model without it", "lobes.png")
    if g.get("oren_nayar"):
        scatter("oren_nayar", g["oren_nayar"], lambda r: r["name"], "median_s",
                "relmse_vs_exact", "Oren-Nayar table vs exact", "oren_nayar.png")
    if g.get("sampling"):
        for name in dict.fromkeys(r["name"] for r in g["sampling"]):
            rows = [r for r in g["sampling"] if r["name"] == name]
            scatter("sampling", rows, lambda r: r["strategy"], "median_s", "relmse",
                    f"{name}, {rows[0]['spp']} spp", f"sampling_{len(made.get('sampling', []))}.png")
    if g.get("integrators"):
        scatter("integrators", g["integrators"], lambda r: r["name"], "median_s", "relmse",
                "vs converged path tracing", "integrators.png")
    if g.get("materials"):
        fig = Figure(figsize=(8, 3.2))
        names = list(dict.fromkeys(r["name"] for r in g["materials"]))
        for ax, name in zip(fig.subplots(1, len(names), squeeze=False)[0], names):
            rows = [r for r in g["materials"] if r["name"] == name]
            n = [r["materials"] for r in rows]
            for side, style in (("plugin", "o-"), ("builtin", "s--")):
                ax.plot(n, [r[f"{side}_warm_s"] for r in rows], style, label=f"{side} warm")
                ax.plot(n, [r[f"{side}_tracing_s"] for r in rows], style, alpha=0.5,
                        label=f"{side} tracing")
                ax.plot(n, [r[f"{side}_frozen_s"] for r in rows], style, alpha=0.25,
                        label=f"{side} frozen replay")
            ax.set_xlabel("materials")
            ax.set_ylabel("seconds")
            ax.set_title(name, fontsize=8)
            ax.legend(fontsize=6)
        save(fig, "materials", "materials.png")
    if g.get("frozen"):
        rows = [{"name": f"{r['passes']} passes{' frozen' if r['frozen'] else ''}",
                 "first_vs_1_pass": r["first_vs_1_pass"]} for r in g["frozen"]]
        bars("frozen", rows, "first_vs_1_pass", "time / one pass's (same spp)", "frozen.png")
    for group in ("kernels", "tracing"):
        if g.get(group):
            rows = [{"name": f"{r['name'].split(' vs ')[0]}: {r['method']}", "ratio": r["ratio"]}
                    for r in g[group]]
            what = "kernel execution" if group == "kernels" else "tracing one call"
            bars(group, rows, "ratio", f"plugin / built-in, {what} (parity: 1)", f"{group}.png")
    return made


def run(out_dir: str, quick: bool = False, only: list[str] | None = None,
        cache_dir: str | None = None, log=print) -> dict:
    import mi_brdfs  # noqa: F401  (plugins registered)

    settings = QUICK if quick else FULL
    groups = only or list(GROUPS)
    for g in groups:
        if g not in RUNNERS:
            raise ValueError(f"unknown bench group {g!r}; valid: {', '.join(GROUPS)}")
    cache = cache_dir or os.path.join(os.path.expanduser("~"), ".cache", "mi_brdfs", "references")
    refs = References(cache, settings.ref_spp)
    start = time.perf_counter()
    results = {"settings_name": "quick" if quick else "full", "settings": settings.__dict__,
               "machine": machine(), "groups": {}, "group_seconds": {}}
    for g in groups:
        log(f"bench: {g} ...")
        group_start = time.perf_counter()
        results["groups"][g] = RUNNERS[g](settings, refs)
        results["group_seconds"][g] = time.perf_counter() - group_start
    results["seconds"] = time.perf_counter() - start
    os.makedirs(out_dir, exist_ok=True)
    results["plots"] = plots(out_dir, results)
    write_outputs(out_dir, results)
    return results


if __name__ == "__main__":
    import sys
    if len(sys.argv) == 4 and sys.argv[1] == "--worker":
        sys.exit(worker_main(sys.argv[2], sys.argv[3]))
    sys.exit("usage: python -m mi_brdfs.tools.bench --worker TASK OPTIONS_JSON (else: mi-brdfs bench)")
