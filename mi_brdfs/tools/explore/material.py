"""Materials as the page and the API send them, checked against the
declarations, and written as Mitsuba loads them (no Dr.Jit here).

A material is a flat JSON object, as ``mi.load_dict`` takes one with colours
as lists::

    {"type": "cook_torrance", "mode": "hdr", "distribution": "ggx",
     "diffuse_reflectance": [0.5, 0.2, 0.1], "alpha": 0.2}

``type`` names a model of ``GET /api/models``; every other key is one of its
options or parameters, or ``mode`` (for Mitsuba's built-ins, which have no
mode, it picks the preview's integrator only). A colour is a list of three
numbers or one number. Left-out options and parameters take their defaults
(:func:`complete`). This module checks the form (names, JSON types, finite
numbers) and, for the built-ins, the ranges; the course plugins check their
own ranges when they load (:func:`.backend.load`).
"""
from __future__ import annotations

import json
import math

import numpy as np

MODES = ("hdr", "scanline")


class RequestError(ValueError):
    """A malformed request or material, reported on one line."""


def _number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _shown(value) -> str:
    text = json.dumps(value) if not isinstance(value, float) else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _range(p: dict) -> str:
    lo = "-inf" if p["lo"] is None else f"{p['lo']:g}"
    hi = "inf" if p["hi"] is None else f"{p['hi']:g}"
    return f"[{lo}, {hi}]"


def _option_value(model: dict, o: dict, value):
    name, kind = f"{model['name']}: option '{o['name']}'", o["type"]
    if kind == "bool" and not isinstance(value, bool):
        raise RequestError(f"{name} = {_shown(value)} is invalid; valid: true or false")
    if kind == "int" and not (isinstance(value, int) and not isinstance(value, bool)
                              and o["lo"] <= value <= o["hi"]):
        raise RequestError(f"{name} = {_shown(value)} is invalid; valid: an integer in "
                           f"[{o['lo']}, {o['hi']}]")
    if kind == "string" and value not in o["choices"]:
        raise RequestError(f"{name} = {_shown(value)} is invalid; valid: one of "
                           + ", ".join(o["choices"]))
    return value


def _param_value(model: dict, p: dict, value):
    name = f"{model['name']}: parameter '{p['name']}'"
    if p["kind"] == "spectrum" and isinstance(value, list):
        if len(value) == 3 and all(_number(v) for v in value):
            values = [float(v) for v in value]
        else:
            raise RequestError(f"{name} = {_shown(value)} is invalid; valid: a finite number "
                               "or a list of three")
    elif _number(value):
        values = [float(value)]
    else:
        valid = "a finite number" + (" or a list of three" if p["kind"] == "spectrum" else "")
        raise RequestError(f"{name} = {_shown(value)} is invalid; valid: {valid}")
    if model["source"] == "mitsuba":          # the course plugins check their own ranges
        for v in values:
            if (p["lo"] is not None and v < p["lo"]) or (p["hi"] is not None and v > p["hi"]):
                raise RequestError(f"{name} = {v!r} is invalid; valid: {_range(p)}")
    if p["kind"] == "spectrum":
        return values * 3 if len(values) == 1 else values
    return values[0]


def complete(models: dict[str, dict], material) -> dict:
    """``material`` checked and completed with the defaults of its options and
    of its model's controls, in declaration order (``type``, ``mode``, the
    options, the parameters); RequestError names what is wrong."""
    if not isinstance(material, dict):
        raise RequestError(f"a material is a JSON object, not {_shown(material)}")
    name = material.get("type")
    if name not in models:
        raise RequestError(f"model {_shown(name)} is unknown; valid: {', '.join(models)}")
    model = models[name]
    options = {o["name"]: o for o in model["options"]}
    params = {p["name"]: p for p in model["params"]}
    for key in material:
        if key not in ("type", "mode") and key not in options and key not in params:
            raise RequestError(f"{name} has no option or parameter {key!r}; valid: "
                               + ", ".join(["mode", *(o for o in options if o != "mode"),
                                            *params]))
    mode = material.get("mode", "hdr")
    if mode not in MODES:
        raise RequestError(f"{name}: option 'mode' = {_shown(mode)} is invalid; valid: one of "
                           + ", ".join(MODES))
    out = {"type": name, "mode": mode}
    for o in model["options"]:
        if o["name"] != "mode":
            out[o["name"]] = _option_value(model, o, material.get(o["name"], o["default"]))
    for p in model["params"]:
        if p["name"] in material:
            out[p["name"]] = _param_value(model, p, material[p["name"]])
        elif p.get("control", True) and not p["optional"]:
            out[p["name"]] = _param_value(model, p, p["default"])
    return out


