"""Everything the explorer takes from the rest of mi_brdfs, in this one module.

The other modules of :mod:`mi_brdfs.tools.explore` know Mitsuba, Dr.Jit and
the JSON declarations :func:`course_models` makes, never mi_brdfs itself: when
the package's modules move or are renamed, only this file changes. What it
takes:

- the plugins and their declarations (``bsdfs.PLUGINS``; each class's
  ``PARAMS``, ``all_options()`` and ``compensable``), as JSON;
- the loader's one-line error (``bsdfs.params.ParameterError``), through
  :func:`load`;
- the lobe evaluations of :mod:`mi_brdfs.tools.analysis` (its albedo
  quadrature launches a kernel per angle, too slow for a slider:
  :func:`.session.directional_albedo` does all angles in one);
- the random walk's albedo (:func:`mi_brdfs.tools.groundtruth.albedo`, Heitz
  et al. 2016) and how ``cook_torrance``'s parameters map onto it;
- the integrators of the two modes and the tone mapping of
  :mod:`mi_brdfs.render.tonemap`;
- the fit of :mod:`mi_brdfs.tools.fit` (one model to one target);
- the command line's conventions: checked numbers, threads and log level
  (:mod:`mi_brdfs.tools.arguments`), errors on one line
  (:mod:`mi_brdfs.tools.errors`).
"""
from __future__ import annotations

import contextlib
import math

import numpy as np

import mitsuba as mi

import mi_brdfs

from ...bsdfs import PLUGINS
from ...bsdfs.microfacet import ALPHA_MIN
from ...bsdfs.params import ParameterError
from ...render import tonemap
from ..analysis import eval_at_viewer, hemisphere
from ..arguments import integer, set_threads, set_verbosity
from ..errors import one_line

ENERGY_COMPENSATION = "energy_compensation"     # the base's option name
MODES = ("scanline", "hdr")
TONEMAP = {"hdr": "aces", "scanline": "clamp"}   # the preview's operator per mode


def port_number():
    """The argparse type of ``--port``: the command line's checked integer."""
    return integer(0, 65535)


def configure(threads: int | None, verbose: int) -> None:
    """Dr.Jit's thread count and the log level, as the other commands set them."""
    set_threads(threads)
    set_verbosity(verbose)


def setup() -> str:
    """Find LLVM, activate ``llvm_ad_rgb`` and register the plugins (importing
    mi_brdfs does all three); returns the variant."""
    return mi_brdfs.register()


# ----------------------------------------------------------------------------
#  Declarations, as JSON
# ----------------------------------------------------------------------------

def _param(p) -> dict:
    return {"name": p.name, "kind": p.kind, "role": p.role, "default": p.default,
            "lo": p.lo, "hi": p.hi, "upper": p.probe_hi(), "optional": p.optional,
            "doc": " ".join(p.doc.split())}


def _option(o) -> dict:
    kind = "bool" if isinstance(o.default, bool) else "int" if isinstance(o.default, int) \
        else "string"
    return {"name": o.name, "type": kind, "default": o.default, "choices": list(o.choices),
            "lo": o.lo, "hi": o.hi, "doc": " ".join(o.doc.split())}


def _title(cls) -> str:
    """The first line of the plugin's docstring, without markup."""
    line = next((s for s in (cls.__doc__ or "").splitlines() if s.strip()), cls.name)
    return line.replace("``", "").strip()


def course_models() -> list[dict]:
    """Every plugin of the package with its parameters and options (the
    schema of ``GET /api/models``; ``control`` is filled in by the caller)."""
    return [{"name": cls.name, "source": "mi_brdfs", "title": _title(cls),
             "compensable": bool(cls.compensable),
             "params": [_param(p) for p in cls.PARAMS],
             "options": [_option(o) for o in cls.all_options()]} for cls in PLUGINS]


# ----------------------------------------------------------------------------
#  Loading, with the plugin's own checks
# ----------------------------------------------------------------------------

class MaterialError(ValueError):
    """A material the plugin refused, with its one-line message."""


@contextlib.contextmanager
def checked():
    """The plugin's own checks, at load time or at ``params.update()``, as
    MaterialError with the plugin's one-line message.

    Mitsuba wraps an exception raised in a Python plugin's constructor in a
    RuntimeError that carries the traceback: the plugin's own message is its
    last line, after the exception's class name."""
    try:
        yield
    except ParameterError as error:
        raise MaterialError(str(error)) from None
    except RuntimeError as error:
        tag = ParameterError.__name__ + ": "
        last = str(error).strip().splitlines()[-1].strip()
        raise MaterialError(last.split(tag, 1)[1] if tag in last else message(error)) from None


def load(props: dict):
    """``mi.load_dict(props)``, checked (:func:`checked`)."""
    with checked():
        return mi.load_dict(props)


def message(error: BaseException) -> str:
    """Any error on one line, as the ``mi-brdfs`` command reports it."""
    return one_line(error)


# ----------------------------------------------------------------------------
#  Lobes (mi_brdfs.tools.analysis)
# ----------------------------------------------------------------------------

