"""An answer per scene: ``mi-brdfs fit --scene SCENE.xml -o DIR [-D key=value ...]
[--models NAME ...] [--quick] [-j N]``.

For every BSDF a shape of the scene uses (built-in or course model; named
BSDFs and ``<ref>`` followed, ``twosided``, ``bumpmap``, ``normalmap`` and
``mask`` wrappers kept as they are and their inner BSDF judged), the cheapest
course model whose render of *that* scene — its own camera, lights and
integrator — looks the same as the original's:

1. **Candidates** come from the per-material fit (:mod:`.task`, with the
   quick settings and without the sphere renders: a scene takes minutes):
   every model (or ``--models``) fitted to the material, the
   :data:`CANDIDATES` best by the fit's ranking (:func:`.rank.ranked`).
2. **Cheapest first**: the candidates are tried in the order of their count
   of traced operations (one ``eval`` and one ``sample``,
   :func:`.cost.operations`, the same on every run: a wall-clock time per
   candidate would be noise at a scene's scale).
3. **Verified in the scene**: the scene is rendered with only that BSDF
   changed, at the seed of the original's render, and compared with it by
   HDR-FLIP (:mod:`mi_brdfs.tools.compare`) over the whole image and over the
   pixels the material covers (those whose camera ray, through the pixel's
   centre, first hits a shape that uses it). The rule is the fit's
   (:func:`.rank.looks_the_same`): the original is the best "fit" (FLIP 0
   against itself) and the tolerance is its seed noise, the FLIP between two
   renders of the original at different seeds, each over the same pixels. A
   candidate looks the same when both its errors are within their
   tolerances; the first that does is the material's stand-in, and it
   replaces the original when it is cheaper by the fit's rule
   (:func:`.rank.cheaper`: a lower cost class, its operations over the
   original's below 1.05^-½).

**Kept as they are**, each with its reason in one line: an area light's
surface (a shape that emits keeps its BSDF; one shared with other shapes is
copied inline for the light), BSDFs that transmit light (``dielectric``,
``thindielectric``, ``roughdielectric``, a principled with transmission),
measured BSDFs, BSDFs with a texture (the fit fits constant parameters),
those with a delta lobe and every other target the fit refuses
(:func:`.targets.check`), those no candidate of which looks the same, and
those whose stand-in is no cheaper.

**The scene's time** before and after: the two scenes are rendered in turn
(:data:`TIMING_ROUNDS` rounds, one untimed render first in each load), and
the time per sample is the median over the rounds. The time to the same
noise is that times the ratio of the noise at equal samples, the noise being
the relative MSE between two renders at different seeds (:func:`.measures.relmse`)
halved: the time the simplified scene needs to be as noisy as the original.
Both are measured at the analysis resolution (``res``, ``spp``), with the
load average beside them.

**Output** (``DIR``, written atomically, :func:`.destinations.report_dir`:
nothing of the user's is deleted): ``SCENE.simplified.xml``, the scene with
every replaced BSDF swapped in place (``<include>`` files inlined, comments
dropped, the scene's ``<default>`` values kept); every relative file name
(meshes, textures) is rewritten relative to ``DIR``, so that the file loads
from there as long as the scene's folder and ``DIR`` keep their places;
``scenefit.json`` and ``index.html`` (per material: what it was, what it
became or why it was kept, its errors and operations; the scene's times),
and small PNG renders of the two scenes.

Mitsuba's Cornell box (``mi.cornell_box()``, a dictionary) is written as a
scene file by :func:`write_cornell_box` (``python -m
mi_brdfs.tools.fit.scenefit --cornell-box FILE``).
"""
from __future__ import annotations

import argparse
import copy
import gc
import html
import json
import math
import os
import re
import statistics
import time
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass, field

import numpy as np

import drjit as dr
import mitsuba as mi

import mi_brdfs

from .. import compare, destinations
from ...render.tonemap import write_png
from ..errors import CLIError, one_line
from ..measures import relmse, render_waited
from . import cost, models as M, rank, sweep, targets as T
from .task import QUICK

RES = 128                  # the renders' longer side (pixels)
SPP = 32
QUICK_RES, QUICK_SPP = 48, 8
CANDIDATES = 4             # the best fits of a material tried in its scene
TIMING_ROUNDS = 3
SETTINGS = QUICK.replace(render=False, cost=False)
WRAPPERS = ("twosided", "bumpmap", "normalmap", "mask")
TRANSMITTING = ("dielectric", "thindielectric", "roughdielectric")
MEASURED = ("measured", "measured_polarized")
SHAPE_MARK = "scenefit-shape"          # attributes on the working tree only, never written
MATERIAL_MARK = "scenefit-material"


