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

    L(x, w_r) = clamp( sum_l V(x, l) · L(l, lx) · f_r(x, lx, w_r) ),   f_r = bsdf.eval(wi = w_r, wo = lx)

with L(l, lx) the light's radiance arriving at x (point: I/r²; spot: with its
cone; directional: its irradiance) and V = 1 without ``shadows``. Lights
behind the surface are passed to the BSDF too: its own clamps zero what must
be zero (the toon model's dark side depends on this). Point, spot and
directional lights are exact; area and environment lights are estimated from
one light sample per pixel sample. Emitters seen directly show their
radiance. Use with BSDFs in ``mode="scanline"`` for the lecture's images.

**Mitsuba's adapters.** ``twosided``, ``normalmap``, ``bumpmap`` and
``blendbsdf`` are BSDFs like any other: the integrator evaluates them, in
either mode of the BSDFs they hold. Surfaces one can see through — a
``mask`` (its opacity), ``null``, ``thindielectric``: the BSDFs with a
``BSDFFlags.Null`` component — are handled as Mitsuba's ``volpath`` handles
them:

- the camera ray continues through them: each surface adds its shading
  (``mask`` weighs its BSDF by the opacity), and what lies behind is added
  times ``eval_null_transmission`` (1 − opacity), deterministically, up to
  ``MAX_LAYERS`` surfaces. A fully transparent ``mask`` card is invisible.
- with ``shadows``, V is the transmittance along the shadow ray: the product
  of ``eval_null_transmission`` over the surfaces it crosses (0 at an opaque
  one), so a card of opacity 0.3 lets 70 % of the light through.

In a scene without such a surface the integrator is the single-hit one above.
With clamp off and hdr-mode BSDFs it computes what ``volpath`` with
``max_depth=2`` computes (direct light; ``path`` counts a crossing of a null
surface as a bounce and stops shadow rays at every surface). See
``docs/guide/scanline.md``.

``course`` is registered too: the course's two ways of rendering behind one
name, chosen by its ``mode`` (``"scanline"``: this integrator; ``"hdr"``, the
default: Mitsuba's ``path``; its other properties are passed on), so that a
scene's ``<integrator type="course"><string name="mode" value="$mode"/>``
switches between scan-line and path tracing with ``-D mode=...``, the mode its
BSDFs take too.

.. code-block:: xml

    <integrator type="scanline">
        <boolean name="shadows" value="true"/>
    </integrator>
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .._binding import bind, create


MAX_LAYERS = 64      # see-through surfaces a camera or shadow ray crosses, at most


class Scanline:
    name = "scanline"

    def __init__(self, props: mi.Properties):
        mi.SamplingIntegrator.__init__(self, props)
        self.shadows = bool(props.get("shadows", False))
        self.clamp = bool(props.get("clamp", True))
        self.hide_emitters = bool(props.get("hide_emitters", False))
        # Accepted and ignored, so one <integrator type="course"> element can give
        # the hdr path tracer a max_depth: scan-line lighting is direct only.
        props.get("max_depth", -1)

    def sample(self, scene, sampler, ray, medium=None, active=True):
        ray = mi.Ray3f(ray)
        active = mi.Bool(active)
        if not see_through(scene):
            result = self.shade(scene, sampler, ray, active, through=False)[0]
        else:
            # ---------------- Through the see-through surfaces ----------------
            def body(sampler, ray, result, β, layer, active):
                L, si, bsdf, hit = self.shade(scene, sampler, ray, active, through=True)
                result = result + β * L
                β = β * null_transmission(bsdf, si, hit)
                return (sampler, si.spawn_ray(ray.d), result, β, layer + 1,
                        hit & (layer + 1 < MAX_LAYERS) & passes(β))

            state = (sampler, ray, mi.Spectrum(0.0), mi.Spectrum(1.0), mi.UInt32(0), active)
            result = dr.while_loop(state, lambda *s: s[-1], body,
                                   label="scanline: see-through layers")[2]
        if self.clamp:
            result = dr.fmin(dr.fmax(result, 0.0), 1.0)
        return result, mi.Bool(active), []

    def shade(self, scene, sampler, ray, active, through: bool):
        """The radiance the first surface along ``ray`` sends back (every
        light, the emitter seen), its interaction, BSDF and hit mask.
        ``through``: shadow rays cross see-through surfaces (else any surface
        occludes)."""
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
            if self.shadows and through:
                radiance = radiance * transmittance(scene, si, ds, lit)
            elif self.shadows:
                lit &= dr.select(scene.ray_test(si.spawn_ray_to(ds.p), lit), False, True)
            f_r = bsdf.eval(ctx, si, si.to_local(ds.d), lit)
            result += dr.select(lit, radiance * f_r, 0.0)
        return result, si, bsdf, hit

    def aov_names(self):
        return []

    def to_string(self):
        return (f"Scanline[shadows={self.shadows}, clamp={self.clamp}, "
                f"hide_emitters={self.hide_emitters}]")


# ----------------------------------------------------------------------------
#  See-through surfaces (BSDFs with a null component: mask, null, thindielectric)
# ----------------------------------------------------------------------------

def see_through(scene) -> bool:
    """Whether a shape of the scene may be seen through: a BSDF with a
    ``BSDFFlags.Null`` component, or an instance (its shapes are not listed).
    A Python-side choice of the code traced; frozen renders key on every
    shape's BSDF flags (:mod:`.frozen`), so a change re-records."""
    for shape in scene.shapes():
        bsdf = shape.bsdf()
        if shape.class_name() == "Instance":
            return True
        if bsdf is not None and mi.has_flag(bsdf.flags(), mi.BSDFFlags.Null):
            return True
    return False


def null_transmission(bsdf, si, hit) -> mi.Spectrum:
    """The fraction of light that passes straight through the surface at
    ``si`` (1 − opacity for a mask, 0 for an opaque BSDF, 0 where nothing was hit)."""
    if bsdf is None:                                   # scalar variants: no surface
        return mi.Spectrum(0.0)
    return dr.select(hit, bsdf.eval_null_transmission(si, hit), 0.0)


def passes(β) -> mi.Bool:
    """Whether any light still passes (a throughput not all zero)."""
    return dr.max(mi.unpolarized_spectrum(β)) > 0


def transmittance(scene, si, ds, active) -> mi.Spectrum:
    """The transmittance from ``si`` to the light sample ``ds``: the product of
    ``eval_null_transmission`` over the surfaces in between (``volpath``'s
    shadow rays, without media)."""
    ray = si.spawn_ray_to(ds.p)
    max_t = mi.Float(ray.maxt)

    def body(ray, travelled, T, layer, active):
        blocker = scene.ray_intersect(ray, active)
        hit = mi.Bool(active) & blocker.is_valid()
        bsdf = blocker.bsdf(ray) if dr.is_jit_v(mi.Float) or hit else None
        T = dr.select(hit, T * null_transmission(bsdf, blocker, hit), T)
        travelled = travelled + dr.select(hit, blocker.t, 0.0)
        ray = blocker.spawn_ray(ray.d)
        ray.maxt = max_t - travelled
        return ray, travelled, T, layer + 1, hit & (layer + 1 < MAX_LAYERS) & passes(T)

    state = (ray, mi.Float(0.0), mi.Spectrum(1.0), mi.UInt32(0), mi.Bool(active))
    T = dr.while_loop(state, lambda *s: s[-1], body, label="scanline: shadow ray")[2]
    return dr.select(active, T, 0.0)


COURSE_MODES = {"scanline": "scanline", "hdr": "path"}     # course's mode -> integrator


def make_course(props: mi.Properties):
    """``course``: the integrator its ``mode`` names, with the other properties."""
    mode = props["mode"] if "mode" in props else "hdr"
    if mode not in COURSE_MODES:
        raise ValueError(f"course: parameter 'mode' = {mode!r} is invalid; valid: "
                         + ", ".join(f'"{m}"' for m in COURSE_MODES))
    return create(COURSE_MODES[mode], {key: props[key] for key in props.keys() if key != "mode"})


def register() -> None:
    """Register ``scanline`` and ``course`` for the active variant."""
    cls = bind(Scanline, "SamplingIntegrator")
    mi.register_integrator("scanline", lambda props: cls(props))
    mi.register_integrator("course", make_course)
