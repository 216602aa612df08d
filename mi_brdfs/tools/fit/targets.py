"""Fit targets: any Mitsuba BSDF, named on the command line.

A target is either

- an XML file whose root element is a ``<bsdf>`` (as Mitsuba writes one
  material), or a scene file holding exactly one ``<bsdf>`` at its top level;
- the shorthand ``PLUGIN:key=value,...``, e.g. ``roughconductor:material=Au,alpha=0.3``
  or ``roughplastic:alpha=0.1,diffuse_reflectance=[0.6,0.2,0.1]``: numbers are
  floats, ``true``/``false`` booleans, ``[r,g,b]`` (or ``[v]``) colours, anything
  else a string (a material name, a distribution, a file name).

A :class:`Target` carries the XML text itself (not only its path), so that a
worker on another machine can load it; files the XML refers to (a measured
BSDF's data, a texture) are resolved relative to the XML's folder, which must
then exist at the same path on the workers.

Targets are checked before any work (:func:`check`): the file or shorthand
must load as a BSDF with no delta lobe (a perfectly smooth conductor or
coating: ``eval`` never sees it, no model fitted to ``eval`` could represent
it; give the rough plugin a small ``alpha``), give finite values, and
reflect light (a black target is refused: every model would fit it, and its
errors, relative to its own brightness, are 0/0). A target given twice is
fitted once (:func:`unique`).
"""
from __future__ import annotations

import math
import os
import re
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass

import numpy as np

import mitsuba as mi

from ..errors import one_line
from .effective import albedo
from .metric import pairs
from .optimise import eval_pairs


class TargetError(ValueError):
    """A target that cannot be fitted (reported on one line)."""


@dataclass(frozen=True)
class Target:
    """What a worker needs to load one target."""
    spec: str                    # as given on the command line
    name: str                    # short, file-name safe, unique within a run
    xml: str | None = None       # the XML text (XML targets)
    folder: str | None = None    # the XML's folder (relative file names)
    props: tuple = ()            # the shorthand's (key, value) pairs, plugin first

    def load(self):
        """The target as a Mitsuba BSDF (in the active variant)."""
        if self.xml is None:
            return mi.load_dict(self.as_dict())
        if self.folder:
            resolver = mi.file_resolver()
            if self.folder not in [str(p) for p in resolver]:
                resolver.prepend(self.folder)
        obj = mi.load_string(self.xml)
        if isinstance(obj, mi.Scene):
            raise TargetError(f"target {self.spec}: the scene holds no <bsdf> at its top level")
        return obj

    def as_dict(self) -> dict:
        """The shorthand as a ``mi.load_dict`` dictionary."""
        d = dict(self.props)
        return {k: ({"type": "rgb", "value": list(v)} if isinstance(v, tuple) else v)
                for k, v in d.items()}


# ----------------------------------------------------------------------------
#  Parsing
# ----------------------------------------------------------------------------

SHORTHAND = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*):(.*)$")


def parse_value(text: str):
    """A shorthand value: float, bool, colour (tuple) or string."""
    t = text.strip()
    if t.lower() in ("true", "false"):
        return t.lower() == "true"
    if t.startswith("[") != t.endswith("]"):
        raise ValueError(f"{t} has unbalanced brackets; a colour is [r,g,b] or [v]")
    if t.startswith("["):
        try:
            values = tuple(float(v) for v in t[1:-1].split(","))
        except ValueError:
            raise ValueError(f"{t} is not a colour; valid: [r,g,b] or [v] (numbers)") from None
        if len(values) == 1:
            values = values * 3
        if len(values) != 3 or not all(math.isfinite(v) for v in values):
            raise ValueError(f"{t} is not a colour; valid: [r,g,b] or [v] (finite numbers)")
        return values
    try:
        value = float(t)
    except ValueError:
        return t
    if not math.isfinite(value):
        raise ValueError(f"{t} is not a finite number")
    return value


def split_pairs(text: str) -> list[str]:
    """``a=1,b=[1,2,3]`` -> ``["a=1", "b=[1,2,3]"]`` (commas inside brackets kept)."""
    parts, depth, current = [], 0, ""
    for ch in text:
        depth += (ch == "[") - (ch == "]")
        if ch == "," and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += ch
    if current or parts:
        parts.append(current)
    return parts


def slug(text: str, limit: int = 48) -> str:
    """A file-name safe rendering of ``text``."""
    s = re.sub(r"[^A-Za-z0-9.]+", "-", text).strip("-.")
    return s[:limit] or "target"


def parse_shorthand(spec: str) -> tuple:
    match = SHORTHAND.match(spec)
    if not match:
        raise TargetError(f"target {spec}: not a file, and not PLUGIN:key=value,... "
                          "(e.g. roughconductor:material=Au,alpha=0.3)")
    plugin, rest = match.groups()
    props = [("type", plugin)]
    for pair in split_pairs(rest):
        key, sep, value = pair.partition("=")
        key = key.strip()
        if not sep or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_.]*", key):
            raise TargetError(f"target {spec}: {pair.strip()!r} is not key=value")
        if key in dict(props):
            raise TargetError(f"target {spec}: {key} is given twice")
        try:
            props.append((key, parse_value(value)))
        except ValueError as error:
            raise TargetError(f"target {spec}: {key}={value.strip()}: {error}") from None
    return tuple(props)


