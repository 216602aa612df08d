"""The course models a fit tries, and how each parameter is searched.

**Models.** Every plugin of :data:`mi_brdfs.bsdfs.PLUGINS`, in hdr mode; a
plugin with options that change the model itself (those its declaration marks
``model``: the D and G of ``cook_torrance``, the specular cosine of ``toon``)
gives one model per combination, and a ``compensable`` plugin each of those
with and without ``energy_compensation`` (the name gets ``+ec``). Options that
change only how a model is computed or sampled (``sampling``,
``sample_visible``, Ward's ``formula``, Oren-Nayar's ``method``) keep their
defaults. Names:
``lambert``, ``phong+ec``, ``cook_torrance/ggx/smith``, ... (:func:`names`).

**Rungs** (:func:`rungs`): ``cook_torrance`` with Smith's G under GGX and
Beckmann, one option away from the lecture's forms (issue 35), the steps
from the lecture's approximation to the physics it stands for:

- ``cook_torrance/<D>/smith/f82``: Hoffman's F82-tint (``f0`` and
  ``f82_tint`` free, both colours, as Hoffman's metal has them;
  ``specular_reflectance`` held at 1: the Fresnel carries the colour);
- ``cook_torrance/<D>/smith/conductor``: the exact conductor Fresnel, ``eta``
  in [0, 8] and ``kappa`` in [0, 10] per channel (every material of
  Mitsuba's ``data/ior`` lies inside: η ≤ 7.6, κ ≤ 9.3 in RGB), free and not
  seeded from a ``roughconductor`` target's own data (a target given as XML
  or a ``principled`` has none), but the scan adds every measured metal of
  Mitsuba at the best candidate's roughness as a start (:func:`metal_starts`:
  a target that is one of them starts from its own indices),
  ``specular_reflectance`` held at 1 (the Fresnel carries the colour);
- both conductor rungs hold ``k`` at 0, as ``roughconductor``: a metal has no
  diffuse lobe, and a negligible one (k·m_D ~ 1e-8, which the objective does
  not see) lights pixels that are black in a conductor's render, which
  HDR-FLIP, whose exposures reach far above such a render's bright pixels,
  counts as errors;
- ``cook_torrance/<D>/smith/plastic``: ``roughplastic``'s base under the exact
  dielectric Fresnel, ``int_ior`` in [1, 3] (``ext_ior`` held at air's: only
  the ratio counts), the diffuse and specular colours free;
  ``.../plastic/nonlinear`` with ``nonlinear``.

They are not in the default selection of every target (:func:`all_models`):
the fit adds them to the targets they are for
(:func:`.effective.extended_models`: the conductor rungs to conductors, the
plastic rung to plastics), and ``--models`` names them.

**Parameters.** A model's free parameters are those its plugin exposes in
``mi.traverse`` when loaded with its defaults (so optional alternatives stay
out: Ward's anisotropic ``alpha_u``/``alpha_v``, toon's ramps), each with its
declaration in the plugin's ``PARAMS`` (range, kind, role); a colour
parameter is fitted per channel, except those :data:`ONE_NUMBER` names (the
lecture's ``f0``: a number, unless a model fits it as a colour, the F82
rung). Each is searched
over [lo, hi] of its declaration, with ``hi`` = the declared upper end, or
``upper``, or 1 for an unbounded colour (white); exponents stop at
``EXPONENT_MAX``. The optimiser moves an unconstrained coordinate u per
parameter (per channel of a colour), and the parameter is the logistic
x = lo + (hi - lo)·σ(u): a smooth bijection from the real line onto the open
range, so no gradient is ever cut off (a clip has zero gradient at its bound:
a parameter that touched it stayed there). Near lo, x - lo ≈ (hi - lo)·e^u,
so a roughness or an exponent far below its upper end moves on a log scale.
u is kept within ±``U_MAX`` (σ = 6·10⁻⁶ from either end).

Where the search starts (:func:`.optimise.candidates`): the plugin's
defaults; every shape and weight parameter at the low end, then at the high
end (u = ±``U_START``); then a Latin hypercube across the ranges
(:meth:`Free.spread`: on a log scale for roughnesses and exponents, evenly in
angle for cosines).
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

import drjit as dr

from ...bsdfs import PLUGINS
EXPONENT_MAX = 1e6        # exponents are searched up to here (a mirror-like lobe)
U_MAX = 30.0              # coordinates stay within ±U_MAX (σ(-30) = 1e-13; σ(u) rounds to 1 in float32 from u = 17)
U_START = 6.0             # a start "at a bound" is u = ±6 (0.25 % of the range inside it)
ROUGHNESS_START_FLOOR = 0.01   # log-scale starts: roughnesses over [0.01 hi, hi],
EXPONENT_START_FLOOR = 1.0     # exponents over [1, EXPONENT_MAX]
EC = "+ec"


@dataclass(frozen=True)
class Model:
    """One model: a plugin with fixed options."""
    name: str
    plugin: str
    options: tuple          # (name, value) pairs, energy_compensation included
    held: tuple = ()        # (name, value) not fitted: given as value, or not given (None)
    bounds: tuple = ()      # (name, lo, hi): a search range other than the declaration's
    curved: tuple = ()      # colour parameters eval is not linear in (scanned, not solved)
    colours: tuple = ()     # parameters of ONE_NUMBER this model fits per channel
    metals: bool = False    # the scan also starts from Mitsuba's measured metals (:func:`metal_starts`)

    def properties(self) -> dict:
        return {"type": self.plugin, "mode": "hdr", **dict(self.options),
                **{k: v for k, v in self.held if v is not None}}


def all_models() -> list[Model]:
    out = []
    for cls in PLUGINS:
        variants = [o for o in cls.OPTIONS if o.model]       # each choice another model
        names = tuple(o.name for o in variants)
        for combo in itertools.product(*(o.choices for o in variants)):
            base = "/".join((cls.name, *combo))
            opts = tuple(zip(names, combo))
            for ec in ((False, True) if cls.compensable else (False,)):
                extra = (("energy_compensation", True),) if ec else ()
                out.append(Model(base + (EC if ec else ""), cls.name, opts + extra))
    return out


RUNG_DISTRIBUTIONS = ("ggx", "beckmann")
ETA_RANGE, KAPPA_RANGE, IOR_RANGE = (0.0, 8.0), (0.0, 10.0), (1.0, 3.0)
CONDUCTOR_RUNGS, PLASTIC_RUNG = ("f82", "conductor"), "plastic"
METAL = (("k", 0.0), ("diffuse_reflectance", None))     # the conductor rungs: no diffuse lobe


def rung(distribution: str, form: str, nonlinear: bool = False) -> Model:
    """One rung (module docstring): ``form`` "f82", "conductor" or "plastic"."""
    base = f"cook_torrance/{distribution}/smith/{form}"
    opts = (("distribution", distribution), ("geometry", "smith"))
    if form == PLASTIC_RUNG:
        return Model(base + ("/nonlinear" if nonlinear else ""), "cook_torrance",
                     opts + (("fresnel", "dielectric"), ("base", "plastic"),
                             ("nonlinear", bool(nonlinear))),
                     held=(("k", None), ("f0", None), ("ext_ior", None)),
                     bounds=(("int_ior",) + IOR_RANGE,),
                     curved=("diffuse_reflectance",) if nonlinear else ())
    if form == "conductor":
        return Model(base, "cook_torrance", opts + (("fresnel", "conductor"),),
                     held=(("f0", None), ("specular_reflectance", 1.0)) + METAL,
                     bounds=(("eta",) + ETA_RANGE, ("kappa",) + KAPPA_RANGE),
                     curved=("eta", "kappa"), metals=True)
    if form != "f82":
        raise ValueError(f"rung {form!r} is unknown; valid: f82, conductor, plastic")
    return Model(base, "cook_torrance", opts + (("fresnel", "f82"),),
                 held=(("specular_reflectance", 1.0),) + METAL,
                 curved=("f82_tint", "f0"), colours=("f0",))


def metal_starts(alpha: float) -> list[dict]:
    """More starts of the conductor rung (:func:`.optimise.fit_model`): (η, κ)
    of every metal of Mitsuba's ``data/ior`` in the active variant's colours,
    at roughness ``alpha`` (the best scanned candidate's). A target that is
    one of these metals is then started from its own indices; the descent
    still finds the roughness and refines the indices. The two indices trade against each other along
    a valley of nearly equal reflectance (gold's red channel: η 0.14, κ 4.0
    and η 0.8, κ 10 differ only towards grazing), and from a grey start the
    descent can end on the far side of it at a bound."""
    import mitsuba as mi
    from ...bsdfs import cook_torrance as ct
    key = mi.variant()
    if key not in _METALS:
        si = dr.zeros(mi.SurfaceInteraction3f)
        found = []
        level = mi.log_level()
        # Mitsuba warns when a metal's spectra reduce to a colour out of its gamut (it
        # clamps it): about metals the user did not name, so not shown (the clamp stays)
        mi.set_log_level(mi.LogLevel.Error)
        try:
            textures = {name: ct.material_textures(name) for name in ct.materials()}
        finally:
            mi.set_log_level(level)
        for name, pair in textures.items():
            eta, kappa = (np.array(t.eval(si), dtype=np.float64).ravel() for t in pair)
            if len(eta) == 3 and np.isfinite(eta).all() and np.isfinite(kappa).all():
                found.append({"eta": [float(min(max(v, ETA_RANGE[0]), ETA_RANGE[1])) for v in eta],
                              "kappa": [float(min(max(v, KAPPA_RANGE[0]), KAPPA_RANGE[1]))
                                        for v in kappa]})
        _METALS[key] = found
    return [{**m, "alpha": alpha} for m in _METALS[key]]


_METALS: dict = {}


def rungs(conductor: bool = True, plastic: bool = True, nonlinear: bool = False) -> list[Model]:
    """The rungs for a conductor-like target, a plastic-like one, or both."""
    forms = (CONDUCTOR_RUNGS if conductor else ()) + ((PLASTIC_RUNG,) if plastic else ())
    return [rung(d, f, nonlinear) for f in forms for d in RUNG_DISTRIBUTIONS]


def known_models() -> list[Model]:
    """Every model a name may ask for: :func:`all_models`, each rung placed
    after the Schlick model of its distribution (``cook_torrance/<D>/smith+ec``),
    the plastic rung with and without ``nonlinear``."""
    extra = rungs() + [rung(d, PLASTIC_RUNG, True) for d in RUNG_DISTRIBUTIONS]
    out = []
    for m in all_models():
        out.append(m)
        for d in RUNG_DISTRIBUTIONS:
            if m.name == f"cook_torrance/{d}/smith{EC}":
                out += [r for r in extra if r.name.startswith(f"cook_torrance/{d}/smith/")]
    return out


def names() -> list[str]:
    return [m.name for m in known_models()]


def select(wanted: list[str] | None) -> list[Model]:
    """The models named: a model's name (a rung's too), or a plugin's name
    that is no model's (``cook_torrance``, ``toon``: all its models, the
    rungs included); ValueError naming the unknown one and the valid names.
    None: :func:`all_models` (the rungs are added per target)."""
    if not wanted:
        return all_models()
    models = known_models()
    chosen: list[Model] = []
    for w in wanted:
        found = [m for m in models if m.name == w] or [m for m in models if m.plugin == w]
        if not found:
            several = sorted({m.plugin for m in models if m.name != m.plugin})
            raise ValueError(f"unknown model {w!r}; valid: "
                             f"{', '.join(m.name for m in models)}, or {', '.join(several)} "
                             "(all their models)")
        chosen += [m for m in found if m not in chosen]
    return chosen


# ----------------------------------------------------------------------------
#  Free parameters: a smooth bijection from the real line onto each range
# ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Free:
    """A fitted parameter: its traverse key and range. The optimiser moves an
    unconstrained coordinate u; the parameter is x = lo + (hi - lo)·σ(u)."""
    name: str
    key: str                 # mi.traverse key ("alpha.value", "k")
    colour: bool             # three channels (a "spectrum" parameter)
    lo: float
    hi: float
    log_start: bool = False  # starts spread on a log scale (roughnesses, exponents)
    linear: bool = True      # a colour eval is linear in (solved by least squares; else scanned)

    @property
    def scanned(self) -> bool:
        """Searched by the scan's candidates (a shape, or a colour eval is not linear in)."""
        return not self.colour or not self.linear

    def value(self, u):
        """Coordinate(s) u -> parameter value (Dr.Jit or NumPy)."""
        return self.lo + (self.hi - self.lo) * logistic(u)

    def coordinate(self, x, edge: float = U_MAX) -> float:
        """Parameter value -> coordinate, kept within ±edge (a value at a
        bound maps to the edge: u = ±∞ is no start)."""
        t = (float(x) - self.lo) / (self.hi - self.lo)
        t = min(max(t, 1e-300), 1.0 - 1e-16)
        return float(min(max(math.log(t) - math.log1p(-t), -edge), edge))

    def spread(self, s: float) -> float:
        """A start's value at s in [0, 1] across the range: on a log scale for
        a roughness or an exponent (a lobe's width spans decades), evenly in
        angle for a cosine (a range [-1, 1]: toon's thresholds), else linear."""
        if self.lo == -1.0 and self.hi == 1.0 and not self.colour:
            return math.cos(math.pi * (1.0 - s))        # a cosine: evenly in angle
        if not self.log_start:
            return self.lo + (self.hi - self.lo) * s
        floor = EXPONENT_START_FLOOR if self.hi > 10.0 else ROUGHNESS_START_FLOOR * self.hi
        return self.lo + floor * (self.hi / floor) ** s


