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

**Parameters.** A model's free parameters are those its plugin exposes in
``mi.traverse`` when loaded with its defaults (so optional alternatives stay
out: Ward's anisotropic ``alpha_u``/``alpha_v``, toon's ramps), each with its
declaration in the plugin's ``PARAMS`` (range, kind, role). Each is searched
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

    def properties(self) -> dict:
        return {"type": self.plugin, "mode": "hdr", **dict(self.options)}


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


def names() -> list[str]:
    return [m.name for m in all_models()]


def select(wanted: list[str] | None) -> list[Model]:
    """The models named: a model's name, or a plugin's name that is no model's
    (``cook_torrance``, ``toon``: all its models); ValueError naming the
    unknown one and the valid names."""
    models = all_models()
    if not wanted:
        return models
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


def free_parameters(plugin_cls, traversed: list[str]) -> list[Free]:
    """The Free parameters of a plugin instance whose traverse keys are ``traversed``."""
    declared = {p.name: p for p in plugin_cls.PARAMS}
    out = []
    for key in traversed:
        name = key.split(".")[0]
        p = declared.get(name)
        if p is None:
            continue
        lo = p.lo if p.lo is not None else -1.0
        hi = p.probe_hi()
        log_start = p.role == "shape" and lo == 0.0
        if log_start and hi > 10.0:
            hi = min(hi, EXPONENT_MAX)
        out.append(Free(name, key, p.kind == "spectrum", lo, hi, log_start))
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