def parameter_names(models: dict[str, dict], material: dict) -> list[str]:
    """The keys of a complete material that are parameters (the rest: type and options)."""
    declared = {p["name"] for p in models[material["type"]]["params"]}
    return [k for k in material if k in declared]


# ----------------------------------------------------------------------------
#  As Mitsuba loads it
# ----------------------------------------------------------------------------

def _loadable(models: dict[str, dict], material: dict) -> dict:
    """The items that go to the loader: a built-in's ``mode`` is the preview's only."""
    builtin = models[material["type"]]["source"] == "mitsuba"
    return {k: v for k, v in material.items() if not (builtin and k == "mode")}


def _colour(value) -> list[float]:
    return list(value) if isinstance(value, list) else [value] * 3


def load_dict(models: dict[str, dict], material: dict) -> dict:
    """A complete material as a ``mi.load_dict`` dictionary (colours as ``rgb``)."""
    kinds = {p["name"]: p["kind"] for p in models[material["type"]]["params"]}
    return {k: ({"type": "rgb", "value": _colour(v)} if kinds.get(k) == "spectrum" else v)
            for k, v in _loadable(models, material).items()}


def short(value) -> str:
    """A number as the shortest text that reads back as the same float32 (the
    precision of the llvm_ad_rgb variant): what a user would type, "0.3" for
    0.30000001192092896 or 0.2999999999972802."""
    return str(np.float32(value))


def xml(models: dict[str, dict], material: dict) -> str:
    """A complete material as a ``<bsdf>`` element ``mi.load_string`` loads
    (numbers as :func:`short` writes them)."""
    kinds = {p["name"]: p["kind"] for p in models[material["type"]]["params"]}
    lines = [f'<bsdf type="{material["type"]}" version="3.0.0">']
    for k, v in _loadable(models, material).items():
        if k == "type":
            continue
        if kinds.get(k) == "spectrum":
            lines.append(f'    <rgb name="{k}" value="{", ".join(short(c) for c in _colour(v))}"/>')
        elif isinstance(v, bool):
            lines.append(f'    <boolean name="{k}" value="{"true" if v else "false"}"/>')
        elif isinstance(v, int) and k not in kinds:
            lines.append(f'    <integer name="{k}" value="{v}"/>')
        elif isinstance(v, str):
            lines.append(f'    <string name="{k}" value="{v}"/>')
        else:
            lines.append(f'    <float name="{k}" value="{short(v)}"/>')
    return "\n".join(lines + ["</bsdf>"]) + "\n"


def python(models: dict[str, dict], material: dict) -> str:
    """A complete material as a Python snippet that loads it with ``mi.load_dict``."""
    items = []
    for k, v in load_dict(models, material).items():
        if isinstance(v, dict):
            text = '{"type": "rgb", "value": [' + ", ".join(short(c) for c in v["value"]) + "]}"
        elif isinstance(v, float):
            text = short(v)
        else:
            text = json.dumps(v) if not isinstance(v, bool) else repr(v)
        items.append(f'    "{k}": {text},')
    return "\n".join(["import mi_brdfs  # the course plugins; activates llvm_ad_rgb",
                      "import mitsuba as mi", "", "bsdf = mi.load_dict({", *items, "})"]) + "\n"