# ----------------------------------------------------------------------------
#  Reading the scene
# ----------------------------------------------------------------------------

def _subst(text: str, params: dict) -> str:
    return re.sub(r"\$(\w+)", lambda m: str(params.get(m.group(1), m.group(0))), text)


def _parse(path: str, shown: str) -> ElementTree.Element:
    try:
        return ElementTree.parse(path).getroot()
    except ElementTree.ParseError as error:
        raise CLIError(f"--scene {shown}: not well-formed XML ({error}; Python's parser is "
                       "stricter than Mitsuba's: e.g. no '--' inside a comment)") from None
    except OSError as error:
        raise CLIError(f"--scene {shown}: cannot read {path} ({error.strerror})") from None


def _rebase(elements, src: str, dst: str, params: dict, also: tuple = ()) -> None:
    """Every relative ``filename`` under ``elements``, read from folder
    ``src`` (or from the first of ``also`` where the file is, as Mitsuba's
    resolver searches its folders in turn), rewritten relative to folder ``dst``."""
    for top in elements:
        for e in top.iter():
            if e.tag == "string" and e.get("name") == "filename":
                value = _subst(e.get("value", ""), params)
                if not os.path.isabs(value):
                    found = next((f for f in (src, *also)
                                  if os.path.exists(os.path.join(f, value))), src)
                    value = os.path.relpath(os.path.join(found, value), dst)
                e.set("value", value.replace(os.sep, "/"))


def _inline(parent: ElementTree.Element, folder: str, base: str, params: dict, shown: str,
            depth: int = 0) -> None:
    """``<include>`` elements of ``parent`` replaced by the files' elements
    (their relative file names rebased to ``base``)."""
    for i, e in reversed(list(enumerate(parent))):
        if e.tag != "include":
            continue
        if depth > 8:
            raise CLIError(f"--scene {shown}: <include> nested deeper than 8")
        path = os.path.join(folder, _subst(e.get("filename", ""), params))
        root = _parse(path, shown)
        here = os.path.dirname(os.path.abspath(path))
        _inline(root, here, base, params, shown, depth + 1)
        found = list(root) if root.tag == "scene" else [root]
        _rebase(found, here, base, params, also=(base,))
        parent.remove(e)
        for j, child in enumerate(found):
            parent.insert(i + j, child)


def read_scene(path: str, defines: dict | None = None) -> tuple[ElementTree.Element, dict]:
    """The scene's element tree (includes inlined) and its parameters (its
    ``<default>`` values, overridden by ``defines``); CLIError on one line."""
    root = _parse(path, path)
    if root.tag != "scene":
        raise CLIError(f"--scene {path}: its root is <{root.tag}>, not <scene>; "
                       "give a Mitsuba scene file")
    params = {d.get("name"): d.get("value") for d in root.iter("default")}
    params.update(defines or {})
    folder = os.path.dirname(os.path.abspath(path))
    _inline(root, folder, folder, params, path)
    return root, params


# ----------------------------------------------------------------------------
#  Materials
# ----------------------------------------------------------------------------

@dataclass
class Material:
    """One BSDF the scene's shapes use (the innermost, wrappers left out)."""
    key: str
    element: ElementTree.Element
    label: str
    shapes: list = field(default_factory=list)       # shape numbers
    wrappers: list = field(default_factory=list)
    emitter: bool = False

    @property
    def plugin(self) -> str:
        return self.element.get("type", "?")


def _named(root) -> dict:
    return {e.get("id"): e for e in root.iter("bsdf") if e.get("id")}


def _attached(shape):
    return next((c for c in shape if c.tag in ("bsdf", "ref")), None)


def _resolve(e, named):
    return named.get(e.get("id")) if e is not None and e.tag == "ref" else e


def _inner(e, named):
    """(innermost BSDF element, wrapper types) of an attached BSDF element."""
    wrappers = []
    e = _resolve(e, named)
    while e is not None and e.get("type") in WRAPPERS:
        inner = _resolve(next((c for c in e if c.tag in ("bsdf", "ref")
                               and (c.tag == "bsdf" or c.get("id") in named)), None), named)
        if inner is None:
            break
        wrappers.append(e.get("type"))
        e = inner
    return e, wrappers