def bsdf_xml(path: str) -> str:
    """The XML text of a file holding a ``<bsdf>`` (root, or the only one at
    the top level of a scene), with a version attribute."""
    try:
        root = ElementTree.parse(path).getroot()
    except ElementTree.ParseError as error:
        raise TargetError(f"target {path}: not an XML file ({error})") from None
    except OSError as error:
        raise TargetError(f"target {path}: cannot read it ({error.strerror})") from None
    if root.tag != "bsdf":
        expected = "valid: a <bsdf> root, or a <scene> with exactly one <bsdf> at its top level"
        if root.tag != "scene":
            raise TargetError(f"target {path}: its root is <{root.tag}>; {expected}")
        found = [e for e in root if e.tag == "bsdf"]
        if len(found) != 1:
            raise TargetError(f"target {path}: its <scene> has {len(found)} <bsdf> at its top "
                              f"level (a <bsdf> inside a <shape> is not counted); {expected}")
        version = root.get("version", "3.0.0")
        root = found[0]
        root.set("version", version)
    root.attrib.setdefault("version", "3.0.0")
    return ElementTree.tostring(root, encoding="unicode")


def parse(specs: list[str]) -> list[Target]:
    """Targets from command-line arguments (files or shorthands), named uniquely."""
    targets = []
    for i, spec in enumerate(specs):
        if os.path.isdir(spec):
            raise TargetError(f"target {spec} is a folder; give an XML file or PLUGIN:key=value,...")
        if os.path.exists(spec):
            base = os.path.splitext(os.path.basename(spec))[0]
            targets.append(Target(spec, f"t{i + 1}-{slug(base)}", xml=bsdf_xml(spec),
                                  folder=os.path.dirname(os.path.abspath(spec))))
        elif spec.lower().endswith(".xml"):
            raise TargetError(f"target {spec}: no such file")
        else:
            props = parse_shorthand(spec)
            label = "-".join([props[0][1]] + [_short(v) for _, v in props[1:]])
            targets.append(Target(spec, f"t{i + 1}-{slug(label)}", props=props))
    return targets


def unique(targets: list[Target]) -> tuple[list[Target], list[str]]:
    """The targets without repeats (the same shorthand values, or the same
    XML), and the specs left out."""
    kept, seen, dropped = [], set(), []
    for t in targets:
        key = t.xml if t.xml is not None else repr(sorted(t.as_dict().items(), key=lambda kv: kv[0]))
        if key in seen:
            dropped.append(t.spec)
        else:
            seen.add(key)
            kept.append(t)
    return kept, dropped


def _short(value) -> str:
    if isinstance(value, tuple):
        return "_".join(f"{v:g}" for v in value)
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


# ----------------------------------------------------------------------------
#  Checking (in the active variant; before any work)
# ----------------------------------------------------------------------------

def check(target: Target) -> None:
    """Raise TargetError unless ``target`` loads as a BSDF that reflects light
    and has no delta lobe. Nothing stays alive afterwards."""
    try:
        bsdf = target.load()
    except TargetError:
        raise
    except Exception as error:
        raise TargetError(f"target {target.spec}: {one_line(error)}") from None
    try:
        if not isinstance(bsdf, mi.BSDF):
            raise TargetError(f"target {target.spec}: it loads as a {type(bsdf).__name__}, "
                              "not a BSDF")
        flags = bsdf.flags()
        if not flags & mi.BSDFFlags.Reflection:
            raise TargetError(f"target {target.spec}: it reflects no light (no reflection lobe)")
        if flags & mi.BSDFFlags.Delta:
            raise TargetError(f"target {target.spec}: it has a delta (perfectly smooth) lobe, "
                              "which eval() never sees and no fitted model can represent; "
                              "use the rough plugin with a small alpha (e.g. roughconductor)")
        check_values(target.spec, bsdf)
    finally:
        del bsdf


def check_values(spec: str, bsdf) -> None:
    """TargetError if ``eval`` is not finite on the quick metric's pairs, or
    if the target reflects no light (0 at every pair, and a directional
    albedo of 0 at 0°, 45° and 80° by its own sampling)."""
    p = pairs("cosine", (8, 4), (8, 8), 16)
    values = eval_pairs(bsdf, p.wi, p.wo)
    bad = int(np.sum(~np.isfinite(values).all(axis=1)))
    if bad:
        raise TargetError(f"target {spec}: its eval is not finite (NaN or infinite) at {bad} of "
                          f"{len(values)} direction pairs")
    reflected = np.array(albedo(bsdf, (0.0, 45.0, 80.0), samples=4096))
    if not (reflected > 0).any() and not (values > 0).any():
        raise TargetError(f"target {spec}: it is black (it reflects no light at any direction "
                          "pair tried, nor in 4096 sampled directions at 0°, 45° and 80°)")
