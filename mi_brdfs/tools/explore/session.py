"""What the explorer computes, and the Dr.Jit state it keeps.

One :class:`Explorer` per server, used from one thread at a time (the
worker's, :mod:`.worker`), except :meth:`Explorer.walk` and the pure
:meth:`Explorer.strings`, which touch no Dr.Jit state.

**Loaded configurations.** A configuration is a model with its options (and
``mode``): the parameters it does not expose in ``mi.traverse`` are part of
it too. Each is loaded once into an :class:`Entry` — one BSDF, the preview
scenes that hold it, one per resolution — kept in a small LRU cache. A new
value of a parameter goes through ``mi.traverse`` and ``params.update()`` as
an opaque Dr.Jit value (a literal would be compiled into the kernels, a new
kernel per value), so a parameter change replays the kernels already
compiled; only a change of options loads another configuration. The
plugin checks a new configuration when it loads and new values at
``params.update()``, with the same one-line message; a refused value leaves
the values before.
"""
from __future__ import annotations

import base64
import math
from collections import OrderedDict

import numpy as np

import drjit as dr
import mitsuba as mi

from . import backend, preview
from .builtins import builtin_models
from .material import RequestError, complete, load_dict, parameter_names, python, xml

ALBEDO_ANGLES = tuple(range(0, 90, 5)) + (89,)   # degrees
ALBEDO_SIDE = 48                                 # 48² samples of the BSDF per angle
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
LOBE_POINTS = 181                                # the plane of incidence, -90° .. 90°
HEMISPHERE_N = 30                                # the 3-D lobe: n × 4n directions
RESOLUTIONS = (128, 256)
PASSES = (1, 3, 4, 8)             # spp of the first passes, then 8 each: a quick first
#                                   image, and a pass runs to its end (the plots a slider
#                                   asks for wait for the pass running, never longer)
MAX_SPP = 256                                    # a preview stops refining here
CACHE = 12                                       # loaded configurations kept
WALK_PATHS = 8000                                # random-walk paths per angle
WALK_CACHE = 64


