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
from ...bsdfs import BY_NAME, cases
from ..analysis import eval_at_viewer
from .metric import pairs
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
    normal, grazing = (model.effective(p, math.cos(math.radians(a))) for a in (0.0, GRAZING_DEG))
    return {"diffuse": normal.diffuse, "specular_0": normal.specular,
            "specular_85": grazing.specular, "notes": list(normal.notes)}


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
    """:func:`features` of a :class:`.targets.Target` on the settings' metric pairs."""
    bsdf = target.load()
    try:
        return features(bsdf, pairs(settings.metric, settings.viewers, settings.uniform,
                                    settings.lobe))
    finally:
        del bsdf


def describe(found: dict) -> list[str]:
    """Sentences on the features present (empty: none found)."""
    out = []
    w = found["whitening"]
    if w["present"]:
        out.append(f"its specular colour turns white towards grazing incidence (chroma "
                   f"{w['chroma_0']:.2f} at 0°, {w['chroma_80']:.2f} at 80°): a conductor's "
                   "spectral Fresnel; no course model has it (Schlick's scalar f0 times a "
                   "colour keeps that colour at every angle)")
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
                    "directions; no course model has a coating over its diffuse layer",
}
KNOWN["plastic"] = KNOWN["roughplastic"]


def known_reasons(plugin: str) -> list[str]:
    """What a target of this Mitsuba plugin is known to have that no course
    model has (empty if nothing is known)."""
    return [KNOWN[plugin]] if plugin in KNOWN else []


def extended_models(found: dict) -> list:
    """The course models' extended configurations worth fitting for the
    features found: for an anisotropic target, those the models declare
    (their cases' ``anisotropic``: ward and cook_torrance with alpha_u and
    alpha_v)."""
    if not found["anisotropy"]["present"]:
        return []
    return [Model(name, plugin, tuple(props.items()))
            for plugin, declared in cases.ALL.items() for name, props in declared.anisotropic]
