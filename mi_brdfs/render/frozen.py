"""Repeated renders through Dr.Jit's function freezing (``dr.freeze``).

Every ``mi.render`` call traces the Python code of every BSDF in the scene
again, even when the kernels it produces are compiled already (0.77 ms per
``cook_torrance`` material, 0.48 ms per ``roughconductor`` one, in one run of
``mi-brdfs bench --only materials``). ``dr.freeze`` records the kernel
launches of a first call and replays them on later calls with new inputs — a
new seed, new parameter values — without running the Python code at all.
Two repeated renders use it:

- the passes of one image: :class:`FrozenRender` (used by
  :func:`mi_brdfs.render.passes.render_passes`);
- the steps of a gradient descent: :class:`GradientStep` records the render,
  the loss and the backward pass together (notebook 05 fits with it).
  Dr.Jit propagates gradients from inside a frozen function to the variables
  its inputs depend on, but not from its outputs back through it, so a frozen
  render alone would return an image without gradients: the loss and
  ``dr.backward`` must be inside.

What a replay cannot see, and how it is handled here:

- the seed: passed as an opaque ``mi.UInt32``. A Python int is part of the
  recording's key (a new recording per seed); a literal would be made opaque
  only at the second call (two recordings).
- the plugins' Python-side choices, e.g. which lobes exist and which
  parameters are folded as numbers (decided in ``parameters_changed`` from
  the parameter values): the flags of every shape's BSDF and the plugins'
  ``trace_key`` are part of the key (``state_fn``), so a change re-records
  instead of replaying stale code.
- the first render of a fresh scene initialises state of its sensor and
  emitters that the next call sees as a changed input: a function frozen on a
  fresh scene records twice. :func:`warm_up` does that initialisation
  without tracing any BSDF.

What cannot be frozen: a BSDF alive in the process but outside the scene's
shapes (e.g. one loaded on its own with ``mi.load_dict`` to plot its lobe).
Mitsuba's virtual calls cover every live BSDF instance, and Dr.Jit can only
collect the members of those it finds among the frozen function's inputs: the
recording fails (:func:`why` says so); ``render_passes`` then renders plainly,
``GradientStep`` raises. Spectral variants fail to record too, built-in BSDFs alike
(Mitsuba 3.9.1: a spectral table is used without being an input). Scalar
variants have no JIT and nothing to freeze: :func:`unavailable` says why.
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi


def unavailable() -> str | None:
    """Why renders in the active variant cannot be frozen, or None if they can."""
    variant = mi.variant()
    if variant is None or not dr.is_jit_v(mi.Float):
        return f"variant {variant} has no JIT (dr.freeze needs an llvm_* or cuda_* variant)"
    if not dr.flag(dr.JitFlag.KernelFreezing):
        return "Dr.Jit's KernelFreezing flag is off"
    return None


def why(error: Exception) -> str:
    """A frozen call's error in one line: Dr.Jit raises a generic error whose
    cause says what went wrong."""
    cause = error.__cause__ or error
    return f"{type(cause).__name__}: " + " ".join(str(cause).replace("record(): ", "").split())


def bsdf_flags(scene, *args, **kwargs) -> tuple:
    """The flags of every shape's BSDF, and for a plugin of this package the
    rest of what its calls trace (``BRDF.trace_key``): the Python-side choices
    a replay cannot see (``state_fn`` of the frozen functions)."""
    return tuple((int(bsdf.flags()), getattr(bsdf, "trace_key", tuple)())
                 for bsdf in (shape.bsdf() for shape in scene.shapes()) if bsdf)


def warm_up(scene) -> None:
    """Initialise what the first render of a fresh scene initialises, without
    tracing any BSDF: one sample per pixel of the ``depth`` integrator (the
    sensor's state) and one direction sampled from every emitter (the emitters'
    state, which the ``scanline`` integrator's first render sets). Without it a
    function frozen on a fresh scene records twice (Mitsuba 3.9; with it every
    shipped scene records once, in both modes)."""
    image = mi.render(scene, integrator=mi.load_dict({"type": "depth"}), spp=1)
    si = dr.zeros(mi.SurfaceInteraction3f)
    for emitter in scene.emitters():
        dr.eval(emitter.sample_direction(si, mi.Point2f(0.5, 0.5), True))
    dr.eval(image)


def opaque_seed(seed: int):
    """A seed the recording does not bake in."""
    return dr.opaque(mi.UInt32, seed)


# ----------------------------------------------------------------------------
#  One image in passes
# ----------------------------------------------------------------------------

def _render(scene, seed, spp: int):
    return mi.render(scene, spp=spp, seed=seed)


class FrozenRender:
    """``mi.render(scene, spp=spp, seed=seed)`` through a frozen function: the
    first call with a given spp records (traces), the next ones replay.

    The image equals the unfrozen render with the same seed (to float
    precision). ``recordings`` counts the traced calls."""

    def __init__(self):
        self.function = dr.freeze(_render, state_fn=bsdf_flags)

    def __call__(self, scene, spp: int, seed: int):
        return self.function(scene, opaque_seed(seed), spp)

    @property
    def recordings(self) -> int:
        return self.function.n_recordings


# ----------------------------------------------------------------------------
#  Gradient descent
# ----------------------------------------------------------------------------

def mse(image, reference):
    """Mean squared error over every pixel and channel."""
    return dr.mean(dr.square(image - reference), axis=None)


class GradientStep:
    """One step of a gradient descent on scene parameters, frozen:
    ``step(scene, reference, seed) -> loss``.

    Renders ``scene`` at ``spp`` with gradients tracked on the parameters
    ``keys`` (``mi.traverse`` keys), computes ``loss(image, reference)`` and
    propagates its gradient to those parameters — and on to what they were
    computed from, e.g. an optimizer's variables set with ``params.update()``
    before the call. The first calls record, the next ones replay (a new
    recording when the BSDFs' lobes change). ``freeze=False``, or a variant
    without JIT, runs the same code unfrozen; ``frozen`` says which.

    If the recording fails (e.g. a BSDF alive outside the scene), the call
    raises instead of falling back: the failed call has already propagated
    its gradients.

    It records twice, whatever the number of steps: the first render with
    gradients initialises state that the second call sees as a changed input
    (measured; :func:`warm_up` does not cover it, one unfrozen step first
    does, at the cost of the same trace).
    """

    def __init__(self, keys: list[str], spp: int, loss=mse, freeze: bool = True):
        self.keys, self.spp, self.loss = list(keys), spp, loss
        self.frozen = freeze and unavailable() is None
        self.function = (dr.freeze(self._step, state_fn=bsdf_flags) if self.frozen
                         else self._step)

    def _step(self, scene, reference, seed):
        params = mi.traverse(scene)
        params.keep(self.keys)
        image = mi.render(scene, params, spp=self.spp, seed=seed)
        loss = self.loss(image, reference)
        dr.backward(loss)
        return loss

    def __call__(self, scene, reference, seed: int):
        if not self.frozen:
            return self.function(scene, reference, seed)
        try:
            return self.function(scene, reference, opaque_seed(seed))
        except Exception as error:
            # Not retried unfrozen: the failed recording has run the backward
            # pass already, and a second one would add its gradients twice.
            raise RuntimeError(f"frozen gradient step failed ({why(error)}); this step's "
                               "gradients may have been accumulated once; use "
                               "GradientStep(..., freeze=False)") from error

    @property
    def recordings(self) -> int:
        return self.function.n_recordings if self.frozen else 0