def logistic(u):
    """σ(u) = 1/(1 + e^-u), NumPy (float64) or Dr.Jit. With |u| <= U_MAX its
    value and gradient are finite, and relative precision holds near 0 (where
    1 + tanh(u/2) would cancel in float32: an exponent of 10 in [0, 10⁶])."""
    if isinstance(u, (float, int, np.ndarray, np.floating)):
        return 1.0 / (1.0 + np.exp(-np.asarray(u, dtype=np.float64)))
    return dr.rcp(1.0 + dr.exp(-u))


# Colour parameters fitted as one number (a plugin loaded with its defaults
# holds them as a ``uniform``, whose traverse key takes one): cook_torrance's
# ``f0``, a number in the lecture; as a colour beside the colour m_S it would
# trade against it channel by channel (m_S·F0 nearly one product per channel).
ONE_NUMBER = {"cook_torrance": ("f0",)}


def free_parameters(plugin_cls, traversed: list[str], model: Model | None = None) -> list[Free]:
    """The Free parameters of a plugin instance whose traverse keys are
    ``traversed``; a ``model``'s held parameters left out, its bounds and
    curved colours applied; :data:`ONE_NUMBER` fitted as one number unless
    the model names them in ``colours``."""
    declared = {p.name: p for p in plugin_cls.PARAMS}
    one = set(ONE_NUMBER.get(plugin_cls.name, ())) - set(model.colours if model else ())
    held = {k for k, _ in model.held} if model else set()
    bounds = {b[0]: b[1:] for b in model.bounds} if model else {}
    curved = set(model.curved) if model else set()
    out = []
    for key in traversed:
        name = key.split(".")[0]
        p = declared.get(name)
        if p is None or name in held:
            continue
        lo = p.lo if p.lo is not None else -1.0
        hi = p.probe_hi()
        log_start = p.role == "shape" and lo == 0.0
        if log_start and hi > 10.0:
            hi = min(hi, EXPONENT_MAX)
        lo, hi = bounds.get(name, (lo, hi))
        log_start = log_start and lo == 0.0
        out.append(Free(name, key, p.kind == "spectrum" and name not in one, lo, hi, log_start,
                        linear=name not in curved))
    return out


