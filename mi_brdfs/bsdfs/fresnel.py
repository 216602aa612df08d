"""Fresnel reflectance: how much of the light a microfacet reflects at the
cosine c = ω·m between a direction and the facet's normal.

``schlick``: the lecture's F = F0 + (1 - F0)(1 - clamp(c))^5 (Schlick 1994),
F0 the reflectance at normal incidence (a number or a colour).
"""
from __future__ import annotations

import drjit as dr


def schlick(f0, c):
    """F0 + (1 - F0)(1 - clamp(c))^5; the Python number 1 for the number 1 (F = 1
    at every angle: nothing traced)."""
    if type(f0) is float and f0 == 1.0:
        return 1.0
    m = 1.0 - dr.fmin(dr.fmax(c, 0.0), 1.0)
    m2 = m * m
    return f0 + (1.0 - f0) * (m2 * m2 * m)