def _standalone(e, named) -> ElementTree.Element:
    """A copy of a BSDF element with every ``<ref>`` to a named BSDF inlined
    and no id (for an emitter's own copy and for a target's XML)."""
    e = copy.deepcopy(_resolve(e, named))
    e.attrib.pop("id", None)
    for parent in list(e.iter()):
        for i, c in enumerate(list(parent)):
            if c.tag == "ref" and c.get("id") in named:
                parent.remove(c)
                parent.insert(i, _standalone(c, named))
    return e


def find_materials(root) -> list[Material]:
    """The scene's materials, in the order shapes first use them; each shape
    and material element marked (:data:`SHAPE_MARK`, :data:`MATERIAL_MARK`).
    A shape that emits gets its own inline copy of its BSDF (kept)."""
    named = _named(root)
    found: dict[int, Material] = {}
    for n, shape in enumerate(root.iter("shape")):
        shape.set(SHAPE_MARK, str(n))
        attached = _attached(shape)
        if attached is None or (attached.tag == "ref" and attached.get("id") not in named):
            continue
        emits = shape.find("emitter") is not None
        if emits:                              # the light keeps its own copy of its BSDF
            own = _standalone(attached, named)
            index = list(shape).index(attached)
            shape.remove(attached)
            shape.insert(index, own)
            attached = own
        element, wrappers = _inner(attached, named)
        if element is None:
            continue
        m = found.get(id(element))
        if m is None:
            key = f"m{len(found) + 1}"
            name = element.get("id") or shape.get("id") or f"shape {n + 1} ({shape.get('type')})"
            label = f"{name}: {element.get('type')}"
            m = found[id(element)] = Material(key, element, label, wrappers=wrappers)
            element.set(MATERIAL_MARK, key)
        m.shapes.append(n)
        m.emitter = m.emitter or emits
    return list(found.values())


def target_xml(m: Material, root, params: dict) -> str:
    """The material as a standalone ``<bsdf>`` (parameters substituted)."""
    e = _standalone(m.element, _named(root))
    e.attrib.pop(MATERIAL_MARK, None)
    for sub in e.iter():
        sub.attrib.pop(MATERIAL_MARK, None)
    e.set("version", "3.0.0")
    return _subst(ElementTree.tostring(e, encoding="unicode"), params)


def kept_reason(m: Material, target: T.Target, named: dict) -> str | None:
    """Why no course model can stand for ``m`` (one line), or None."""
    if m.emitter:
        return "the surface of an area light: a light keeps its own BSDF"
    if m.plugin in TRANSMITTING:
        return f"{m.plugin} transmits light; every course model only reflects"
    if m.plugin in MEASURED:
        return f"{m.plugin}: measured data, kept as measured"
    if any(e.tag == "texture" or (e.tag == "ref" and e.get("id") not in named)
           for e in m.element.iter()):
        return "a texture drives its parameters; the fit fits constant parameters"
    try:
        T.check(target)
        bsdf = target.load()
        transmits = bool(bsdf.flags() & mi.BSDFFlags.Transmission)
        del bsdf
    except T.TargetError as error:
        return str(error).replace(f"target {target.spec}: ", "")
    except Exception as error:
        return one_line(error)
    finally:
        gc.collect()
    if transmits:
        return f"{m.plugin} transmits light here; every course model only reflects"
    return None


# ----------------------------------------------------------------------------
#  Variants of the scene, renders, pixels
# ----------------------------------------------------------------------------

def replacement(m: Material, properties: dict) -> ElementTree.Element:
    """A fitted model's ``<bsdf>`` in ``m``'s place (its id, and the
    original's ``mode`` if it had one)."""
    e = ElementTree.fromstring(M.xml(properties))
    e.attrib.pop("version", None)
    if m.element.get("id"):
        e.set("id", m.element.get("id"))
    mode = next((c for c in m.element if c.tag == "string" and c.get("name") == "mode"), None)
    if mode is not None:
        for c in e:
            if c.tag == "string" and c.get("name") == "mode":
                c.set("value", mode.get("value"))
    return e


