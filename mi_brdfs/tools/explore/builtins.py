"""Mitsuba's built-in BSDFs the explorer compares with, declared in the schema
of the course plugins (:func:`.backend.course_models`).

Only the parameters the page offers are declared; their defaults are what
Mitsuba 3.9.1 loads when they are left out (read back with ``mi.traverse``),
their ranges those of Mitsuba's documentation. Mitsuba does not check most of
them, so :mod:`.material` does, with the course plugins' message.
"""
from __future__ import annotations

DISTRIBUTIONS = ["beckmann", "ggx"]
# Conductors of Mitsuba's table of measured η, k ("none": a perfect mirror's F = 1).
CONDUCTORS = ["none", "Ag", "Al", "Au", "Cr", "Cu"]


def _param(name: str, default: float, kind: str = "scalar", role: str = "shape",
           hi: float | None = 1.0, upper: float = 1.0, doc: str = "") -> dict:
    return {"name": name, "kind": kind, "role": role, "default": default, "lo": 0.0, "hi": hi,
            "upper": upper, "optional": False, "doc": doc}


def _colour(name: str, default: float, doc: str) -> dict:
    return _param(name, default, kind="spectrum", role="colour", doc=doc)


def _choice(name: str, default: str, choices: list[str], doc: str) -> dict:
    return {"name": name, "type": "string", "default": default, "choices": choices,
            "lo": None, "hi": None, "doc": doc}


ROUGHNESS = "the microfacet roughness α (Mitsuba's alpha)"

BUILTINS = [
    {"name": "diffuse", "title": "diffuse — Mitsuba's Lambertian BSDF",
     "params": [_colour("reflectance", 0.5, "the albedo")],
     "options": []},
    {"name": "roughconductor", "title": "roughconductor — Mitsuba's rough conductor",
     "params": [_param("alpha", 0.1, hi=None, doc=ROUGHNESS),
                _colour("specular_reflectance", 1.0, "a factor on the Fresnel reflectance")],
     "options": [_choice("distribution", "beckmann", DISTRIBUTIONS, "the microfacet distribution"),
                 _choice("material", "none", CONDUCTORS, "the conductor's measured η, k")]},
    {"name": "roughplastic", "title": "roughplastic — Mitsuba's rough plastic",
     "params": [_colour("diffuse_reflectance", 0.5, "the diffuse base's albedo"),
                _param("alpha", 0.1, kind="float", hi=None, doc=ROUGHNESS)],
     "options": [_choice("distribution", "beckmann", DISTRIBUTIONS, "the microfacet distribution")]},
    {"name": "principled", "title": "principled — Mitsuba's Disney principled BSDF",
     "params": [_colour("base_color", 0.5, "the base colour"),
                _param("roughness", 0.5, doc="the roughness"),
                _param("metallic", 0.0, role="weight", doc="0 dielectric, 1 metal"),
                _param("specular", 0.5, kind="float", role="weight",
                       doc="the dielectric's specular reflectance at normal incidence"),
                _param("spec_tint", 0.0, role="weight", doc="tint of the specular by the base"),
                _param("sheen", 0.0, role="weight", doc="the sheen's weight"),
                _param("clearcoat", 0.0, role="weight", doc="the clear coat's weight"),
                _param("clearcoat_gloss", 0.0, doc="the clear coat's glossiness")],
     "options": []},
]


def builtin_models() -> list[dict]:
    """The built-ins, each marked ``"source": "mitsuba"``."""
    return [{**m, "source": "mitsuba", "compensable": False} for m in BUILTINS]