def split(free: list[Free], u: np.ndarray) -> dict:
    """A flat coordinate vector -> {name: coordinate (float or 3-tuple)}."""
    out, i = {}, 0
    for f in free:
        n = 3 if f.colour else 1
        out[f.name] = tuple(float(c) for c in u[i:i + n]) if f.colour else float(u[i])
        i += n
    return out


def values(free: list[Free], u: np.ndarray) -> dict:
    """A flat coordinate vector -> {name: parameter value (float or list of 3)}."""
    coords = split(free, u)
    return {f.name: ([float(v) for v in f.value(np.array(coords[f.name]))] if f.colour
                     else float(f.value(coords[f.name]))) for f in free}


# ----------------------------------------------------------------------------
#  Properties and XML
# ----------------------------------------------------------------------------

def load_dict(properties: dict) -> dict:
    """Fit parameters (colours as lists) -> a ``mi.load_dict`` dictionary."""
    return {k: ({"type": "rgb", "value": list(v)} if isinstance(v, (list, tuple)) else v)
            for k, v in properties.items()}


def xml(properties: dict) -> str:
    """A ``<bsdf>`` element that loads as ``properties`` (full float precision)."""
    lines = [f'<bsdf type="{properties["type"]}" version="3.0.0">']
    for k, v in properties.items():
        if k == "type":
            continue
        if isinstance(v, bool):
            lines.append(f'    <boolean name="{k}" value="{"true" if v else "false"}"/>')
        elif isinstance(v, str):
            lines.append(f'    <string name="{k}" value="{v}"/>')
        elif isinstance(v, (list, tuple)):
            lines.append(f'    <rgb name="{k}" value="{", ".join(repr(float(c)) for c in v)}"/>')
        else:
            lines.append(f'    <float name="{k}" value="{float(v)!r}"/>')
    lines.append("</bsdf>")
    return "\n".join(lines) + "\n"
