"""The course models a fit tries, and how each parameter is searched.

**Models.** Every plugin of :data:`mi_brdfs.bsdfs.PLUGINS`, in hdr mode; a
plugin with options that change the model itself (:data:`VARIANTS`: the D and
G of ``cook_torrance``, the specular cosine of ``toon``) gives one model per
combination, and a ``compensable`` plugin each of those with and without
``energy_compensation`` (the name gets ``+ec``). Options that change only how
a model is computed or sampled (``sampling``, ``sample_visible``, Ward's
``formula``, Oren-Nayar's ``method``) keep their defaults. Names:
``lambert``, ``phong+ec``, ``cook_torrance/ggx/smith``, ... (:func:`names`).

**Parameters.** A model's free parameters are those its plugin exposes in
``mi.traverse`` when loaded with its defaults (so optional alternatives stay
out: Ward's anisotropic ``alpha_u``/``alpha_v``, toon's ramps), each with its
declaration in the plugin's ``PARAMS`` (range, kind, role). Each is searched
over the box [lo, hi] of its declaration, with ``hi`` = the declared upper
end, or ``upper``, or 1 for an unbounded colour (white); shape parameters
with a lower end of 0 are searched on a logarithmic scale — exponents
(upper end above 10) as log(1 + x) up to ``EXPONENT_MAX``, roughnesses as
log(x + 1e-3·hi) — all others linearly. The optimiser moves unit
coordinates y in [0, 1]^n (clipped after each step) mapped onto the boxes.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

# Options that make different models (the others are computation choices).
VARIANTS = {"cook_torrance": ("distribution", "geometry"), "toon": ("specular_model",)}
EXPONENT_MAX = 1e6        # exponents are searched up to here (a mirror-like lobe)
LOG_SHAPE_OFFSET = 1e-3   # roughness: log(x + 1e-3 hi)
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
    from ...bsdfs import PLUGINS
    out = []
    for cls in PLUGINS:
        choices = {o.name: o.choices for o in cls.all_options()}
        names = VARIANTS.get(cls.name, ())
        for combo in itertools.product(*(choices[n] for n in names)):
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
            raise ValueError(f"unknown model {w!r}; valid: "
                             f"{', '.join(m.name for m in models)}, or cook_torrance, toon "
                             "(all their models)")
        chosen += [m for m in found if m not in chosen]
    return chosen


# ----------------------------------------------------------------------------
#  Free parameters and their search boxes
# ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Free:
    """A fitted parameter: its traverse key, box and scale."""
    name: str
    key: str                 # mi.traverse key ("alpha.value", "k")
    colour: bool             # three channels (a "spectrum" parameter)
    lo: float
    hi: float
    offset: float | None     # log scale: log(x + offset); None: linear

    def _ends(self):
        if self.offset is None:
            return self.lo, self.hi
        return math.log(self.lo + self.offset), math.log(self.hi + self.offset)

    def value(self, y):
        """Unit coordinate(s) y -> parameter value (Dr.Jit or NumPy)."""
        a, b = self._ends()
        t = a + (b - a) * y
        if self.offset is None:
            return t
        import drjit as dr
        exp = dr.exp if not isinstance(t, (float, np.ndarray, np.floating)) else np.exp
        return exp(t) - self.offset

    def unit(self, x: float) -> float:
        """Parameter value -> unit coordinate (clipped into the box)."""
        x = min(max(float(x), self.lo), self.hi)
        a, b = self._ends()
        t = x if self.offset is None else math.log(x + self.offset)
        return (t - a) / (b - a) if b > a else 0.0


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
        offset = None
        if p.role == "shape" and lo == 0.0:
            if hi > 10.0:
                hi, offset = min(hi, EXPONENT_MAX), 1.0
            else:
                offset = LOG_SHAPE_OFFSET * hi
        out.append(Free(name, key, p.kind == "spectrum", lo, hi, offset))
    return out


def starts(free: list[Free], defaults: dict, count: int, seed: int = 7) -> list[np.ndarray]:
    """``count`` starting points in unit coordinates: the plugin's defaults,
    then a Latin hypercube over the boxes (each colour channel its own axis)."""
    dims = sum(3 if f.colour else 1 for f in free)
    first = []
    for f in free:
        d = defaults[f.name]
        first += [f.unit(d)] * (3 if f.colour else 1)
    points = [np.array(first)]
    n = count - 1
    if n > 0:
        rng = np.random.default_rng(seed)
        grid = np.stack([(rng.permutation(n) + rng.random(n)) / n for _ in range(dims)], axis=1)
        points += list(grid)
    return points[:count]


def split(free: list[Free], y: np.ndarray) -> dict:
    """A flat unit vector -> {name: unit value (float or 3-tuple)}."""
    out, i = {}, 0
    for f in free:
        n = 3 if f.colour else 1
        out[f.name] = tuple(y[i:i + n]) if f.colour else float(y[i])
        i += n
    return out


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
