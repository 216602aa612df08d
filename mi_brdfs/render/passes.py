"""Rendering in passes: Mitsuba's JIT variants report no progress of their own,
so the samples per pixel are rendered in passes with distinct seeds and
averaged, with a progress callback after each pass.

The passes go through one frozen function (:class:`.frozen.FrozenRender`):
the first pass traces the scene's Python code (every BSDF plugin), the next
ones replay the recorded kernels with a new seed. Passes of another spp (spp
not divisible by the number of passes) record once more. Where freezing is not
possible — a variant without JIT, a scene that changed between passes so that
a pass had to be traced again, an error inside the frozen function (e.g. a
BSDF alive outside the scene, see :mod:`.frozen`) — the remaining passes are
rendered plainly and ``log`` says why. Either way the image is the same: the
seeds are the same and a replay computes what a trace would (equal to float
precision).
"""
from __future__ import annotations

import time

import numpy as np

import mitsuba as mi

from . import frozen


def split_passes(spp: int, passes: int) -> list[int]:
    """spp as `passes` near-equal chunks (none empty)."""
    passes = max(1, min(passes, spp))
    base, extra = divmod(spp, passes)
    return [base + (i < extra) for i in range(passes)]


def render_passes(scene, spp: int, passes: int = 8, seed: int = 0, show=None,
                  freeze: bool = True, log=None):
    """Render ``spp`` samples per pixel in passes with distinct seeds; the
    spp-weighted mean of every film channel as an (H, W, C) NumPy array.

    ``show(done_spp, total_spp, elapsed_s)`` is called at the start (0 spp)
    and after each pass;
    ``log(message)`` receives informational messages (whether and why the
    passes were not frozen). ``freeze=False`` traces every pass."""
    say = log or (lambda message: None)
    chunks = split_passes(spp, passes)
    render = None                     # the frozen render, while it is used
    if freeze:
        reason = frozen.unavailable()
        if reason is None and len(chunks) == 1:
            reason = "a single pass, nothing to replay"
        if reason:
            say(f"passes not frozen: {reason}")
        else:
            try:
                frozen.warm_up(scene)
                render = frozen.FrozenRender()
            except Exception as error:           # noqa: BLE001  (reported, then rendered plainly)
                say(f"passes not frozen: the warm-up render failed ({frozen.why(error)})")

    total, done, start = None, 0, time.perf_counter()
    if show:
        show(0, spp, 0.0)
    for i, n in enumerate(chunks):
        pass_seed = seed * len(chunks) + i
        image = None
        if render is not None:
            try:
                image = render(scene, n, pass_seed)
            except Exception as error:           # noqa: BLE001  (reported, then rendered plainly)
                say(f"pass {i + 1}: frozen render failed ({frozen.why(error)}); "
                    "rendering the remaining passes unfrozen")
                render = None
            else:
                if render.recordings > len(set(chunks[:i + 1])):
                    say(f"pass {i + 1}: traced again (the scene changed since the last pass); "
                        "rendering the remaining passes unfrozen")
                    render = None
        if image is None:
            image = mi.render(scene, spp=n, seed=pass_seed)
        image = np.array(image, dtype=np.float64)
        total = image * n if total is None else total + image * n
        done += n
        if show:
            show(done, spp, time.perf_counter() - start)
    if render is not None:
        say(f"{len(chunks)} passes frozen: {render.recordings} traced, "
            f"{len(chunks) - render.recordings} replayed")
    return (total / spp).astype(np.float32)
