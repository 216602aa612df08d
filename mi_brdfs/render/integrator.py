"""
``scanline`` — the lecture's scan-line rendering as a Mitsuba integrator
========================================================================

.. list-table::
   :header-rows: 1

   * - Parameter
     - Type
     - Description
     - Default
   * - ``shadows``
     - bool
     - trace a shadow ray to each light (scan-line rasterizers have no shadows
       without shadow maps).
     - false
   * - ``clamp``
     - bool
     - clamp the result to [0, 1] per channel (overexposed areas turn white).
     - true
   * - ``hide_emitters``
     - bool
     - do not show emitters seen directly by the camera.
     - false
   * - ``max_depth``
     - int
     - accepted and ignored (scan-line lighting is direct), so a scene's
       ``<integrator type="$mode">`` can set the hdr path tracer's depth.
     - —

At the first surface the camera sees, the sum over **every** light of the
scene (not one picked at random)::

    L(x, w_r) = clamp( sum_l L(l, lx) · f_r(x, lx, w_r) ),   f_r = bsdf.eval(wi = w_r, wo = lx)

with L(l, lx) the light's radiance arriving at x (point: I/r²; spot: with its
cone; directional: its irradiance). Lights behind the surface are passed to
the BSDF too: its own clamps zero what must be zero (the toon model's dark
side depends on this). Point, spot and directional lights are exact; area and
environment lights are estimated from one light sample per pixel sample.
Emitters seen directly show their radiance. Use with BSDFs in
``mode="scanline"`` for the lecture's images.

``hdr`` is registered too: Mitsuba's ``path`` integrator under the name the
scenes' ``mode`` default uses, so ``<integrator type="$mode"/>`` switches
between scan-line and path tracing with ``-D mode=...`` (its properties are
passed to ``path``).

.. code-block:: xml

    <integrator type="scanline">
        <boolean name="shadows" value="true"/>
    </integrator>
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .._binding import bind


class Scanline:
    name = "scanline"

    def __init__(self, props: mi.Properties):
        mi.SamplingIntegrator.__init__(self, props)
        self.shadows = bool(props.get("shadows", False))
        self.clamp = bool(props.get("clamp", True))
        self.hide_emitters = bool(props.get("hide_emitters", False))
        # Accepted and ignored, so one <integrator type="$mode"> element can give
        # the hdr path tracer a max_depth: scan-line lighting is direct only.
        props.get("max_depth", -1)

    def sample(self, scene, sampler, ray, medium=None, active=True):
        ray = mi.Ray3f(ray)
        si = scene.ray_intersect(ray, active)
        result = mi.Spectrum(0.0)
        # Emitters seen directly (the environment where the ray misses). In
        # scalar variants a missing emitter or BSDF is None, not a null pointer.
        seen = si.emitter(scene)
        if not self.hide_emitters and seen is not None:
            result += seen.eval(si, active)

        hit = mi.Bool(active) & si.is_valid()
        # (scalar variants: si.bsdf() of a missed ray dereferences no shape)
        bsdf = si.bsdf(ray) if dr.is_jit_v(mi.Float) or hit else None
        ctx = mi.BSDFContext()
        for emitter in scene.emitters() if bsdf is not None else ():   # every light
            ds, radiance = emitter.sample_direction(si, sampler.next_2d(hit), hit)
            lit = hit & (ds.pdf > 0)
            if self.shadows:
                lit &= dr.select(scene.ray_test(si.spawn_ray_to(ds.p), lit), False, True)
            f_r = bsdf.eval(ctx, si, si.to_local(ds.d), lit)
            result += dr.select(lit, radiance * f_r, 0.0)

        if self.clamp:
            result = dr.fmin(dr.fmax(result, 0.0), 1.0)
        return result, mi.Bool(active), []

    def aov_names(self):
        return []

    def to_string(self):
        return (f"Scanline[shadows={self.shadows}, clamp={self.clamp}, "
                f"hide_emitters={self.hide_emitters}]")


def make_hdr(props: mi.Properties):
    """Mitsuba's ``path`` integrator, with the given properties."""
    config = {"type": "path"}
    for key in props.keys():
        config[key] = props[key]
    return mi.load_dict(config)


def register() -> None:
    """Register ``scanline`` and ``hdr`` for the active variant."""
    cls = bind(Scanline, "SamplingIntegrator")
    mi.register_integrator("scanline", lambda props: cls(props))
    mi.register_integrator("hdr", make_hdr)
