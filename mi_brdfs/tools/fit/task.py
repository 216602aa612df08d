"""One fit, target × model, as a worker runs it (in a process of its own or
on a Dask worker): the model's parameters fitted to the target's values at
the metric's direction pairs by Adam (Dr.Jit's AD) from several starts, then
renders and render cost in the standard scene (:mod:`.scene`).

The optimisation: the unit coordinates y of the free parameters
(:mod:`.models`) are Adam's variables; each step sets the plugin's public
parameters (``mi.traverse`` keys) to their values, evaluates ``eval`` at every
pair, and minimises the relative squared error E²/E²(0) of the metric. The
learning rate decays geometrically from ``lr`` to ``lr_end`` over the steps;
y is clipped to [0, 1] after each. Every start runs the same schedule; the
start with the lowest final error wins.
"""
from __future__ import annotations

import math
import time
import traceback
from dataclasses import asdict, dataclass, field

import numpy as np

from ..._jit import from_numpy

SLICE_ANGLES = (0.0, 30.0, 60.0, 80.0)     # viewer angles of the lobe slices (degrees)
SLICE_POINTS = 181
HOLD = 0.5                                  # the share of the steps at the full learning rate


@dataclass(frozen=True)
class Settings:
    """How much work one fit does (:data:`QUICK`, :data:`FULL`)."""
    metric: str = "cosine"
    viewers: tuple[int, int] = (12, 6)       # viewer strata (cos θ, φ)
    uniform: tuple[int, int] = (12, 12)      # uniform light strata per viewer
    lobe: int = 36                           # mirror-guided lights per viewer and roughness
    starts: int = 3
    steps: int = 250
    lr: float = 0.05
    lr_end: float = 1e-3
    res: int = 128                           # the standard scene
    spp: int = 64
    rounds: int = 4                          # side-by-side timing rounds
    render: bool = True                      # renders, image error and cost (else: the fit only)

    def replace(self, **changes) -> "Settings":
        return Settings(**{**asdict(self), **changes})


FULL = Settings()
QUICK = Settings(viewers=(8, 4), uniform=(8, 8), lobe=16, starts=2, steps=120, res=48, spp=16,
                 rounds=2)


# ----------------------------------------------------------------------------
#  Evaluating BSDFs at the pairs
# ----------------------------------------------------------------------------

@dataclass
class Problem:
    """The pairs as Dr.Jit arrays and the target's values there."""
    si: object
    wo: object
    weight: object           # mi.Float
    target: object           # mi.Color3f (eval of the target)
    norm: float              # Σ w ‖target‖²: E²(0)
    arrays: dict = field(default_factory=dict)     # NumPy copies (weight, target)


def problem(target_bsdf, pairs) -> Problem:
    import drjit as dr
    import mitsuba as mi
    n = len(pairs.wi)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = from_numpy(mi.Vector3f, pairs.wi.T)
    si.uv = mi.Point2f(0.5, 0.5)
    wo = from_numpy(mi.Vector3f, pairs.wo.T)
    values = values_of(target_bsdf, si, wo)
    finite = np.isfinite(values).all(axis=1)
    values = np.where(finite[:, None], values, 0.0)
    weight = np.where(finite, pairs.weight, 0.0)
    norm = float(np.sum(weight * np.sum(values ** 2, axis=1)))
    return Problem(si, wo, from_numpy(mi.Float, weight), from_numpy(mi.Color3f, values.T),
                   norm, {"weight": weight, "target": values})


def values_of(bsdf, si, wo) -> np.ndarray:
    """eval at the pairs as (N, 3) float64."""
    import mitsuba as mi
    value = np.array(bsdf.eval(mi.BSDFContext(), si, wo), dtype=np.float64)
    return value.T if value.ndim == 2 else np.repeat(value[:, None], 3, axis=1)


# ----------------------------------------------------------------------------
#  The optimisation
# ----------------------------------------------------------------------------

def fit_model(model, prob: Problem, settings: Settings, log=None) -> dict:
    """Fit ``model`` (a :class:`.models.Model`) to ``prob``; returns the fitted
    properties, the BRDF error and what each start reached."""
    import drjit as dr
    import mitsuba as mi

    from ...bsdfs import BY_NAME
    from . import models as M
    cls = BY_NAME[model.plugin]
    defaults = {p.name: p.default for p in cls.PARAMS}
    probe = mi.load_dict(model.properties())
    free = M.free_parameters(cls, list(mi.traverse(probe).keys()))
    del probe
    points = M.starts(free, defaults, settings.starts)
    results = []
    for y0 in points:
        unit = M.split(free, y0)
        props = model.properties()
        props.update({f.name: (list(f.value(np.array(unit[f.name]))) if f.colour
                               else float(f.value(unit[f.name]))) for f in free})
        bsdf = mi.load_dict(M.load_dict(props))
        params = mi.traverse(bsdf)
        opt = mi.ad.Adam(lr=settings.lr)
        for f in free:
            opt[f.key] = (mi.Color3f(*map(float, unit[f.name])) if f.colour
                          else mi.Float(float(unit[f.name])))
        history = []
        steps = settings.steps                  # 0: the start as it is (no descent)
        for it in range(steps):
            opt.set_learning_rate(learning_rate(settings, it / steps))
            for f in free:
                params[f.key] = dr.clip(f.value(opt[f.key]), f.lo, f.hi)
            params.update()
            value = bsdf.eval(mi.BSDFContext(), prob.si, prob.wo)
            loss = dr.sum(prob.weight * dr.sum(dr.square(value - prob.target), axis=0),
                          axis=None) / prob.norm
            dr.backward(loss)
            opt.step()
            for f in free:
                opt[f.key] = dr.clip(opt[f.key], 0.0, 1.0)
            if it % 25 == 0 or it == steps - 1:
                history.append(float(loss.array[0]))
        fitted = {}
        for f in free:
            v = np.array(dr.detach(dr.clip(f.value(opt[f.key]), f.lo, f.hi)), dtype=np.float64).ravel()
            fitted[f.name] = [float(c) for c in v[:3]] if f.colour else float(v[0])
        for f in free:
            params[f.key] = (mi.Color3f(*fitted[f.name]) if f.colour else mi.Float(fitted[f.name]))
        params.update()
        error = relative(values_of(bsdf, prob.si, prob.wo), prob)
        results.append({"start": [float(v) for v in y0], "error": error, "history": history,
                        "parameters": {**model.properties(), **fitted}})
        if log:
            log(f"{model.name}: start {len(results)}/{len(points)}: error {error:.4g}")
        del bsdf, params, opt
    best = min(results, key=lambda r: r["error"] if math.isfinite(r["error"]) else math.inf)
    return {"parameters": best["parameters"], "brdf_error": best["error"],
            "starts": [{"error": r["error"], "history": r["history"]} for r in results]}