def lobe_in_plane(bsdf, theta_i: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(θ_o in degrees, signed, > 0 on the mirror side; eval per channel, (n, 3))
    in the plane of incidence, the viewer at θ_i."""
    theta = np.linspace(-90.0, 90.0, n)
    t = np.radians(theta)
    wo = np.stack([np.sin(t), np.zeros(n), np.cos(t)], axis=1)
    return theta, eval_at_viewer(bsdf, theta_i, wo)


def lobe_over_hemisphere(bsdf, theta_i: float, n: int):
    """θ_o, φ_o (radians, (n, 4n) grids) and eval's channel mean there."""
    return hemisphere(bsdf, theta_i, n)


# ----------------------------------------------------------------------------
#  The random walk on the microsurface (mi_brdfs.tools.groundtruth)
# ----------------------------------------------------------------------------

def walk_applies(material: dict) -> bool:
    """True for the configurations the walk is the ground truth of:
    ``cook_torrance`` in hdr mode with a Beckmann or GGX distribution."""
    return (material.get("type") == "cook_torrance" and material.get("mode") == "hdr"
            and material.get("distribution") in ("beckmann", "ggx"))


def walk_albedo(material: dict, angles, paths: int, seed: int = 1) -> np.ndarray:
    """The white furnace of ``material`` (a complete ``cook_torrance``, see
    :func:`walk_applies`) by the random walk: k + (1 - k) W(θ; α, F0), W the
    walk's albedo of the Smith microsurface with Schlick's F at every bounce
    and white m_D = m_S = 1; for a colour ``f0`` its largest channel's, as the
    explorer's albedo curves show the largest channel (W grows with F0 on every
    path: each bounce's Schlick F does). NumPy only (no Dr.Jit): any thread may run it."""
    from ..groundtruth import albedo    # here: the walk needs SciPy, not in the explore extra
    mu = np.cos(np.radians(np.asarray(angles, dtype=np.float64)))
    alpha = max(float(material["alpha"]), ALPHA_MIN)
    f0 = material["f0"]
    f0 = max(float(v) for v in (f0 if isinstance(f0, (list, tuple)) else [f0]))
    w = albedo(material["distribution"], np.maximum(mu, 1e-3), alpha, (f0,),
               paths=paths, seed=seed)[:, 0]
    k = float(material["k"])
    return k + (1.0 - k) * w


# ----------------------------------------------------------------------------
#  Rendering
# ----------------------------------------------------------------------------

def integrator(mode: str) -> dict:
    """The lecture's scan-line integrator, or the path tracer (``hdr``); depth
    3 suffices for a convex object under an environment."""
    return {"type": "scanline"} if mode == "scanline" else {"type": "path", "max_depth": 3}


def light_scale(mode: str) -> float:
    """The preview's lights for a course plugin in ``mode``: the lecture's
    scan-line formulas have no 1/π (m_D·clamp(d·n) for Lambert), so their
    lights are divided by π to show a scan-line material as bright as its hdr
    counterpart (Mitsuba's built-ins keep 1 in either mode)."""
    return 1.0 / math.pi if mode == "scanline" else 1.0


def to_srgb8(image: np.ndarray, mode: str) -> np.ndarray:
    """Linear RGB -> 8-bit sRGB, tone-mapped as the preview does in ``mode``."""
    return tonemap.to_srgb8(image[..., :3], TONEMAP[mode])


# ----------------------------------------------------------------------------
#  The fit (mi_brdfs.tools.fit)
# ----------------------------------------------------------------------------

def fit(model: dict, target: dict, options: tuple[str, ...]) -> tuple[dict, float | None]:
    """Fit the course model ``model`` (complete flat material; ``options``: its
    option names, kept fixed) to the BSDF ``target`` (a ``mi.load_dict``
    dictionary) with the project's fit at its QUICK settings, without
    renders (its metric's direction pairs; a scan of candidate settings,
    then Levenberg-Marquardt from the best few:
    :mod:`mi_brdfs.tools.fit.optimise`); returns (the fitted values, flat,
    colours as lists; the relative BRDF error: 0 identical, 1 as far as
    black; None if it is not finite)."""
    # here, not above: the command line imports this module at every start
    # (for --port) and the fit package would add a tenth to its start-up
    from ..fit import metric, models, optimise, task
    settings = task.QUICK.replace(render=False)
    pairs = metric.pairs(settings.metric, settings.viewers, settings.uniform, settings.lobe)
    fixed = tuple((name, model[name]) for name in options if name in model)
    chosen = models.Model(model["type"], model["type"], fixed)
    target_bsdf = load(target)
    problem = optimise.problem(target_bsdf, pairs)
    del target_bsdf
    if not problem.norm > 0:
        raise MaterialError("fit: the target reflects no light at the metric's directions")
    result = optimise.fit_model(chosen, problem, settings)
    error = float(result["brdf_error"])
    return dict(result["parameters"]), (error if math.isfinite(error) else None)
