"""What a fitted material means, beyond its raw parameters.

:func:`parameters`: the colours that matter given the weights, as each
model declares them (its ``effective``) — a ``cook_torrance`` shows k·m_D
(its diffuse colour) and (1 - k)·m_S·F(θ) (its specular colour, Schlick's F
at normal and at 85° incidence), not m_D when k = 0; phong, blinn and ward
have no Fresnel, so their specular colour is m_S at every angle.

:func:`albedo`: the directional albedo (the share of light from one
direction that the surface reflects, per channel) at 0°, 60° and 85°, by the
BSDF's own sampling (``sample``'s weight is f·cos θ / pdf); above 1 a
material creates light.

:func:`features`: the physical features of a target that none of the course
models has, measured on the target itself — its mirror colour turning white
towards grazing incidence (a conductor's spectral Fresnel: Schlick's scalar
F0 times a colour keeps the colour; the specular colour is the mirror
direction's less the body's, so that a coloured diffuse body under a white
highlight is not mistaken for it), and anisotropy (the highlight changes
when both directions turn about the normal); an anisotropic target is then
fitted once more by ward with ``alpha_u`` and ``alpha_v``, the project's one
anisotropic configuration (:func:`extended_models`).
"""
from __future__ import annotations

import math

import numpy as np

import drjit as dr
import mitsuba as mi

from ..._jit import from_numpy
from ...bsdfs import BY_NAME, cases, fresnel
from ..analysis import eval_at_viewer
from .metric import pairs
from . import models as M
from .models import Model
from .optimise import eval_pairs

ALBEDO_ANGLES = (0.0, 60.0, 85.0)
ALBEDO_SAMPLES = 1 << 16
GRAZING_DEG = 85.0
WHITENING_DEG = (0.0, 80.0)      # the mirror colour compared at these incidences
ANISOTROPY_MIN = 0.02            # relative change under a 90° turn that counts as anisotropic
WHITENING_MIN = 0.05             # chroma lost between 0° and 80° that counts as whitening
CHROMA_MIN = 0.1                 # a specular colour this close to grey cannot whiten
BODY_DEG = 30.0                  # the body colour is read from a light 30° off the normal, viewer's side


def parameters(plugin: str, p: dict) -> dict:
    """The effective colours of fitted parameters ``p`` of ``plugin``, as its
    model declares them (:meth:`mi_brdfs.bsdfs.base.BRDF.effective`):
    ``diffuse`` (or None where no diffuse lobe shows), ``specular_0`` and
    ``specular_85`` (the specular colour at normal and 85° incidence), and
    ``notes`` on parameters that do not matter."""
    model = BY_NAME[plugin]
    if plugin == "cook_torrance" and (p.get("fresnel", "schlick") != "schlick"
                                      or p.get("base", "lambert") != "lambert"):
        return rung_parameters(p)
    normal, grazing = (model.effective(p, math.cos(math.radians(a))) for a in (0.0, GRAZING_DEG))
    return {"diffuse": normal.diffuse, "specular_0": normal.specular,
            "specular_85": grazing.specular, "notes": list(normal.notes)}


def _channels(value) -> list[float]:
    return [float(c) for c in value] if isinstance(value, (list, tuple)) else [float(value)] * 3


def rung_fresnel(p: dict, cos_theta: float) -> list[float]:
    """F per channel of a ``cook_torrance`` rung's fitted parameters at
    cos θ, by the plugin's own Fresnel forms (:mod:`mi_brdfs.bsdfs.fresnel`)."""
    form, c = p.get("fresnel", "schlick"), float(cos_theta)
    if form == "conductor":
        value = fresnel.conductor(mi.Float(_channels(p["eta"])), mi.Float(_channels(p["kappa"])), c)
    elif form == "f82":
        value = fresnel.f82(mi.Float(_channels(p.get("f0", 0.04))),
                            mi.Float(_channels(p.get("f82_tint", 1.0))), c)
    elif form == "dielectric":
        eta = float(p.get("int_ior", 1.49)) / float(p.get("ext_ior", 1.000277))
        value = fresnel.dielectric(mi.Float([eta] * 3), c)
    else:
        value = fresnel.schlick(mi.Float(_channels(p.get("f0", 0.04))), c)
    return [float(v) for v in np.array(value, dtype=np.float64).ravel()]


def rung_parameters(p: dict) -> dict:
    """:func:`parameters` of a ``cook_torrance`` with another Fresnel form or
    base: the specular colour m_S·F(θ) (times 1 - k on the Lambert base); the
    plastic base's diffuse colour is m_D, seen through the interface."""
    plastic = p.get("base", "lambert") == "plastic"
    k = 0.0 if plastic else float(p.get("k", 0.5))
    m_s = _channels(p.get("specular_reflectance", 1.0))
    spec = {a: [(1.0 - k) * s * f for s, f in zip(m_s, rung_fresnel(p, math.cos(math.radians(a))))]
            for a in (0.0, GRAZING_DEG)}
    notes = []
    if plastic:
        notes.append("base plastic: diffuse_reflectance is the substrate's, seen through "
                     "the dielectric interface")
    elif k < 1e-3:
        notes.append(f"k = {k:.2g}: diffuse_reflectance has no effect")
    diffuse = _channels(p.get("diffuse_reflectance", 0.5))
    return {"diffuse": diffuse if plastic else [k * d for d in diffuse],
            "specular_0": spec[0.0], "specular_85": spec[GRAZING_DEG], "notes": notes}


