"""Rendering in passes: Mitsuba's JIT variants report no progress of their own,
so the samples per pixel are rendered in passes with distinct seeds and
averaged, with a progress callback after each pass."""
from __future__ import annotations

import time


def split_passes(spp: int, passes: int) -> list[int]:
    """spp as `passes` near-equal chunks (none empty)."""
    passes = max(1, min(passes, spp))
    base, extra = divmod(spp, passes)
    return [base + (i < extra) for i in range(passes)]


def render_passes(scene, spp: int, passes: int = 8, seed: int = 0, show=None,
                  freeze: bool = True, log=None):
    """Render ``spp`` samples per pixel in passes with distinct seeds; the
    spp-weighted mean of every film channel as an (H, W, C) NumPy array.

    ``show(done_spp, total_spp, elapsed_s)`` is called after each pass;
    ``log(message)`` receives informational messages (e.g. why a render was
    not frozen). ``freeze`` is reserved for replaying passes through
    ``dr.freeze`` (not implemented yet: every pass is traced)."""
    import mitsuba as mi
    import numpy as np

    chunks = split_passes(spp, passes)
    total, done, start = None, 0, time.perf_counter()
    for i, n in enumerate(chunks):
        image = np.array(mi.render(scene, spp=n, seed=seed * len(chunks) + i), dtype=np.float64)
        total = image * n if total is None else total + image * n
        done += n
        if show:
            show(done, spp, time.perf_counter() - start)
    return (total / spp).astype(np.float32)