def variant(root, swaps: dict, res: int | None = None, params: dict | None = None
            ) -> ElementTree.Element:
    """A copy of the scene with ``swaps`` (material key -> element) in place
    and the marks removed; with ``res``, shapes get ids (``scenefit-shape-N``
    unless they have one) and the film's longer side is ``res``."""
    r = copy.deepcopy(root)
    parents = {c: p for p in r.iter() for c in p}
    for e in list(r.iter()):
        key = e.attrib.pop(MATERIAL_MARK, None)
        number = e.attrib.pop(SHAPE_MARK, None)
        if res is not None and number is not None and not e.get("id"):
            e.set("id", f"{SHAPE_MARK}-{number}")
        if key in swaps:
            p = parents[e]
            i = list(p).index(e)
            p.remove(e)
            p.insert(i, copy.deepcopy(swaps[key]))
    if res is not None:
        _film_size(r, res, params or {})
    return r


def _film_size(root, res: int, params: dict) -> None:
    sensor = root.find("sensor")
    if sensor is None:
        raise CLIError("--scene: the scene has no <sensor> at its top level; nothing to render")
    film = sensor.find("film")
    if film is None:
        film = ElementTree.SubElement(sensor, "film", {"type": "hdrfilm"})
    size = {}
    for name, default in (("width", 768), ("height", 576)):
        e = next((c for c in film if c.tag == "integer" and c.get("name") == name), None)
        if e is None:
            e = ElementTree.SubElement(film, "integer", {"name": name, "value": str(default)})
        size[name] = (e, int(float(_subst(e.get("value"), params))))
    scale = res / max(v for _, v in size.values())
    for e, v in size.values():
        e.set("value", str(max(1, round(v * scale))))


def shape_number(root) -> dict:
    """Shape id in a render variant (:func:`variant`) -> shape number, from the marked tree."""
    return {(s.get("id") or f"{SHAPE_MARK}-{s.get(SHAPE_MARK)}"): int(s.get(SHAPE_MARK))
            for s in root.iter("shape")}


class Scenes:
    """Loads variants of one scene for rendering (parameters and the
    scene's folder for relative file names)."""

    def __init__(self, path: str, params: dict, res: int, spp: int):
        self.folder = os.path.dirname(os.path.abspath(path))
        self.params, self.res, self.spp = params, res, spp

    def load(self, root, optimize: bool = True):
        """The scene (``optimize=False``: shapes not merged, so that each keeps its id)."""
        resolver = mi.file_resolver()
        if self.folder not in [str(p) for p in resolver]:
            resolver.prepend(self.folder)
        text = ElementTree.tostring(root, encoding="unicode")
        used = {k: v for k, v in self.params.items() if re.search(rf"\${k}\b", text)}
        return mi.load_string(text, parallel=False, optimize=optimize, **used)

    def render(self, root, seed: int = 0) -> np.ndarray:
        scene = self.load(root)
        try:
            return np.array(render_waited(scene, self.spp, seed), dtype=np.float64)[..., :3]
        finally:
            del scene
            gc.collect()