def albedo(bsdf, angles=ALBEDO_ANGLES, samples: int = ALBEDO_SAMPLES, seed: int = 3) -> list:
    """The directional albedo [angle][channel] (the mean of ``sample``'s weights)."""
    rng = np.random.default_rng(seed)
    u1 = from_numpy(mi.Float, rng.random(samples, dtype=np.float32))
    u2 = from_numpy(mi.Point2f, rng.random((2, samples), dtype=np.float32))
    out = []
    for a in angles:
        t = math.radians(a)
        si = dr.zeros(mi.SurfaceInteraction3f, samples)
        si.wi = mi.Vector3f(math.sin(t), 0.0, math.cos(t))
        si.uv = mi.Point2f(0.5, 0.5)
        _, weight = bsdf.sample(mi.BSDFContext(), si, u1, u2)
        w = np.array(weight, dtype=np.float64).reshape(3, -1) if dr.size_v(weight) == 3 else \
            np.repeat(np.array(weight, dtype=np.float64)[None], 3, 0)
        w = np.where(np.isfinite(w), w, 0.0)
        out.append([float(c) for c in w.mean(axis=1)])
    return out


def _at(bsdf, theta_i: float, theta_o: float) -> np.ndarray:
    """eval (RGB) for a viewer at θ_i and a light at θ_o in the plane of
    incidence (θ_o > 0: the mirror side, θ_o < 0: the viewer's side)."""
    t = math.radians(theta_o)
    wo = np.array([[math.sin(t), 0.0, math.cos(t)]])
    return eval_at_viewer(bsdf, theta_i, wo)[0]


def specular_colour(bsdf, theta_deg: float) -> np.ndarray:
    """The specular lobe's own colour at incidence θ: eval at the mirror
    direction less the body's (the eval at a light on the viewer's side,
    BODY_DEG off the normal, scaled by the cosines as a Lambert body is).
    A course model's specular colour is one colour times a scalar F(θ)."""
    body = _at(bsdf, theta_deg, -BODY_DEG) / math.cos(math.radians(BODY_DEG))
    return _at(bsdf, theta_deg, theta_deg) - body * math.cos(math.radians(theta_deg))


def _chroma(rgb: np.ndarray) -> float:
    """How far a colour is from grey: (largest - smallest channel) / mean."""
    m = float(np.mean(rgb))
    return float((np.max(rgb) - np.min(rgb)) / m) if m > 0 else 0.0


def features(target_bsdf, pairs) -> dict:
    """Measured on the target: ``whitening`` (its specular colour's chroma at
    0° and at 80° incidence, :func:`specular_colour`, and the share lost) and
    ``anisotropy`` (the relative change of eval at ``pairs`` when both
    directions turn 90° about the normal)."""
    c0, c80 = (_chroma(specular_colour(target_bsdf, a)) for a in WHITENING_DEG)
    lost = (c0 - c80) / c0 if c0 > 0 else 0.0
    turn = lambda w: np.stack([-w[:, 1], w[:, 0], w[:, 2]], axis=1)
    evals = [eval_pairs(target_bsdf, wi, wo)
             for wi, wo in ((pairs.wi, pairs.wo), (turn(pairs.wi), turn(pairs.wo)))]
    w = pairs.weight[:, None]
    num = float(np.sum(w * (evals[0] - evals[1]) ** 2))
    den = float(np.sum(w * evals[0] ** 2))
    aniso = math.sqrt(num / den) if den > 0 else 0.0
    return {"whitening": {"chroma_0": c0, "chroma_80": c80, "lost": lost,
                          "present": bool(c0 > CHROMA_MIN and lost > WHITENING_MIN)},
            "anisotropy": {"change": aniso, "present": bool(aniso > ANISOTROPY_MIN)}}


def conductor_f0(target) -> list[float] | None:
    """F0 per channel of a conductor target given as a shorthand, or None:
    ((η - 1)² + k²)/((η + 1)² + k²) of a ``roughconductor``'s RGB indices
    of refraction, a metallic ``principled``'s base colour."""
    props = dict(target.props)
    if props.get("type") == "principled" and props.get("metallic", 0.0) >= 1.0:
        return list(props.get("base_color", (0.5, 0.5, 0.5)))
    if props.get("type") != "roughconductor":
        return None
    bsdf = target.load()
    p = mi.traverse(bsdf)
    eta, k = (np.array(p[key], dtype=float).ravel() for key in ("eta.value", "k.value"))
    del bsdf, p
    return [float(v) for v in ((eta - 1) ** 2 + k ** 2) / ((eta + 1) ** 2 + k ** 2)]


