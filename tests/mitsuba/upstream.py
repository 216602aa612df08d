"""What the ports of Mitsuba's own tests share: the release they come from,
the configurations of our plugins that stand in for Mitsuba's, and the
surface interaction Mitsuba's BSDF tests build.

Every ported module names its upstream file and lists what it changed; the
upstream sources are Mitsuba 3.9.1 (the release ``pip install mitsuba==3.9.1``
installs), tag ``v3.9.1`` of https://github.com/mitsuba-renderer/mitsuba3.
"""
from __future__ import annotations

import mitsuba as mi

TAG = "v3.9.1"
COMMIT = "478e193a183c21723f4a8251afc3ad29a8da4c5e"     # the tag's commit


def lambert(**properties) -> dict:
    """``lambert`` in place of ``diffuse``: hdr mode (the default) is
    Mitsuba's diffuse BRDF, default reflectance 0.5 as ``diffuse``'s."""
    return {"type": "lambert", **properties}


def cook_torrance(alpha: float = 0.1, distribution: str = "beckmann", **properties) -> dict:
    """``cook_torrance`` in place of ``roughconductor``: no diffuse lobe
    (k = 0), F0 = 1 (roughconductor's default ``material="none"`` is a
    perfect conductor, F = 1), Smith's G, hdr mode; roughconductor's defaults
    (Beckmann, alpha 0.1). tests/bsdfs/test_cook_torrance.py checks that this
    configuration evaluates and samples as roughconductor does."""
    return {"type": "cook_torrance", "k": 0.0, "f0": 1.0, "geometry": "smith",
            "distribution": distribution, "alpha": alpha, **properties}


def frontal_si() -> mi.SurfaceInteraction3f:
    """The interaction of Mitsuba's BSDF tests: at the origin, normal +z,
    the viewer along the normal."""
    si = mi.SurfaceInteraction3f()
    si.t = 0.1
    si.p = [0, 0, 0]
    si.n = [0, 0, 1]
    si.sh_frame = mi.Frame3f(si.n)
    si.wi = [0, 0, 1]
    return si
