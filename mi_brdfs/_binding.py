"""Plain-Python plugin classes bound onto the active variant's Mitsuba base class.

Mitsuba's classes differ per variant (``mi.BSDF`` of ``llvm_ad_rgb`` is not that
of ``scalar_rgb``) and nanobind allows a single base, so each plain-Python
class of a plugin hierarchy is re-created on top of the variant's base class
the first time it is registered for that variant. Used by the BSDFs
(:mod:`mi_brdfs.bsdfs`) and the integrators (:mod:`mi_brdfs.render`).
"""
from __future__ import annotations

import mitsuba as mi

_bound: dict[tuple[str, type], type] = {}


def bind(cls: type, root: str = "BSDF") -> type:
    """The class ``cls`` rebuilt on top of the active variant's ``mi.<root>``."""
    key = (mi.variant(), cls)
    if key not in _bound:
        base = getattr(mi, root) if cls.__base__ is object else bind(cls.__base__, root)
        body = {k: v for k, v in vars(cls).items() if k not in ("__dict__", "__weakref__")}
        _bound[key] = type(cls.__name__, (base,), body)
    return _bound[key]