def covered(scene, numbers: dict) -> dict[int, np.ndarray]:
    """Shape number -> (H, W) True where the camera ray through the pixel's
    centre first hits that shape."""
    sensor = scene.sensors()[0]
    w, h = (int(v) for v in sensor.film().crop_size())
    i = dr.arange(mi.UInt32, w * h)
    pos = mi.Vector2f((mi.Float(i % w) + 0.5) / w, (mi.Float(i // w) + 0.5) / h)
    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    si = scene.ray_intersect(ray)
    out = {}
    for s in scene.shapes():
        if s.id() in numbers:
            hit = si.is_valid() & (si.shape == mi.ShapePtr(s))
            out[numbers[s.id()]] = np.array(hit, dtype=bool).reshape(h, w)
    return out


def flips(ref: np.ndarray, test: np.ndarray, pixels: np.ndarray) -> tuple[float, float | None]:
    """HDR-FLIP over the whole image and over ``pixels`` (None if it is empty)."""
    whole = compare.metrics(ref, test, flip_mode="hdr")["flip"]
    if not pixels.any():
        return whole, None
    return whole, compare.metrics(ref, test, flip_mode="hdr", mask=~pixels)["flip"]


def looks_same(error: float | None, noise: float | None) -> bool:
    """The fit's rule (:func:`.rank.looks_the_same`), the original as the
    best fit (FLIP 0) and its seed noise as the tolerance."""
    if error is None:
        return True
    records = [{"model": "original", "image_flip": 0.0, "image_noise_flip": noise},
               {"model": "candidate", "image_flip": error, "image_noise_flip": noise}]
    return rank.looks_the_same(records[1], records)


def _ops(load) -> int:
    bsdf = load()
    try:
        return cost.operations(bsdf)
    finally:
        del bsdf
        gc.collect()


# ----------------------------------------------------------------------------
#  Timing
# ----------------------------------------------------------------------------

def timing(scenes: Scenes, before, after, rounds: int = TIMING_ROUNDS) -> dict:
    """Time per sample of each scene (median over ``rounds``, the order
    alternating, one untimed render per load) and the noise of each at equal
    samples (relMSE between seeds 0 and 1, halved)."""
    times = {"before": [], "after": []}
    for k in range(rounds):
        for name in (("before", "after") if k % 2 == 0 else ("after", "before")):
            scene = scenes.load(before if name == "before" else after)
            render_waited(scene, scenes.spp, 100)
            start = time.perf_counter()
            render_waited(scene, scenes.spp, 101 + k)
            times[name].append((time.perf_counter() - start) / scenes.spp)
            del scene
            gc.collect()
    noise = {}
    for name, root in (("before", before), ("after", after)):
        a, b = scenes.render(root, 0), scenes.render(root, 1)
        noise[name] = relmse(a, b) / 2
    tps = {k: statistics.median(v) for k, v in times.items()}
    ratio = tps["after"] / tps["before"]
    noise_ratio = noise["after"] / noise["before"] if noise["before"] > 0 else math.nan
    return {"seconds_per_sample": tps, "samples": times, "noise": noise,
            "time_per_sample_ratio": ratio, "noise_ratio": noise_ratio,
            "time_to_noise_ratio": ratio * noise_ratio,
            "load_average": os.getloadavg()[0], "cores": os.cpu_count(),
            "res": scenes.res, "spp": scenes.spp, "rounds": rounds}


# ----------------------------------------------------------------------------
#  The run
# ----------------------------------------------------------------------------

def _check_models(model_names):
    try:
        return M.select(model_names)
    except ValueError as error:
        raise CLIError(f"--models: {error}") from None


def fit_scene(scene_path: str, out_dir: str, defines: dict | None = None,
              model_names: list[str] | None = None, res: int = RES, spp: int = SPP,
              jobs: int | None = None, show=None, command: str = "mi-brdfs fit --scene",
              candidates: int = CANDIDATES, rounds: int = TIMING_ROUNDS, log=None) -> dict:
    """Simplify every material of ``scene_path`` (module docstring) and write
    the report to ``out_dir``; returns the report's record. ``log(line)``
    after each material's verdict and before the timing."""
    log = log or (lambda line: None)
    if mi.variant() != "llvm_ad_rgb":
        mi.set_variant("llvm_ad_rgb")
    mi_brdfs.register()
    start = time.perf_counter()
    destinations.check_report_dir(out_dir, [scene_path])
    compare.require_reports()
    chosen_models = _check_models(model_names)
    root, params = read_scene(scene_path, defines)
    materials = find_materials(root)
    if not materials:
        raise CLIError(f"--scene {scene_path}: no shape has a BSDF; nothing to fit")
    folder = os.path.dirname(os.path.abspath(scene_path))
    scenes = Scenes(scene_path, params, res, spp)
    base = variant(root, {}, res, params)
    try:
        scene = scenes.load(base, optimize=False)
    except Exception as error:
        raise CLIError(f"--scene {scene_path}: {one_line(error)}") from None
    pixels = covered(scene, shape_number(root))
    del scene
    gc.collect()

    rows, targets = [], {}
    for m in materials:
        t = T.Target(m.label, f"{m.key}-{T.slug(m.label)}", xml=target_xml(m, root, params),
                     folder=folder)
        mask = np.zeros(next(iter(pixels.values())).shape, bool) if pixels else None
        for n in m.shapes:
            if n in pixels:
                mask |= pixels[n]
        row = {"key": m.key, "label": m.label, "plugin": m.plugin, "shapes": len(m.shapes),
               "wrappers": m.wrappers, "xml": t.xml,
               "pixels": float(mask.mean()) if mask is not None else 0.0}
        row["kept_because"] = kept_reason(m, t, _named(root))
        row["_mask"] = mask
        rows.append(row)
        if row["kept_because"] is None:
            targets[m.key] = t
    tasks = [(t, model) for t in targets.values() for model in chosen_models]
    records = sweep.run_fits(tasks, SETTINGS, jobs=jobs, show=show) if tasks else []
    fit_seconds = time.perf_counter() - start

    reference = scenes.render(base, 0)
    again = scenes.render(base, 1)
    swaps = {}
    for row, m in zip(rows, materials):
        if row["kept_because"] is not None:
            continue
        t = targets[m.key]
        fits = [r for r in records if r.get("target_name") == t.name]
        order = rank.ranked(fits)[:candidates]
        if not order:
            row["kept_because"] = "every fit failed: " + "; ".join(
                sorted({r.get("error", "?") for r in fits}))[:300]
            continue
        row["ops"] = _ops(t.load)
        mask = row["_mask"]
        noise = flips(reference, again, mask)
        row["noise_flip"] = {"image": noise[0], "pixels": noise[1]}
        tried = []
        for r in order:
            tried.append({"model": r["model"], "parameters": r["parameters"],
                          "objective_error": r.get("objective_error"),
                          "ops": _ops(lambda p=r["parameters"]: mi.load_dict(M.load_dict(p)))})
        tried.sort(key=lambda c: (c["ops"], c["objective_error"] or 0.0, c["model"]))
        row["tried"] = tried
        for c in tried:
            element = replacement(m, c["parameters"])
            image = scenes.render(variant(root, {m.key: element}, res, params), 0)
            c["flip_image"], c["flip_pixels"] = flips(reference, image, mask)
            c["looks_same"] = (looks_same(c["flip_image"], noise[0])
                               and looks_same(c["flip_pixels"], noise[1]))
            c["cheaper"] = rank.cheaper({"cost_ratio": c["ops"] / row["ops"]},
                                        {"cost_ratio": 1.0})
            if c["looks_same"]:
                row["stand_in"] = c
                if c["cheaper"]:
                    row["became"] = c
                    swaps[m.key] = element
                break
        if "became" in row:
            log(f"{m.label}: becomes {row['became']['model']} ({row['became']['ops']} traced "
                f"operations against {row['ops']})")
            continue
        if "stand_in" in row:
            c = row["stand_in"]
            row["kept_because"] = (
                f"the cheapest course model that looks the same, {c['model']}, is no cheaper: "
                f"{c['ops']} traced operations against {row['ops']} (FLIP "
                f"{c['flip_image']:.3f} image / {_num(c['flip_pixels'])} its pixels)")
        else:
            best = min(tried, key=lambda c: c["flip_image"])
            row["kept_because"] = (
                f"no course model looks the same in the scene: the closest of the "
                f"{len(tried)} best fits, {best['model']}, is at FLIP {best['flip_image']:.3f} "
                f"(image) / {_num(best['flip_pixels'])} (its pixels) against the seed noise "
                f"{noise[0]:.3f} / {_num(noise[1])}")

    for row in rows:
        if "became" not in row:
            log(f"{row['label']}: kept: {row['kept_because']}")
    if swaps:
        log(f"timing the scene before and after ({rounds} rounds)")
    simplified = variant(root, swaps, res, params)
    final = scenes.render(simplified, 0)
    for row in rows:
        mask = row.pop("_mask")
        row["error"] = dict(zip(("image", "pixels"), flips(reference, final, mask)
                                if mask is not None else (None, None)))
    times = timing(scenes, base, simplified, rounds) if swaps else None
    whole = flips(reference, final, np.zeros(reference.shape[:2], bool))[0]
    seconds = time.perf_counter() - start
    result = {"scene": scene_path, "command": command, "defines": defines or {},
              "res": list(reference.shape[1::-1]), "spp": spp, "candidates": candidates,
              "models": [m.name for m in chosen_models], "fit_settings": "quick",
              "tolerance": "the original's seed noise: FLIP between its renders at seeds 0 "
                           "and 1, over the whole image and over the material's pixels",
              "materials": rows, "replaced": len(swaps), "flip_image": whole,
              "noise_flip_image": flips(reference, again, np.zeros(reference.shape[:2], bool))[0],
              "timing": times, "fit_seconds": fit_seconds, "seconds": seconds,
              "simplified": _stem(scene_path) + ".simplified.xml"}
    out_root = variant(root, swaps)
    with destinations.report_dir(out_dir, "fit", [scene_path]) as tmp:
        _rebase([out_root], folder, destinations.report_target(out_dir), params)
        ElementTree.indent(out_root)
        with open(os.path.join(tmp, result["simplified"]), "w", encoding="utf-8") as f:
            f.write(ElementTree.tostring(out_root, encoding="unicode") + "\n")
        write_png(os.path.join(tmp, "original.png"), reference)
        write_png(os.path.join(tmp, "simplified.png"), final)
        with open(os.path.join(tmp, "scenefit.json"), "w", encoding="utf-8") as f:
            json.dump(result, f, indent=1, default=float)
        with open(os.path.join(tmp, "index.html"), "w", encoding="utf-8") as f:
            f.write(html_report(result))
    return result


def _stem(path: str) -> str:
    return os.path.splitext(os.path.basename(path))[0]


def _num(x, spec: str = ".3f") -> str:
    return "—" if x is None else format(x, spec)


def summary(result: dict) -> str:
    """One line: what changed and the time."""
    t = result["timing"]
    text = f"{result['replaced']} of {len(result['materials'])} materials replaced"
    if t:
        text += (f"; time per sample {t['time_per_sample_ratio']:.2f}×, time to the same noise "
                 f"{t['time_to_noise_ratio']:.2f}× (load {t['load_average']:.1f})")
    return text + f"; whole image FLIP {result['flip_image']:.3f}"


def html_report(result: dict) -> str:
    esc = html.escape
    rows = []
    for r in result["materials"]:
        if "became" in r:
            c = r["became"]
            became = (f"<b>{esc(c['model'])}</b> ({c['ops']} operations against {r['ops']})"
                      f"<br><code>{esc(json.dumps(c['parameters']))}</code>")
        else:
            became = f"kept: {esc(r['kept_because'])}"
        tried = "<br>".join(
            f"{esc(c['model'])}: {c['ops']} ops"
            + (f", FLIP {_num(c['flip_image'])} / {_num(c['flip_pixels'])}"
               f"{' (looks the same)' if c['looks_same'] else ''}" if "looks_same" in c
               else ", not rendered (a cheaper one looked the same)")
            for c in r.get("tried", []))
        noise = r.get("noise_flip") or {}
        rows.append(
            f"<tr><td>{esc(r['label'])}{' (in ' + esc(', '.join(r['wrappers'])) + ')' if r['wrappers'] else ''}"
            f"<br>{r['shapes']} shape(s), {100 * r['pixels']:.1f} % of the pixels</td>"
            f"<td>{became}</td><td>{_num(r['error']['image'])}</td>"
            f"<td>{_num(r['error']['pixels'])}</td>"
            f"<td>{_num(noise.get('image'))} / {_num(noise.get('pixels'))}</td>"
            f"<td>{tried}</td></tr>")
    t = result["timing"]
    if t:
        sps = t["seconds_per_sample"]
        timing_text = (
            f"<p>Time per sample ({t['res']} px longer side, {t['spp']} spp, median of "
            f"{t['rounds']} rounds, load average {t['load_average']:.1f} on {t['cores']} cores): "
            f"{1e3 * sps['before']:.2f} ms before, {1e3 * sps['after']:.2f} ms after "
            f"({t['time_per_sample_ratio']:.2f}×). Noise at equal samples (relMSE between two "
            f"seeds, halved): {t['noise']['before']:.3g} before, {t['noise']['after']:.3g} after "
            f"({t['noise_ratio']:.2f}×). Time to the original's noise: "
            f"<b>{t['time_to_noise_ratio']:.2f}×</b> the original's.</p>")
    else:
        timing_text = "<p>Nothing was replaced: the scene is as it was, and so is its time.</p>"
    w, h = result["res"]
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>Scene fit: {esc(result['scene'])}</title>
<style>body{{font-family:sans-serif;max-width:72em;margin:1em auto}}
td,th{{border-bottom:1px solid #ccc;padding:4px;vertical-align:top;text-align:left}}
table{{border-collapse:collapse}} code{{font-size:80%}}</style></head><body>
<h1>Scene fit: {esc(os.path.basename(result['scene']))}</h1>
<p><code>{esc(result['command'])}</code></p>
<p>{esc(summary(result))}. The simplified scene: <a href="{esc(result['simplified'])}">{esc(result['simplified'])}</a>.</p>
<p>Each material's candidates are the {result['candidates']} best of the per-material fit
(quick settings, models: {len(result['models'])}), tried from the fewest traced operations
(one eval and one sample) and only when fewer than the original's; each is rendered in the
scene with only that BSDF changed ({w}×{h} px, {result['spp']} spp, the original's seed) and
compared by HDR-FLIP over the whole image and over the pixels the material covers. It looks
the same when both are within the tolerance: {esc(result['tolerance'])}. Errors below are
of the simplified scene (every replacement in place) against the original.</p>
<figure style="display:inline-block"><img src="original.png" width="{2 * w}"><figcaption>original</figcaption></figure>
<figure style="display:inline-block"><img src="simplified.png" width="{2 * w}"><figcaption>simplified
(whole image FLIP {result['flip_image']:.3f}; the original's seed noise {result['noise_flip_image']:.3f})</figcaption></figure>
<table><tr><th>material</th><th>became</th><th>FLIP image</th><th>FLIP its pixels</th>
<th>seed noise (image / pixels)</th><th>tried (FLIP image / pixels)</th></tr>
{''.join(rows)}</table>
{timing_text}
<p>Fits {result['fit_seconds']:.0f} s; the whole run {result['seconds']:.0f} s.</p>
</body></html>
"""


# ----------------------------------------------------------------------------
#  Mitsuba's Cornell box as a scene file
# ----------------------------------------------------------------------------

_TAGS = {"sensor": "sensor", "film": "film", "rfilter": "rfilter", "sampler": "sampler",
         "integrator": "integrator", "emitter": "emitter", "bsdf": "bsdf"}
_SHAPES = ("rectangle", "cube", "sphere", "obj", "ply", "disk", "cylinder")


def _xml_value(parent, name: str, value) -> None:
    if isinstance(value, dict):
        if value.get("type") == "ref":
            ElementTree.SubElement(parent, "ref", {"id": value["id"]})
        elif value.get("type") == "rgb":
            ElementTree.SubElement(parent, "rgb", {
                "name": name, "value": ", ".join(repr(float(v)) for v in value["value"])})
        else:
            tag = _TAGS.get(name) or ("shape" if value.get("type") in _SHAPES else "bsdf")
            e = ElementTree.SubElement(parent, tag, {"type": value["type"]})
            if parent.tag == "scene" and tag in ("shape", "bsdf"):
                e.set("id", name)
            for k, v in value.items():
                if k != "type":
                    _xml_value(e, k, v)
    elif isinstance(value, bool):
        ElementTree.SubElement(parent, "boolean", {"name": name, "value": str(value).lower()})
    elif isinstance(value, int):
        ElementTree.SubElement(parent, "integer", {"name": name, "value": str(value)})
    elif isinstance(value, float):
        ElementTree.SubElement(parent, "float", {"name": name, "value": repr(value)})
    elif isinstance(value, str):
        ElementTree.SubElement(parent, "string", {"name": name, "value": value})
    elif isinstance(value, mi.ScalarTransform4f):
        t = ElementTree.SubElement(parent, "transform", {"name": name})
        matrix = np.array(value.matrix, dtype=np.float64)
        ElementTree.SubElement(t, "matrix", {"value": " ".join(repr(float(v))
                                                               for v in matrix.ravel())})
    else:
        raise ValueError(f"{name}: {type(value).__name__} values are not written")


def dict_xml(scene: dict) -> str:
    """A scene dictionary of the kinds ``mi.cornell_box()`` holds (objects,
    references, rgb, numbers, strings, transforms) as scene XML."""
    root = ElementTree.Element("scene", {"version": "3.0.0"})
    for k, v in scene.items():
        if k != "type":
            _xml_value(root, k, v)
    ElementTree.indent(root)
    return ElementTree.tostring(root, encoding="unicode") + "\n"


def write_cornell_box(path: str) -> None:
    """``mi.cornell_box()`` written as a scene file at ``path``."""
    if mi.variant() is None:
        mi.set_variant("llvm_ad_rgb")
    with open(path, "w", encoding="utf-8") as f:
        f.write(dict_xml(mi.cornell_box()))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m mi_brdfs.tools.fit.scenefit",
                                description="write Mitsuba's Cornell box as a scene file")
    p.add_argument("--cornell-box", required=True, metavar="FILE")
    args = p.parse_args(argv)
    write_cornell_box(args.cornell_box)
    print(f"wrote {args.cornell_box}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