def rounded(a, digits: int = 4) -> list:
    """An array as nested lists of ``digits`` significant digits of its
    largest value (smaller JSON); non-finite values as 0."""
    a = np.nan_to_num(np.asarray(a, dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    top = float(np.max(np.abs(a))) if a.size else 0.0
    places = digits - 1 - int(np.floor(np.log10(top))) if top > 0 else digits
    return np.round(a, max(places, 0)).tolist()


def png_data_url(rgb8: np.ndarray) -> str:
    """An 8-bit RGB image as a ``data:image/png;base64,...`` URL."""
    stream = mi.MemoryStream()
    mi.Bitmap(np.ascontiguousarray(rgb8), mi.Bitmap.PixelFormat.RGB).write(
        stream, mi.Bitmap.FileFormat.PNG)
    return "data:image/png;base64," + base64.b64encode(bytes(stream.raw_buffer())).decode()


def directional_albedo(bsdf, angles, side: int) -> np.ndarray:
    """E(θ_i) = ∫ eval(wi, wo) dω_o at each angle (degrees), the largest of the
    three channels: the mean sample weight of the BSDF's own importance
    sampling at ``side``² stratified points per angle (cell midpoints; the lobe
    choice by the golden ratio's sequence), every angle in one kernel (a viewer
    per block of lanes). A uniform quadrature would need 10⁶ directions per
    angle to resolve a lobe of α = 0.05 to 1 %; a sampler checked by χ² tests
    resolves it with a few thousand."""
    n = side * side
    lane = dr.arange(mi.UInt32, len(angles) * n)
    block, cell = lane // n, lane % n
    t = np.radians(np.asarray(angles, dtype=np.float64))
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(dr.gather(mi.Float, mi.Float(list(np.sin(t))), block), 0.0,
                        dr.gather(mi.Float, mi.Float(list(np.cos(t))), block))
    si.uv = mi.Point2f(0.5, 0.5)
    u = mi.Point2f((mi.Float(cell // side) + 0.5) / side, (mi.Float(cell % side) + 0.5) / side)
    pick = mi.Float(cell) * GOLDEN + 0.5
    _, weight = bsdf.sample(mi.BSDFContext(), si, pick - dr.floor(pick), u)
    e = np.array(dr.block_sum(mi.Color3d(weight), n)) / n          # (3, angles)
    return e.reshape(3, len(angles)).max(axis=0)


def pass_spp(index: int) -> int:
    return PASSES[index] if index < len(PASSES) else PASSES[-1]


class Entry:
    """One loaded configuration: its BSDF, parameters and preview scenes."""

    def __init__(self, bsdf, keys: dict[str, str]):
        self.bsdf = bsdf
        self.params = mi.traverse(bsdf)
        self.keys = keys                    # parameter name -> traverse key
        self.values: dict | None = None     # the values set last
        self.scenes: dict[int, object] = {}

    def apply(self, material: dict) -> None:
        """Set the material's parameter values, if they are not set already,
        with the plugin's checks at ``params.update()`` (MaterialError; the
        values before stay). The first call sets every one (each then counts
        as changed for the plugin, which keeps its lobes traced: one kernel
        for every value)."""
        values = {k: v for k, v in material.items() if k in self.keys}
        if values == self.values:
            return
        before, self.values = self.values, None          # unknown until the update succeeded
        try:
            self._update(values, before)
        except backend.MaterialError:
            if before is not None:
                self._update(before, None)
                self.values = before
            raise
        self.values = values

    def _update(self, values: dict, before: dict | None) -> None:
        for name, value in values.items():
            if before is None or before.get(name) != value:
                key = self.keys[name]
                self.params[key] = dr.opaque(type(self.params[key]), value)
        with backend.checked():
            self.params.update()

    def scene(self, res: int, mode: str, env, light: float):
        if res not in self.scenes:
            self.scenes[res] = mi.load_dict(preview.scene_dict(
                self.bsdf, res, backend.integrator(mode), env, light))
        return self.scenes[res]


class Explorer:
    """The models, the loaded configurations and every computation of the page."""

    def __init__(self):
        self.variant = backend.setup()
        self.models: dict[str, dict] = {}
        self.keys: dict[tuple, dict[str, str]] = {}    # configuration -> parameter -> key
        for model in backend.course_models() + builtin_models():
            keys = self._probe(model, {})
            for p in model["params"]:
                p["control"] = p["name"] in keys or model["source"] == "mitsuba"
            if model["source"] == "mi_brdfs":
                self._when(model, keys)
            self.models[model["name"]] = model
        self.env = mi.Bitmap(preview.environment())
        self.entries: OrderedDict[tuple, Entry] = OrderedDict()
        self.walks: OrderedDict[tuple, list] = OrderedDict()

    @staticmethod
    def _options(model: dict, material: dict) -> dict:
        """The options ``material`` (complete or partial) gives its model,
        but ``mode``: with the model, the configuration whose parameters the
        page controls."""
        return {o["name"]: material[o["name"]] for o in model["options"]
                if o["name"] != "mode" and o["name"] in material}

    def _probe(self, model: dict, options: dict) -> dict[str, str] | None:
        """Which parameters the configuration of ``model`` with ``options``
        (the others at their defaults) exposes in ``mi.traverse``, under which
        key: a course plugin loaded with its defaults, a built-in with every
        declared parameter given; None if the plugin refuses the configuration.
        Kept per configuration."""
        config = (model["name"], *((o["name"], options.get(o["name"], o["default"]))
                                   for o in model["options"] if o["name"] != "mode"))
        if config in self.keys:
            return self.keys[config]
        given = {} if model["source"] == "mi_brdfs" else {
            p["name"]: ([p["default"]] * 3 if p["kind"] == "spectrum" else p["default"])
            for p in model["params"]}
        try:
            probe = backend.load(load_dict({model["name"]: model},
                                           {"type": model["name"], "mode": "hdr", **options,
                                            **given}))
        except backend.MaterialError:
            return None
        declared = {p["name"] for p in model["params"]}
        keys = {key.split(".")[0]: key for key in mi.traverse(probe).keys()}
        self.keys[config] = keys = {name: key for name, key in keys.items() if name in declared}
        return keys

    def _when(self, model: dict, default_keys: dict[str, str]) -> None:
        """``when`` of each parameter that a choice of an option exposes and
        the defaults do not (``cook_torrance``'s ``eta`` and ``kappa`` with
        ``fresnel="conductor"``): option -> the choices that expose it. The
        page shows such a parameter's control while one of them is chosen."""
        shown: dict[str, dict[str, list]] = {}
        for o in model["options"]:
            if o["type"] != "string" or o["name"] == "mode":
                continue
            for choice in o["choices"]:
                keys = self._probe(model, {o["name"]: choice}) if choice != o["default"] else None
                for name in (keys or {}).keys() - default_keys.keys():
                    shown.setdefault(name, {}).setdefault(o["name"], []).append(choice)
        for p in model["params"]:
            if p["name"] in shown:
                p["when"] = shown[p["name"]]

    def public_models(self) -> list[dict]:
        """The declarations as ``GET /api/models`` returns them."""
        return list(self.models.values())

    # --- configurations ---------------------------------------------------------
    def prepare(self, raw) -> tuple[dict, Entry]:
        """The complete material and its loaded configuration, the values set
        (the plugin's checks: MaterialError, one line)."""
        material = complete(self.models, raw)
        model = self.models[material["type"]]
        keys = self._probe(model, self._options(model, material)) or {}
        key = tuple((k, json_key(v)) for k, v in material.items() if k not in keys)
        entry = self.entries.get(key)
        if entry is None:
            entry = Entry(backend.load(load_dict(self.models, material)), keys)
            self.entries[key] = entry
            while len(self.entries) > CACHE:
                self.entries.popitem(last=False)
        else:
            self.entries.move_to_end(key)
        entry.apply(material)
        return material, entry

    def white(self, material: dict) -> list[tuple[str, dict]]:
        """(label, material) of the white furnace's configurations: every
        colour 1; a compensable model in hdr mode with and without compensation."""
        model = self.models[material["type"]]
        white = {**material, **{p["name"]: [1.0, 1.0, 1.0] for p in model["params"]
                                if p["role"] == "colour" and p["name"] in material}}
        if not (model["compensable"] and material["mode"] == "hdr"):
            return [("white", white)]
        ec = backend.ENERGY_COMPENSATION
        return [("white, not compensated", {**white, ec: False}),
                ("white, energy compensated", {**white, ec: True})]

    # --- the plots -------------------------------------------------------------
    def plots(self, raw, theta_i: float) -> dict:
        """The lobe in the plane of incidence (per channel), over the
        hemisphere (channel mean), the directional albedo of the material and
        of its white configurations (:func:`directional_albedo`), and the
        white furnace's value: the hemispherical albedo 2∫E(μ)μ dμ of the
        white configuration the material is (its own compensation setting)."""
        if not (isinstance(theta_i, (int, float)) and not isinstance(theta_i, bool)
                and 0.0 <= theta_i <= 89.0):
            raise RequestError(f"theta_i = {theta_i!r} is invalid; valid: a number in [0, 89]")
        material, entry = self.prepare(raw)
        theta, rgb = backend.lobe_in_plane(entry.bsdf, theta_i, LOBE_POINTS)
        t, p, v = backend.lobe_over_hemisphere(entry.bsdf, theta_i, HEMISPHERE_N)
        curves = [{"label": "this material", "E": rounded(
            directional_albedo(entry.bsdf, ALBEDO_ANGLES, ALBEDO_SIDE))}]
        furnace = None
        for label, white in self.white(material):
            _, twin = self.prepare(white)
            e = directional_albedo(twin.bsdf, ALBEDO_ANGLES, ALBEDO_SIDE)
            curves.append({"label": label, "E": rounded(e)})
            if white.get(backend.ENERGY_COMPENSATION) == material.get(backend.ENERGY_COMPENSATION):
                value = hemispherical(e)
                furnace = value and {"label": label, **value}
        return {"material": material, "theta_i": theta_i,
                "lobe": {"theta": rounded(theta), "rgb": rounded(rgb.T)},
                "lobe3d": {"x": rounded(v * np.sin(t) * np.cos(p)),
                           "y": rounded(v * np.sin(t) * np.sin(p)),
                           "z": rounded(v * np.cos(t))},
                "albedo": {"theta": list(ALBEDO_ANGLES), "curves": curves},
                "furnace": furnace}

    # --- the preview ---------------------------------------------------------
    def frames(self, raw, res: int = RESOLUTIONS[0], spp: int = MAX_SPP):
        """A generator of ever better preview images: one pass per step (the
        worker interleaves other work and drops a superseded render between
        passes), each image the mean of every pass so far."""
        if res not in RESOLUTIONS:
            raise RequestError(f"res = {res!r} is invalid; valid: one of "
                               + ", ".join(map(str, RESOLUTIONS)))
        if not (isinstance(spp, int) and not isinstance(spp, bool) and 1 <= spp <= MAX_SPP):
            raise RequestError(f"spp = {spp!r} is invalid; valid: an integer in [1, {MAX_SPP}]")
        material, entry, scene = self.preview(raw, res)
        return self._passes(material, entry, scene, res, spp)

    def preview(self, raw, res: int) -> tuple[dict, Entry, object]:
        """The material, its configuration and its preview scene at ``res``."""
        material, entry = self.prepare(raw)
        course = self.models[material["type"]]["source"] == "mi_brdfs"
        light = backend.light_scale(material["mode"]) if course else 1.0   # built-ins: physical
        return material, entry, entry.scene(res, material["mode"], self.env, light)

    def _passes(self, material, entry, scene, res, spp):
        total, done, index = None, 0, 0
        while done < spp:
            entry.apply(material)      # another request may have set other values meanwhile
            n = min(pass_spp(index), spp - done)
            image = np.array(mi.render(scene, spp=n, seed=index), dtype=np.float64)[..., :3]
            total = image * n if total is None else total + image * n
            done, index = done + n, index + 1
            rgb8 = backend.to_srgb8(total / done, material["mode"])
            yield {"image": png_data_url(rgb8), "spp": done, "res": res, "final": done >= spp}

    # --- the random walk (NumPy only: any thread) ---------------------------------
    def walk(self, raw) -> dict:
        """The white furnace by the random walk on the microsurface, for the
        configurations it is the truth of (else ``E`` is None)."""
        material = complete(self.models, raw)
        if not backend.walk_applies(material):
            return {"theta": list(ALBEDO_ANGLES), "E": None}
        key = tuple(json_key(material[k]) for k in ("distribution", "alpha", "f0", "k"))
        if key not in self.walks:
            self.walks[key] = rounded(backend.walk_albedo(material, ALBEDO_ANGLES, WALK_PATHS))
            while len(self.walks) > WALK_CACHE:
                self.walks.popitem(last=False)
        return {"theta": list(ALBEDO_ANGLES), "E": self.walks[key], "paths": WALK_PATHS}

    # --- the fit and the strings -------------------------------------------------
    def fit(self, left, right) -> dict:
        """The left course model's parameters fitted to the right material."""
        model = complete(self.models, left)
        target = complete(self.models, right)
        if self.models[model["type"]]["source"] != "mi_brdfs":
            raise RequestError(f"fit: the fitted model must be a course model, not "
                               f"{model['type']}")
        options = tuple(o["name"] for o in self.models[model["type"]]["options"])
        fitted, error = backend.fit(model, load_dict(self.models, target), options)
        result = {**model, **{k: fitted[k] for k in parameter_names(self.models, model)
                              if k in fitted}}
        return {"material": complete(self.models, result), "brdf_error": error}

    def strings(self, raw) -> dict:
        material = complete(self.models, raw)
        return {"material": material, "xml": xml(self.models, material),
                "python": python(self.models, material)}


def json_key(value):
    """A value as part of a dictionary key (lists become tuples)."""
    return tuple(value) if isinstance(value, list) else value


def hemispherical(e: np.ndarray) -> dict | None:
    """The hemispherical albedo 2∫E(μ)μ dμ from E at ALBEDO_ANGLES (trapezoid
    rule in μ, E held constant from the last angle to the horizon), and E's
    largest value and its angle; None unless E is finite."""
    if not np.isfinite(e).all():
        return None
    mu = np.cos(np.radians(ALBEDO_ANGLES))[::-1]
    f = (2.0 * e * np.cos(np.radians(ALBEDO_ANGLES)))[::-1]
    value = float(np.trapezoid(f, mu) + f[0] * mu[0] / 2.0)
    i = int(np.argmax(e))
    return {"mean": value, "max": float(e[i]), "at": ALBEDO_ANGLES[i]}