def normal_colour(record: dict) -> list[float] | None:
    """A fit's colour at normal incidence: its specular colour at 0° (the
    highlight seen head-on); a model without a specular lobe, its diffuse colour."""
    e = record.get("effective") or {}
    if e.get("specular_0") is None:
        return e.get("diffuse")
    return e["specular_0"]


def target_features(target, settings) -> dict:
    """:func:`features` of a :class:`.targets.Target` on the settings' metric
    pairs, with its ``kind`` (:func:`kind`)."""
    bsdf = target.load()
    try:
        found = features(bsdf, pairs(settings.metric, settings.viewers, settings.uniform,
                                     settings.lobe))
    finally:
        del bsdf
    found["kind"] = kind(target, found)
    return found


CONDUCTORS = ("roughconductor", "conductor")
PLASTICS = ("roughplastic", "plastic")


def target_props(target) -> dict:
    """The target's plugin and its properties as given: a shorthand's, or the
    XML's top ``<bsdf>`` type and its ``<boolean>``/``<float>`` children."""
    if target.xml is None:
        return dict(target.props)
    import re
    found = re.search(r'<bsdf[^>]*type="([^"]+)"', target.xml)
    props = {"type": found.group(1) if found else None}
    for tag, name, value in re.findall(r'<(boolean|float)\s+name="([^"]+)"\s+value="([^"]+)"',
                                       target.xml):
        try:
            props.setdefault(name, value.lower() == "true" if tag == "boolean" else float(value))
        except ValueError:
            pass
    return props


def kind(target, found: dict) -> dict:
    """Which rungs (:func:`.models.rungs`) a target is fitted with:
    ``conductor`` for Mitsuba's conductors, a ``principled`` with any
    ``metallic``, and any target whose specular colour whitens towards grazing
    (:func:`features`); ``plastic`` for Mitsuba's plastics and a
    ``principled`` that is not wholly metallic (a dielectric coat over a
    diffuse body); ``nonlinear`` as a plastic target's own (default false)."""
    props = target_props(target)
    plugin = props.get("type")
    metallic = float(props.get("metallic", 0.0)) if plugin == "principled" else 0.0
    conductor = (plugin in CONDUCTORS or (plugin == "principled" and metallic > 0.0)
                 or found["whitening"]["present"])
    plastic = plugin in PLASTICS or (plugin == "principled" and metallic < 1.0)
    return {"conductor": bool(conductor), "plastic": bool(plastic),
            "nonlinear": bool(plastic and props.get("nonlinear", False) is True)}


def describe(found: dict) -> list[str]:
    """Sentences on the features present (empty: none found)."""
    out = []
    w = found["whitening"]
    if w["present"]:
        out.append(f"its specular colour turns white towards grazing incidence (chroma "
                   f"{w['chroma_0']:.2f} at 0°, {w['chroma_80']:.2f} at 80°): a conductor's "
                   "spectral Fresnel; no model with the lecture's Fresnel has it (Schlick's "
                   "scalar f0 times a colour keeps that colour at every angle); the rungs "
                   "cook_torrance/<D>/smith/conductor and /f82 are fitted for it")
    a = found["anisotropy"]
    if a["present"]:
        extra = [name for name, _ in cases.every("anisotropic")]
        out.append(f"it is anisotropic (eval changes by {a['change']:.2f} when both "
                   "directions turn 90° about the normal); the models with an anisotropic "
                   f"roughness are fitted below as {' and '.join(extra)}")
    return out


KNOWN = {          # plugin: what it has that no course model has, as the fit guide explains it
    "roughplastic": "it is a plastic: light refracted into its substrate scatters inside and "
                    "leaves through the Fresnel-transmitting coating (internal scattering), so "
                    "its diffuse layer is weighted by the coating's transmission at both "
                    "directions; no model with the lecture's k-mix has a coating over its "
                    "diffuse layer (the rung cook_torrance/<D>/smith/plastic is fitted for it)",
}
KNOWN["plastic"] = KNOWN["roughplastic"]


def known_reasons(plugin: str) -> list[str]:
    """What a target of this Mitsuba plugin is known to have that no course
    model has (empty if nothing is known)."""
    return [KNOWN[plugin]] if plugin in KNOWN else []


def extended_models(found: dict, rungs: bool = True) -> list:
    """The course models' extended configurations worth fitting for the
    features found: for an anisotropic target, those the models declare
    (their cases' ``anisotropic``: ward and cook_torrance with alpha_u and
    alpha_v); with ``rungs``, the rungs of its ``kind`` (:func:`kind`): F82
    and the exact conductor Fresnel for a conductor, the plastic base for a
    plastic (:func:`.models.rungs`, under GGX and Beckmann: 4 more models
    for a conductor, 2 for a plastic)."""
    out = []
    if found["anisotropy"]["present"]:
        out += [Model(name, plugin, tuple(props.items()))
                for plugin, declared in cases.ALL.items() for name, props in declared.anisotropic]
    k = found.get("kind")
    if rungs and k and (k["conductor"] or k["plastic"]):
        out += M.rungs(k["conductor"], k["plastic"], k["nonlinear"])
    return out