def learning_rate(settings: Settings, t: float) -> float:
    """lr for the first HOLD of the steps (t in [0, 1)), then geometrically down to lr_end."""
    if t < HOLD:
        return settings.lr
    return settings.lr * (settings.lr_end / settings.lr) ** ((t - HOLD) / (1.0 - HOLD))


def relative(values: np.ndarray, prob: Problem) -> float:
    w, t = prob.arrays["weight"], prob.arrays["target"]
    values = np.where(np.isfinite(values), values, np.inf)
    num = float(np.sum(w * np.sum((values - t) ** 2, axis=1)))
    return math.sqrt(num / prob.norm) if prob.norm > 0 else math.nan


def slices(bsdf) -> list[list[float]]:
    """eval (channel mean) in the plane of incidence at each SLICE_ANGLES viewer."""
    from ..analysis import plane_of_incidence
    return [plane_of_incidence(bsdf, a, SLICE_POINTS)[1].tolist() for a in SLICE_ANGLES]


# ----------------------------------------------------------------------------
#  One task
# ----------------------------------------------------------------------------

def run(target, model, settings: Settings, pairs=None) -> dict:
    """Fit ``model`` to ``target`` (a :class:`.targets.Target`) and measure it.
    Never raises: a failure is returned as a record with an ``error`` message."""
    try:
        return _run(target, model, settings, pairs)
    except Exception as error:                     # reported in the record, not lost
        from ..errors import one_line
        return {"target": target.spec, "model": model.name, "plugin": model.plugin,
                "error": one_line(error), "traceback": traceback.format_exc()}


def _run(target, model, settings: Settings, pairs) -> dict:
    import mi_brdfs  # noqa: F401  (LLVM, the variant, the plugins: in every worker)
    import mitsuba as mi

    from . import metric, models as M, scene
    if mi.variant() != "llvm_ad_rgb":
        mi.set_variant("llvm_ad_rgb")
        mi_brdfs.register()
    start = time.perf_counter()
    if pairs is None:
        pairs = metric.pairs(settings.metric, settings.viewers, settings.uniform, settings.lobe)
    target_bsdf = target.load()
    prob = problem(target_bsdf, pairs)
    if not prob.norm > 0:
        raise ValueError(f"target {target.spec} reflects no light at the metric's pairs")
    target_slices = slices(target_bsdf)
    del target_bsdf
    fit = fit_model(model, prob, settings)
    fitted = mi.load_dict(M.load_dict(fit["parameters"]))
    model_slices = slices(fitted)
    del fitted, prob
    seconds = time.perf_counter() - start
    record = {"target": target.spec, "target_name": target.name, "model": model.name,
              "plugin": model.plugin, "parameters": fit["parameters"],
              "brdf_error": fit["brdf_error"], "metric": settings.metric,
              "image_relmse": None, "image_flip": None, "image_noise_relmse": None,
              "cost_ratio": None, "seconds": seconds, "starts": fit["starts"],
              "slices": {"angles": list(SLICE_ANGLES), "target": target_slices,
                         "model": model_slices}}
    if settings.render:
        scene.release()
        record.update(measure(target, fit["parameters"], settings))
    return record


def measure(target, properties: dict, settings: Settings) -> dict:
    """Image error and render cost of the fitted model against the target."""
    from .. import compare
    from . import models as M, scene
    # Factories: each scene gets a BSDF of its own, released with it.
    result = scene.side_by_side(lambda: target.as_dict() if target.xml is None else target.load(),
                                lambda: M.load_dict(properties), settings.res,
                                settings.spp, settings.rounds)
    images = result["images"]
    t, m = images["target"], images["model"]
    metrics = compare.metrics(t, m, with_flip=True, flip_mode="hdr")
    noise = compare.metrics(t, images["target_seed1"], with_flip=False)
    return {"image_relmse": metrics["relmse"], "image_flip": metrics["flip"],
            "image_noise_relmse": noise["relmse"], "cost_ratio": result["cost_ratio"],
            "render_seconds": {k: v for k, v in result["times"].items()},
            "images": {"target": t.astype(np.float32), "model": m.astype(np.float32)},
            "render": {"res": settings.res, "spp": settings.spp, "seed": 0}}
