"""What one traced call of a plugin method does (the tracing group): Python
function calls, texture evaluations, MicrofacetDistribution objects built,
BSDF methods it calls again, helpers called more than once; and how often a
path-traced render calls each method. Measured with cProfile, with the
plugin's textures and ``mi.MicrofacetDistribution`` replaced by counting
wrappers for the duration of one call. (The Dr.Jit variables one call
creates, of any BSDF: :func:`mi_brdfs.tools.analysis.variables_created`.)

Plugin code is told by where its file lies, inside this installed package
and outside its tools, never by a name in the path: a virtual environment
inside a checkout called ``mi_brdfs`` has Mitsuba's own Python files under a
path that holds that name too (the counts of calls by Mitsuba then read 0).
"""
from __future__ import annotations

import cProfile
import functools
import os
import pstats

import mitsuba as mi

from ..analysis import BSDF_METHODS, bsdf_call
from ..measures import render_waited
from .measure import scene_dict

PACKAGE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
TOOLS = os.path.join(PACKAGE, "tools")
INTERFACE = os.path.join(PACKAGE, "bsdfs", "mixture.py")   # where the BSDF methods are defined


@functools.lru_cache(maxsize=None)
def _real(filename: str) -> str:
    return os.path.realpath(filename)


def plugin_code(filename: str) -> bool:
    """True if ``filename`` (a code object's) is a file of the plugins: in the
    package, not in its tools (cProfile's built-ins have the file "~")."""
    if not os.path.isabs(filename):
        return False
    path = _real(filename)
    return (os.path.commonpath([path, PACKAGE]) == PACKAGE
            and os.path.commonpath([path, TOOLS]) != TOOLS)


def bsdf_method(key) -> bool:
    """A cProfile key (file, line, name) of a BSDF method every plugin inherits."""
    return key[2] in BSDF_METHODS and _real(key[0]) == INTERFACE


class _CountingTexture:
    """Forwards to a texture and counts its evaluations."""

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


def profile(run) -> dict:
    """cProfile's statistics of ``run()``: {(file, line, name): (cc, nc, tt, ct, callers)}."""
    profiler = cProfile.Profile()
    profiler.enable()
    run()
    profiler.disable()
    return pstats.Stats(profiler).stats


def call_anatomy(bsdf, method: str, x: dict) -> dict:
    """What one traced call of a plugin method does: Python function calls,
    texture evaluations, MicrofacetDistribution objects built, the BSDF
    methods it calls again, and the helpers called more than once."""
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
        stats = profile(lambda: bsdf_call(bsdf, method, x))
    finally:
        mi.MicrofacetDistribution = original
        for k, v in textures.items():
            setattr(bsdf, k, v)
    ours = {k: v[1] for k, v in stats.items() if plugin_code(k[0])}
    inner = {k[2]: n - (k[2] == method) for k, n in ours.items() if bsdf_method(k)}
    return {"python_calls": sum(ours.values()), "texture_evals": evals[0],
            "microfacet_objects": built[0],
            "inner_calls": ", ".join(f"{m} x{n}" for m, n in sorted(inner.items()) if n),
            "repeated": ", ".join(f"{k[2]} x{n}" for k, n in sorted(ours.items(), key=lambda kv: -kv[1])
                                  if n > 1 and not bsdf_method(k))}


def calls_in_a_render(config: dict) -> dict[str, list[int]]:
    """Per BSDF method: [calls from outside the plugins (Mitsuba's), all calls]
    of one plugin instance while one path-traced render (depth 3) is traced."""
    scene = mi.load_dict(scene_dict(config, 8, plane=False), parallel=False)
    stats = profile(lambda: render_waited(scene, 1, seed=0))
    counts = {m: [0, 0] for m in BSDF_METHODS}
    for key, (_, nc, _, _, callers) in stats.items():
        if bsdf_method(key):
            counts[key[2]][0] += sum(c[1] for k, c in callers.items() if not plugin_code(k[0]))
            counts[key[2]][1] += nc
    return counts
