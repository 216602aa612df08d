"""What every mi_brdfs plugin does alike, written once.

- **Parameters** (:class:`Param`): each model declares its parameters (name,
  default, valid range, kind, role) in ``PARAMS``; the base reads them (colours
  and scalars as Mitsuba textures, plain numbers as opaque differentiable
  Floats), checks them at load time *and* at ``params.update()`` with the same
  one-line message (plugin, parameter, value, valid range), and exposes them
  in ``traverse`` as differentiable.
- **Modes**: ``"scanline"`` clamps each lobe per colour channel to [0, 1] (the
  lecture's scan-line BRDFs), ``"hdr"`` keeps them unclamped.
- **Lobes**: a diffuse lobe (cosine- or uniform-hemisphere sampling), a glossy
  lobe (the model's own sampler) and, with ``energy_compensation``, the
  multiple-scattering lobe of :mod:`.energy` (cosine sampling), attached to the
  lobe it compensates. Each lobe is picked in proportion to an estimate of its
  albedo; ``pdf`` is the exact mixture; the sample weight is eval / pdf.
- **Model only what a scene requires**: a lobe whose colour or weight is the
  constant that switches it off (a colour 0, ``k`` = 0 or 1) is not declared in
  the flags and not traced. The rule that keeps inverse rendering right: a
  parameter counts as switched off only while it is a constant, is not
  grad-enabled and was never changed through ``params.update()``. Once a
  parameter is updated or differentiated its lobe stays traced (a gradient at
  the bound 0 is then exact, and an optimiser can leave the bound); the lobes
  are decided again in ``parameters_changed``.
- **Every variant**: scalar and JIT, RGB, mono and spectral; polarized variants
  get the plugins as depolarizers (Mitsuba's ``depolarizer``, as its ``diffuse``).
- **Per call**, each texture is evaluated once (:meth:`BRDF.inputs`) and shared
  by the lobes, the selection weights, the sampler and the pdf; a call traces
  only what it needs (Dr.Jit traces every material of a scene at every render,
  so a traced operation costs per material): a single lobe is sampled by its
  own sampler with no pick, and a lobe that is a colour times a shape
  (:class:`Scaled`) is masked, weighted and divided by its pdf as one Float
  per lane, its colour multiplied last.

A model subclasses :class:`BRDF` and supplies:

``PARAMS``
    its :class:`Param` declarations (``read()`` may be overridden for options
    and parameters that exclude each other; it then calls ``reader.read(p)``);
``has_diffuse()``, ``has_specular()``
    whether a lobe can matter, through :meth:`BRDF.off`;
``eval_textures(si, active)``
    the textures evaluated at ``si``, as a :class:`types.SimpleNamespace`;
``f_diffuse(inp, si, wo)``, ``f_specular(inp, si, wo)``
    each lobe in eval convention (the lecture's clamp(d·n) in scanline mode,
    cos θ_o in hdr mode), before the per-lobe clamp: a spectrum, or, for a lobe
    that is a colour times a shape, a :class:`Scaled` (colour, shape), which
    the base multiplies last; lanes with ``wi`` or ``wo`` below the surface are
    zeroed by the base, unless ``lit_from_behind()``;
``lobe_weights(inp)``
    the factors multiplying each (clamped) lobe, e.g. k and 1 - k;
``selection_weights(inp, si)``
    estimates of each lobe's albedo (weights included), for lobe selection;
``sample_specular(inp, si, sample2)``, ``pdf_specular(inp, si, wo)``
    the glossy lobe's sampler and its density;

and, if ``compensable`` (:mod:`.energy`): ``ms_colour(inp)``, the colour C
that scales the multiple-scattering lobe, and either ``compensation()`` (an
:class:`.energy.Table` of its albedo g per unit colour), ``table_parameters(inp)``
and ``table_sources()`` (the parameter each comes from), or ``ms_albedo(inp, v)``
and ``ms_average(inp)`` (an analytic g). The base specialises the table at the
parameters that are constant over the surface (at load time and at every
update) and holds its Dr.Jit arrays as the member ``m_ms``, so that Dr.Jit
traverses them with the plugin (frozen functions).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from operator import attrgetter
from types import SimpleNamespace
from typing import NamedTuple

import drjit as dr
import mitsuba as mi
import numpy as np

from .._binding import bind
from . import energy

MODES = ("scanline", "hdr")
SAMPLINGS = ("lobe", "cosine")    # each lobe's own importance sampling, or cosine for all
PDF_FLOOR = 1e-37                 # 1/pdf stays finite in float32 (the weight's scaling)
WEIGHT_MAX = 1e12                 # sample weights above this are float32 failures (see sample())
# "On the surface": a viewer or light with cos θ <= HORIZON gets no reflection.
# Above it every value is exact; below it the derivatives of near-mirror lobes
# (alpha 1e-4: d pdf/d alpha ~ 1/(2 pi alpha³ cos θ)) would exceed float32.
HORIZON = 1e-20
# The far ends of the ranges. Every accepted value is finite: a parameter with
# no upper bound takes numbers up to the largest float32. A colour ends at
# COLOUR_MAX (far above any reflectance; the scan-line clamp limits values above
# 1): up to there every value, pdf, sample weight and derivative stays finite for
# every other parameter at its own extremes (tests/bsdfs/test_battery.py), where
# a colour near FLOAT_MAX overflows a sum of two lobes.
FLOAT_MAX = float(np.finfo(np.float32).max)
COLOUR_MAX = 1e6


class ParameterError(ValueError):
    """A plugin parameter has a bad value (raised at load time or at update())."""


class DeclarationError(TypeError):
    """A model's Param or Option declaration is malformed (raised when its
    class is defined, i.e. when the module is imported)."""


# ----------------------------------------------------------------------------
#  Parameters: declaration, reading, checking
# ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Param:
    """One plugin parameter: how it is read, checked, exposed and tested.

    ``kind``: ``"spectrum"`` (any form Mitsuba's own colours take: float, rgb,
    spectrum, texture; evaluated per colour channel), ``"scalar"`` (the same
    forms, evaluated as one value, e.g. a roughness) or ``"float"`` (a plain
    number: an opaque Float, a float in a writable box in scalar variants; its
    traverse key is the bare name). ``role``: ``"colour"`` and ``"weight"`` scale a lobe
    (their gradients are checked at their bounds too), ``"shape"`` shapes it.
    ``upper`` is the upper end of the range the tests and the fit probe when it
    is narrower than the valid one (colours: 1, a white surface). A colour's
    range ends at :data:`COLOUR_MAX` unless it says otherwise; ``hi`` None
    means every finite number (up to :data:`FLOAT_MAX`): infinity is never valid. ``doc`` is its meaning, in the
    plugin's generated parameter table (:func:`parameter_table`); an
    ``optional`` parameter is read only when given (it has no default).
    Checked when declared: a known kind and role, lo <= default <= hi
    (DeclarationError otherwise).
    """
    name: str
    default: float
    lo: float | None = 0.0
    hi: float | None = None
    kind: str = "spectrum"
    role: str = "colour"
    upper: float | None = None
    doc: str = ""
    optional: bool = False

    KINDS = ("spectrum", "scalar", "float")
    ROLES = ("colour", "weight", "shape")

    def __post_init__(self):
        def refuse(what: str):
            raise DeclarationError(f"Param {self.name!r}: {what}")
        if self.role == "colour":               # see COLOUR_MAX; probed up to white
            if self.hi is None:
                object.__setattr__(self, "hi", COLOUR_MAX)
            if self.upper is None:
                object.__setattr__(self, "upper", min(1.0, self.hi))
        if self.kind not in self.KINDS:
            refuse(f"kind {self.kind!r} is unknown; valid: {', '.join(self.KINDS)}")
        if self.role not in self.ROLES:
            refuse(f"role {self.role!r} is unknown; valid: {', '.join(self.ROLES)}")
        if self.lo is not None and self.hi is not None and not self.lo < self.hi:
            refuse(f"empty range {self.valid()}")
        if not (isinstance(self.default, (int, float)) and not isinstance(self.default, bool)
                and math.isfinite(self.default)
                and (self.lo is None or self.default >= self.lo)
                and (self.hi is None or self.default <= self.hi)):
            refuse(f"default {self.default!r} is outside its range {self.valid()}")
        if self.upper is not None and not ((self.lo is None or self.upper > self.lo)
                                           and (self.hi is None or self.upper <= self.hi)):
            refuse(f"upper {self.upper!r} is outside its range {self.valid()}")

    def valid(self) -> str:
        return f"[{_fmt(self.lo, f'{-FLOAT_MAX:.7g}')}, {_fmt(self.hi, f'{FLOAT_MAX:.7g}')}]"

    def forms(self) -> str:
        """The property forms it accepts, with its range (for error messages)."""
        if self.kind == "float":
            return f"a number (<float> or <integer>) in {self.valid()}"
        return f"<float>, <rgb>, <spectrum> or a texture, with values in {self.valid()}"

    def probe_hi(self) -> float:
        """The largest value the tests and the fit try (``upper``, or hi, or 1)."""
        if self.upper is not None:
            return self.upper
        return self.hi if self.hi is not None else 1.0

    def far(self) -> tuple[float, float]:
        """The ends of the valid range as the float32 numbers nearest to them
        inside it: (lo, hi), an open end as the largest float32 of its sign."""
        def inside(bound: float | None, sign: float) -> float:
            if bound is None:
                return sign * FLOAT_MAX
            x = np.float32(bound)
            if (float(x) - bound) * sign > 0:           # rounded out of the range
                x = np.nextafter(x, np.float32(-sign * np.inf))
            return float(x)
        return inside(self.lo, -1.0), inside(self.hi, 1.0)


@dataclass(frozen=True)
class Option:
    """A non-differentiable choice: one of ``choices`` (strings), a boolean
    when ``default`` is a bool, or an integer in [``lo``, ``hi``] when it is an
    int. Read at load time into ``self.<name>``; ``doc`` is its meaning, in
    the generated parameter table. Checked when declared: the default is one
    of the choices, a bool without choices, or an int within its range
    (DeclarationError otherwise)."""
    name: str
    default: str | bool | int
    choices: tuple[str, ...] = ()
    doc: str = ""
    lo: int | None = None
    hi: int | None = None

    def __post_init__(self):
        if isinstance(self.default, bool):
            if self.choices:
                raise DeclarationError(f"Option {self.name!r}: a boolean has no choices")
        elif isinstance(self.default, int):
            if self.choices or self.lo is None or self.hi is None \
                    or not self.lo <= self.default <= self.hi:
                raise DeclarationError(f"Option {self.name!r}: an integer needs lo <= default "
                                       f"<= hi and no choices")
        elif not (isinstance(self.choices, tuple) and self.choices
                  and all(isinstance(c, str) for c in self.choices)):
            raise DeclarationError(f"Option {self.name!r}: choices must be a tuple of strings, "
                                   f"not {self.choices!r}")
        elif self.default not in self.choices:
            raise DeclarationError(f"Option {self.name!r}: default {self.default!r} is not one "
                                   f"of its choices ({', '.join(self.choices)})")

    def valid(self) -> str:
        if isinstance(self.default, bool):
            return "true or false (a <boolean>)"
        if isinstance(self.default, int):
            return f"an integer in [{self.lo}, {self.hi}] (an <integer>)"
        return "one of " + ", ".join(f'"{c}"' for c in self.choices) + " (a <string>)"


def _fmt(x: float | None, none: str) -> str:
    return none if x is None else f"{x:g}"


# ----------------------------------------------------------------------------
#  The generated parameter table of each plugin's documentation
# ----------------------------------------------------------------------------

PARAMETERS = ".. parameters::"     # the line of a model's docstring that becomes its table
FORMS = {"spectrum": "float, rgb, spectrum or texture", "scalar": "float or texture",
         "float": "float"}
BASE_DOCS = {               # the options every plugin has, documented once
    "mode": '``"hdr"``: physically normalised and unclamped, for path tracing; '
            '``"scanline"``: the lecture\'s scan-line formulas, each lobe clamped per '
            'colour channel to [0, 1] (not energy conserving, on purpose).',
    "sampling": '``"lobe"``: each lobe importance-sampled by its own sampler (below); '
                '``"cosine"``: every lobe from the cosine hemisphere, to measure what '
                'importance sampling gains (``mi-brdfs bench``), not for rendering.',
    "energy_compensation": 'hdr only (with ``mode="scanline"`` a load-time error): adds '
                           'the multiple-scattering lobe of :mod:`mi_brdfs.bsdfs.energy`, '
                           'which returns the light a single-scattering lobe loses; see '
                           '*Energy compensation* below.',
}


def _range(lo, hi) -> str:
    if lo is not None and hi is not None:
        return f" in [{lo:g}, {hi:g}]"
    if lo is not None:
        return f" >= {lo:g}"
    return f" <= {hi:g}" if hi is not None else ""


def _row(name: str, kind: str, doc: str, default: str) -> list[str]:
    import textwrap
    lines = textwrap.wrap(" ".join(doc.split()), 66) or [""]
    return [f"   * - ``{name}``", f"     - {kind}", f"     - {lines[0]}",
            *(f"       {line}" for line in lines[1:]), f"     - {default}"]


def parameter_table(cls) -> str:
    """The reStructuredText table of a plugin's parameters and options, made
    from its declarations (``PARAMS``, ``OPTIONS`` and the base's options):
    the one source of the plugin's parameter documentation."""
    rows = [".. list-table::", "   :header-rows: 1", "   :widths: 20 20 50 10", "",
            "   * - Parameter", "     - Type", "     - Description", "     - Default"]
    for p in cls.PARAMS:
        kind = FORMS[p.kind] + _range(p.lo, p.hi) + " (∂)"
        rows += _row(p.name, kind, p.doc, "none" if p.optional else f"{p.default:g}")
    for o in cls.OPTIONS + tuple(o for o in cls.options() if o not in cls.OPTIONS):
        doc = o.doc or BASE_DOCS[o.name]
        if isinstance(o.default, bool):
            kind, default = "boolean", str(o.default).lower()
        elif isinstance(o.default, int):
            kind, default = "integer" + _range(o.lo, o.hi), str(o.default)
        else:
            kind, default = "string", f'``"{o.default}"``'
            doc += " One of " + ", ".join(f'``"{c}"``' for c in o.choices) + "."
        rows += _row(o.name, kind, doc, default)
    return "\n".join(rows)


def document(cls) -> None:
    """Put the generated parameter table into the docstring of ``cls``'s module
    (at its ``.. parameters::`` line) and make that docstring the class's, so
    that ``help()``, the documentation site and the code cannot disagree."""
    import sys
    module = sys.modules.get(cls.__module__)
    doc = getattr(module, "__doc__", None) or ""
    if PARAMETERS in doc:
        doc = doc.replace(PARAMETERS, parameter_table(cls))
        module.__doc__ = doc
    if doc:
        cls.__doc__ = doc


class Shown:
    """A value as an error message shows it: its text, unquoted."""

    def __init__(self, text: str):
        self.text = text

    def __repr__(self) -> str:
        return self.text


def shown(value):
    """``value`` for a one-line error message: numbers and strings as they are,
    a spectrum by its samples, an object by its class (never a multi-line
    description)."""
    if isinstance(value, (bool, int, float, str, Shown)):
        return value
    if isinstance(value, mi.Object):
        kind = "a texture" if isinstance(value, mi.Texture) else "an object"
        return Shown(f"{kind} ({value.class_name()})")
    if hasattr(value, "wavelengths") and hasattr(value, "is_uniform"):   # a <spectrum>
        if value.is_uniform():
            return Shown(f"a spectrum ({value.values[0]:g})")
        pairs = [f"{w:g}:{v:g}" for w, v in zip(value.wavelengths, value.values)]
        if len(pairs) > 4:
            pairs = pairs[:2] + ["...", pairs[-1]]
        return Shown(f"a spectrum ({', '.join(pairs)})")
    text = " ".join(repr(value).split())
    return Shown(text if len(text) <= 60 else text[:57] + "...")


def parameter_error(plugin: str, name: str, value, valid: str) -> ParameterError:
    """The one-line message of every bad parameter value."""
    return ParameterError(f"{plugin}: parameter '{name}' = {shown(value)!r} is invalid; "
                          f"valid: {valid}")


def check_value(plugin: str, name: str, value: float, lo: float | None, hi: float | None,
                valid: str) -> None:
    """Raise ParameterError unless lo <= value <= hi and value is finite
    (NaN and infinities are never valid)."""
    lo_ok = lo is None or value >= lo
    hi_ok = hi is None or value <= hi
    if not (lo_ok and hi_ok and math.isfinite(value)):
        raise parameter_error(plugin, name, value, valid)


def _coefficients(value) -> bool:
    """True for an array of spectral-upsampling coefficients: in spectral
    variants, what ``srgb`` and 3-channel bitmaps store (3 per colour)."""
    if not mi.is_spectral:
        return False
    if dr.is_tensor_v(value):
        return value.ndim == 3 and value.shape[-1] == 3
    return dr.size_v(value) == 3


def _arrays(obj) -> list:
    """The numbers a texture holds, its differentiable parameters (not its
    wavelengths or transforms), or a plain Float itself."""
    if isinstance(obj, mi.Object):
        params = mi.traverse(obj)
        out = []
        for key in params.keys():
            if params.flags(key) & mi.ParamFlags.NonDifferentiable:
                continue
            value = params[key]
            if isinstance(value, (float, int)) or (dr.is_array_v(value) and dr.is_float_v(value)):
                out.append(value)
        return out
    return [obj]


# The coefficients spectral upsampling stores for white, the largest spectrum it
# holds (Mitsuba's rgb2spec: a sigmoid of 8192, i.e. 1 at every wavelength).
WHITE_COEFFICIENTS = (0.0, 0.0, 8192.0)


def saturated_pixels(tex) -> int:
    """How many pixels of a texture's spectral-upsampling coefficients encode
    white (0 outside spectral variants, or for a texture without them)."""
    count = 0
    for a in _arrays(tex):
        if _coefficients(a) and dr.is_tensor_v(a):
            c = np.asarray(dr.detach(a)).reshape(-1, 3)
            count += int(np.all(c == WHITE_COEFFICIENTS, axis=1).sum())
    return count


# Spectral upsampling (Jakob & Hanika 2019) gives a sigmoid of a polynomial in
# the wavelength: every spectrum stored as coefficients lies in [0, 1].
UPSAMPLED_RANGE = (0.0, 1.0)


def value_range(obj) -> tuple[float, float] | None:
    """(min, max) of the values a texture (or a Float) holds; NaN if any is NaN;
    None if it holds none. Spectral-upsampling coefficients count as the range
    of the spectra they encode, [0, 1]."""
    lo, hi = math.inf, -math.inf
    found = False
    for a in _arrays(obj):
        if _coefficients(a):
            x = np.array(UPSAMPLED_RANGE)
        else:
            x = np.asarray(dr.detach(a) if dr.is_array_v(a) else a, dtype=np.float64).ravel()
        if x.size == 0:
            continue
        found = True
        if np.isnan(x).any():
            return math.nan, math.nan
        lo, hi = min(lo, float(x.min())), max(hi, float(x.max()))
    return (lo, hi) if found else None


def grad_enabled(obj) -> bool:
    """True if a Float or any parameter of a texture is attached to the AD graph."""
    return any(dr.grad_enabled(a) for a in _arrays(obj) if dr.is_array_v(a))


def number(x: float):
    """A plain number parameter as the formulas use it: an opaque Float in JIT
    variants (one kernel for every value), a float in scalar ones."""
    return dr.opaque(mi.Float, x)


T = mi.Properties.Type
NUMBERS = (T.Float, T.Integer)


def to_float(x) -> float:
    """A Python float from an opaque Float (JIT variants) or a float (scalar ones)."""
    return float(x[0]) if dr.is_array_v(x) else float(x)


class Reader:
    """Reads one plugin's properties and raises ParameterError on bad values.

    A colour or scalar parameter takes every form Mitsuba's own plugins take
    (``props.get_texture``: a float, an rgb, a spectrum, a texture, a
    reference), and means what it means to them; a Python list of three
    numbers (``mi.load_dict``) reads as an rgb. A plain number takes a float or
    an integer. Range checks apply to the values the element holds.
    """

    def __init__(self, plugin: str, props: mi.Properties):
        self.plugin, self.props = plugin, props

    def error(self, name: str, value, valid: str) -> ParameterError:
        return parameter_error(self.plugin, name, value, valid)

    def check(self, p: Param, value) -> None:
        check_value(self.plugin, p.name, value, p.lo, p.hi, p.valid())

    def read(self, p: Param):
        """The value of parameter ``p``: a texture, or a number for kind "float"."""
        props, name = self.props, p.name
        if name not in props:
            self.check(p, p.default)
            if p.kind == "float":
                return number(p.default)
            return mi.load_dict({"type": "uniform", "value": p.default})
        kind, value = props.type(name), props[name]
        if p.kind == "float":
            if kind not in NUMBERS:
                raise self.error(name, value, p.forms())
            self.check(p, float(value))
            return number(float(value))
        if kind == T.Vector:                       # [r, g, b] from a Python dictionary
            props[name] = mi.ScalarColor3d(value)
            kind = T.Color
        if kind in NUMBERS:
            values = [float(value)]
        elif kind == T.Color:
            values = [float(c) for c in value]
        elif kind == T.Spectrum:
            values = [float(v) for v in value.values]
        elif kind == T.Object and isinstance(value, mi.Texture):
            self.check_texture(p, value)
            self.check_evaluates(p, value)
            self.warn_saturated(p, value)
            return value
        else:
            raise self.error(name, value if kind in (T.String, T.Bool, T.Object)
                             else Shown(f"a <{kind.name.lower()}>"), p.forms())
        for v in values:
            self.check(p, v)
        pairs = kind == T.Spectrum and not value.is_uniform()
        if pairs and min(values) < 0.0:
            # a distribution in spectral variants; clipped to 0 in sRGB in RGB variants
            raise self.error(name, min(values), "a <spectrum> of values >= 0 (a <float> "
                             "for a negative constant)")
        if kind == T.Color and mi.is_spectral and max(values) > 1.0:
            # rgb2spec clamps to [0, 1]: (2, 2, 2) would be 1, (3, 0.5, 0.1) another hue
            raise self.error(name, max(values), "rgb components <= 1 in spectral variants "
                             "(spectral upsampling holds [0, 1]); a <float> or a <spectrum> "
                             "for values above 1")
        # Colours above 1 are accepted (the scanline clamp limits them): unbounded
        # then, so that a spectrum's sRGB colour is not clipped to 1 in RGB variants.
        try:
            tex = (props.get_unbounded_texture if max(values) > 1.0 else props.get_texture)(name)
        except Exception as e:                    # e.g. a spectrum file Mitsuba cannot read
            reason = str(e).strip().splitlines()[-1].split("] ")[-1]
            raise self.error(name, value, f"{p.forms()} (Mitsuba: {reason})") from None
        if pairs:
            self.check_evaluates(p, tex)
        return tex

    def check_texture(self, p: Param, tex) -> None:
        rng = value_range(tex)
        if rng is not None:
            self.check(p, rng[0])
            self.check(p, rng[1])

    def warn_saturated(self, p: Param, tex) -> None:
        """In spectral variants a bitmap's pixels are upsampled to spectra in
        [0, 1] (Jakob & Hanika 2019) when the texture is built, before a plugin
        sees it: a value above 1 reads as 1, as for Mitsuba's ``diffuse``, and
        nothing tells (RGB variants keep it and Mitsuba warns). What is left to
        see is a pixel at the upsampling's ceiling, white; warn once for this
        parameter if any pixel is, since that is where values above 1 went."""
        count = saturated_pixels(tex)
        if count:
            mi.Log(mi.LogLevel.Warn,
                   f"{self.plugin}: parameter '{p.name}': {count} pixel(s) of its bitmap read "
                   "as white (1 in every channel): spectral upsampling clamps each pixel to "
                   "[0, 1], so a value above 1 in the image reads as 1 (as for Mitsuba's "
                   "diffuse); an RGB variant, or a <float> or <spectrum> above 1, keeps it")

    def check_evaluates(self, p: Param, tex) -> None:
        """A texture must answer the plugin's lookups (per channel, or one value
        for kind "scalar"), or Mitsuba raises at the first render: e.g. in
        spectral variants a wavelength-dependent spectrum or a 3-channel
        bitmap has no single value."""
        si = dr.zeros(mi.SurfaceInteraction3f)
        try:
            tex.eval_1(si) if p.kind == "scalar" else tex.eval(si)
        except Exception:
            raise self.error(p.name, tex, p.forms() + (
                "; one value per point in spectral variants (a <float>, a constant "
                "<spectrum>, a one-channel texture)" if p.kind == "scalar" else "")) from None

    def option(self, o: Option):
        """The value of option ``o`` (a string among its choices, or a bool)."""
        if o.name not in self.props:
            return o.default
        kind, value = self.props.type(o.name), self.props[o.name]
        if isinstance(o.default, bool):
            if kind != T.Bool:
                raise self.error(o.name, value, o.valid())
            return value
        if isinstance(o.default, int):
            if kind != T.Integer or not o.lo <= value <= o.hi:
                raise self.error(o.name, value, o.valid())
            return value
        if kind != T.String or value not in o.choices:
            raise self.error(o.name, value, o.valid())
        return value


def as_type(x, kind: type):
    """``x`` as a ``kind`` (a Dr.Jit type): a direct call from Python may pass
    a list, a tuple or a number, as Mitsuba's own bindings accept them."""
    return x if type(x) is kind or isinstance(x, kind) else kind(x)


def mean(spectrum) -> mi.Float:
    """Channel mean of a spectrum: the scalar weight used for lobe selection."""
    return dr.sum(spectrum, axis=0) * (1.0 / dr.size_v(spectrum))


def clamp01(x):
    """The lecture's clamp() per colour channel; NaN-free (fmin drops NaN). At
    x = 0 (a black colour) the derivative is the one from above, 1: an
    optimiser starting from black can leave it."""
    return dr.fmin(dr.select(x >= 0.0, x, 0.0), 1.0)


class Scaled(NamedTuple):
    """A lobe's value as ``colour · shape``, what most lobes are: the colour (a
    spectrum) is multiplied last, so that the base's masks, weights and guards
    act on one Float per lane instead of one per colour channel.

    ``ratio``: shape / pdf of the lobe's own sampler, where it is known in
    closed form (Lambert's lobe under cosine sampling: 1, :func:`.lambert.f`);
    a sample of that lobe alone then weighs ``colour · ratio``, without the
    division and without the float32 guards that the division needs."""
    colour: object
    shape: object
    ratio: object = None


def product(value):
    """A lobe's value as a spectrum (a :class:`Scaled` multiplied out)."""
    return value.colour * value.shape if type(value) is Scaled else value


def one(x) -> bool:
    """True for the Python number 1 (a factor that needs no multiplication)."""
    return (type(x) is float or type(x) is int) and x == 1.0


def weighted(value, w, scanline: bool):
    """w times a lobe's value, clamped per channel to [0, 1] first in scanline
    mode (the lecture's clamp01(lobe)); a :class:`Scaled` value stays one in hdr mode."""
    if scanline:
        value = clamp01(product(value))
    elif type(value) is Scaled:
        if one(w):
            return value
        return Scaled(value.colour, w * value.shape,
                      None if value.ratio is None else w * value.ratio)
    return value if one(w) else w * value


def mixed(p, prob, density):
    """The mixture density p plus one lobe's density picked with probability prob
    (p None: the first lobe; prob the number 1: a lobe alone)."""
    term = density if one(prob) else prob * density
    return term if p is None else p + term


def total(values, mask):
    """The sum of lobe values, 0 where ``mask`` is off, as a spectrum: a
    :class:`Scaled` value is masked on its shape and multiplied by its colour last."""
    f = None
    for v in values:
        v = v.colour * dr.select(mask, v.shape, 0.0) if type(v) is Scaled \
            else dr.select(mask, v, 0.0)
        f = v if f is None else f + v
    return f if type(f) is mi.UnpolarizedSpectrum else mi.UnpolarizedSpectrum(f)


class Lobes(NamedTuple):
    """Which lobes a call evaluates (Python booleans: decided at trace time)."""
    diffuse: bool
    specular: bool
    multiple: bool


class Plan(NamedTuple):
    """What every traced call of an instance reads, decided with its lobes
    (:meth:`BRDF.update_lobes`) so that a call reads it once."""
    lobes: Lobes          # the lobes present
    scanline: bool        # mode == "scanline"
    cosine: bool          # sampling == "cosine": every lobe sampled from the cosine hemisphere
    uniform: bool         # the diffuse lobe sampled from the uniform hemisphere
    behind: bool          # lit_from_behind()


ALL = int(mi.BSDFFlags.All)       # a context's type mask that enables every lobe type
ANY = 2**32 - 1                   # its component (-1): every component
GLOSSY = int(mi.BSDFFlags.GlossyReflection)      # a sample's type
DIFFUSE = int(mi.BSDFFlags.DiffuseReflection)


def facing(si, active):
    """``active`` where the viewer is above the surface: a viewer below (or on)
    it gets no reflection."""
    up = si.wi.z > HORIZON
    return up if active is True else up & active


# ----------------------------------------------------------------------------
#  The shared BSDF logic
# ----------------------------------------------------------------------------

class State:
    """A plugin's Python-side state: its options, which parameters it read,
    which are live, which lobes it has. Kept out of the instance's own
    attributes, which Dr.Jit traverses at every replay of a frozen render
    (measured: 200 lambert instances, 25.6 ms per replay with this state as
    attributes, 16.4 ms without; a plain object is not traversed)."""


STATE = ("params", "live", "diffuse", "specular", "multiple", "diffuse_index",
         "specular_index", "energy_compensation", "plan", "switches", "ms_table")   # what the base keeps


class BRDF:
    """Base of every mi_brdfs plugin (plain Python; bound to mi.BSDF by bind()).

    Its own attributes are the ``m_*`` members (textures, Floats: what Dr.Jit
    must see); every other attribute lives in a :class:`State`, read and
    written through transparently.
    """

    name = "brdf"                     # the registered plugin name
    OPTIONS: tuple[Option, ...] = ()
    PARAMS: tuple[Param, ...] = ()
    reciprocal = True                 # hdr mode: f(wi, wo) = f(wo, wi) (the tests check it)
    compensable = False               # has an energy_compensation parameter
    compensates = "specular"          # the lobe the multiple-scattering lobe belongs to

    def __init__(self, props: mi.Properties):
        mi.BSDF.__init__(self, props)
        object.__setattr__(self, "_s", State())
        reader = Reader(self.name, props)
        self.energy_compensation = False
        for o in self.options():
            setattr(self, o.name, reader.option(o))
        if self.energy_compensation and self.mode == "scanline":
            raise reader.error("energy_compensation", True,
                               'false with mode="scanline" (the lecture\'s scan-line '
                               'formulas are not normalised; compensation is for mode="hdr")')
        self.params: dict[str, Param] = {}     # the parameters read, by name
        self.live: set[str] = set()            # parameters updated or differentiated
        self.boxes: dict = {}                  # scalar variants: plain numbers, writable
        self.read(reader)
        self.update_lobes()

    def __init_subclass__(cls, **kwargs):     # (no super(): bind() copies this body)
        # The declarations, checked when the class is defined.
        for what, items, kind in (("PARAMS", cls.PARAMS, Param), ("OPTIONS", cls.OPTIONS, Option)):
            for item in items:
                if not isinstance(item, kind):
                    raise DeclarationError(f"{cls.__name__}.{what}: {item!r} is not a {kind.__name__}")
        names = [p.name for p in cls.PARAMS] + [o.name for o in cls.options()]
        for name in names:
            if names.count(name) > 1:
                raise DeclarationError(f"{cls.__name__}: {name!r} is declared twice")
        document(cls)
        # Options and the base's state as properties: read at every traced call,
        # ~0.05 us each (attrgetter, in C) against ~0.5 us through __getattr__.
        for name in STATE + tuple(o.name for o in cls.options()):
            if not any(name in vars(k) for k in cls.__mro__):
                setattr(cls, name, property(attrgetter("_s." + name)))

    def __setattr__(self, name, value):
        if name.startswith("m_"):                 # members Dr.Jit must see
            object.__setattr__(self, name, value)
        else:
            setattr(self._s, name, value)

    def __getattr__(self, name):                   # only for names not found otherwise
        try:
            return getattr(object.__getattribute__(self, "_s"), name)
        except AttributeError:
            raise AttributeError(f"{type(self).__name__} has no attribute {name!r}") from None

    # --- options and parameters ----------------------------------------------------
    @classmethod
    def options(cls) -> tuple[Option, ...]:
        """Every option: the base's (mode, sampling, energy_compensation) and the model's."""
        base = (Option("mode", "hdr", MODES),
                # "cosine" samples every lobe from the cosine hemisphere: for measuring
                # what importance sampling gains (mi-brdfs bench), not for rendering.
                Option("sampling", "lobe", SAMPLINGS))
        if cls.compensable:
            base += (Option("energy_compensation", False),)
        return base + cls.OPTIONS

    def read(self, reader: Reader) -> None:
        """Read every declared parameter (override to read options too)."""
        for p in self.PARAMS:
            self.read_param(reader, p)

    def read_param(self, reader: Reader, p: Param):
        """Read ``p`` into ``self.m_<name>`` and remember it as present."""
        value = reader.read(p)
        if p.kind == "float" and not dr.is_jit_v(mi.Float):
            # Scalar variants: a plain number is a Python float, which traverse
            # cannot hand out for writing; the box it hands out instead is read
            # back in parameters_changed.
            self.boxes[p.name] = dr.scalar.Array1f(value)
            value = self.boxes[p.name][0]
        setattr(self, "m_" + p.name, value)
        self.params[p.name] = p
        if grad_enabled(value):
            self.live.add(p.name)
        return value

    def traverse(self, cb):
        for name in self.params:
            value = self.boxes[name] if name in self.boxes else getattr(self, "m_" + name)
            cb.put(name, value, mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys=[]):
        """Check the changed parameters as at load time, mark them live, and
        decide again which lobes the scene requires."""
        names = {key.split(".")[0] for key in keys}
        for name, box in self.boxes.items():       # scalar variants' plain numbers
            setattr(self, "m_" + name, box[0])
        for name in names or self.params:
            p = self.params.get(name)
            if p is None:
                continue
            if name in names:
                self.live.add(name)
            rng = value_range(getattr(self, "m_" + name))
            if rng is not None:        # stored in float32: compare with float32 bounds
                lo, hi = (None if b is None else float(np.float32(b)) for b in (p.lo, p.hi))
                check_value(self.name, name, rng[0], lo, hi, p.valid())
                check_value(self.name, name, rng[1], lo, hi, p.valid())
        self.update_lobes()

    def off(self, name: str, value: float = 0.0) -> bool:
        """True if parameter ``name`` is the constant ``value`` (0: a black colour
        or a zero weight) and cannot change: not spatially varying, not
        grad-enabled, never updated. Models use it to drop lobes that cannot matter."""
        if name not in self.params or name in self.live:
            return False
        obj = getattr(self, "m_" + name)
        if grad_enabled(obj):
            return False
        if isinstance(obj, mi.Object) and obj.is_spatially_varying():
            return False
        rng = value_range(obj)
        return rng is not None and rng == (value, value)

    def switch(self, name: str):
        """Plain-number parameter ``name`` as the formulas take it: the Python
        number 0 or 1 while it is that constant (as :meth:`off` decides), so
        that a weight of 1 or a factor that switches a term off folds away when
        the call is traced (decided again with the lobes); its member otherwise."""
        value = self.switches.get(name)
        return getattr(self, "m_" + name) if value is None else value

    # --- what a model provides -------------------------------------------------
    def has_diffuse(self) -> bool:
        return False

    def has_specular(self) -> bool:
        return False

    def eval_textures(self, si, active) -> SimpleNamespace:
        return SimpleNamespace()

    def with_colours(self, si, active, **shape) -> SimpleNamespace:
        """``eval_textures`` of a model with ``diffuse_reflectance`` and
        ``specular_reflectance``: its evaluated shape parameters (``shape``) and
        the lecture's m_D, m_S for the lobes present (``colour_d``, ``colour_s``)."""
        inp = SimpleNamespace(**shape)
        if self.diffuse:
            inp.colour_d = self.m_diffuse_reflectance.eval(si, active)
        if self.specular:
            inp.colour_s = self.m_specular_reflectance.eval(si, active)
        return inp

    def f_diffuse(self, inp, si, wo):
        raise NotImplementedError

    def f_specular(self, inp, si, wo):
        raise NotImplementedError

    def lobe_weights(self, inp):
        return 1.0, 1.0

    def selection_weights(self, inp, si):
        return mi.Float(1.0), mi.Float(1.0)

    def sample_specular(self, inp, si, sample2):
        raise NotImplementedError

    def pdf_specular(self, inp, si, wo):
        raise NotImplementedError

    def f_pdf_specular(self, inp, si, wo):
        """(f_specular, pdf_specular) at once; a model may share their work."""
        return self.f_specular(inp, si, wo), self.pdf_specular(inp, si, wo)

    def albedo_spec(self) -> energy.AlbedoSpec | None:
        """The :class:`.energy.AlbedoSpec` of this instance's single-scattering
        albedo (None: a model with an analytic one)."""
        return None

    def compensation(self) -> energy.Table | None:
        """The table of the multiple-scattering lobe's albedo g per unit colour
        (default: 1 - E of :meth:`albedo_spec`; None: an analytic g)."""
        spec = self.albedo_spec()
        return None if spec is None else energy.complement(spec)

    def table_parameters(self, inp) -> tuple:
        """The model parameters of that table's axes, evaluated (``inp``)."""
        raise NotImplementedError

    def table_sources(self) -> tuple[str, ...]:
        """The name of the parameter each table parameter comes from."""
        raise NotImplementedError

    def specialise_compensation(self) -> None:
        """The compensation table at the parameters constant over the surface
        (plain numbers and uniform textures, evaluated once here), its arrays
        held as the member ``m_ms``."""
        table = self.compensation()
        if table is None:
            return
        inp = self.eval_textures(dr.zeros(mi.SurfaceInteraction3f), True)
        constants = tuple(
            None if isinstance(obj, mi.Object) and obj.is_spatially_varying() else to_float(x)
            for obj, x in zip((getattr(self, "m_" + n) for n in self.table_sources()),
                              self.table_parameters(inp)))
        self.ms_table = table.specialise(constants)
        self.m_ms = self.ms_table.data               # traversed with the plugin

    def ms_albedo(self, inp, v):
        """g(v): the directional albedo of the multiple-scattering lobe per unit
        colour, at direction v (local)."""
        return self.ms_table(v, self.table_parameters(inp), self.m_ms)

    def ms_average(self, inp):
        """G_avg: its cosine-weighted hemispherical average."""
        return self.ms_table.average(self.table_parameters(inp), self.m_ms)

    def ms_colour(self, inp):
        """The colour C scaling the multiple-scattering lobe (see :mod:`.energy`)."""
        raise NotImplementedError

    def diffuse_sampling(self) -> str:
        """How the diffuse lobe is sampled: "cosine" (for lobes carrying a
        cos theta_o, the Lambert-like ones) or "uniform" (for a lobe that is
        constant over the hemisphere, like toon's, where cosine sampling would
        give weights 1/cos theta_o of infinite variance)."""
        return "cosine"

    def lit_from_behind(self) -> bool:
        """True if eval() must see lights below the surface (cos_o <= 0), e.g.
        the toon model's dark side in scanline mode; the lobes then zero what
        must be zero."""
        return False

    # --- lobes and flags ---------------------------------------------------------
    def update_lobes(self) -> None:
        """Declare exactly the lobes present: an absent lobe is never traced."""
        self.switches = {p.name: v for p in self.params.values() if p.kind == "float"
                         for v in (0.0, 1.0) if self.off(p.name, v)}
        self.diffuse, self.specular = self.has_diffuse(), self.has_specular()
        parent = self.specular if self.compensates == "specular" else self.diffuse
        self.multiple = self.energy_compensation and parent
        components = []
        if self.diffuse:
            components.append(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
        if self.specular:
            components.append(mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide)
        self.diffuse_index = 0
        self.specular_index = len(components) - 1
        flags = mi.BSDFFlags.Empty
        for c in components:
            flags |= c
        self.m_components = components
        self.m_flags = flags
        if self.multiple:
            self.specialise_compensation()
        self.plan = Plan(Lobes(self.diffuse, self.specular, self.multiple),
                         self.mode == "scanline", self.sampling == "cosine",
                         self.diffuse_sampling() == "uniform", self.lit_from_behind())

    def trace_key(self) -> tuple:
        """The Python-side choices that decide what a call traces beyond the
        flags: the plan and the parameters folded as numbers. A frozen
        function keys on it (:mod:`mi_brdfs.render.frozen`): a change
        re-records instead of replaying stale code."""
        table = getattr(self, "ms_table", None) if self.multiple else None
        fixed = tuple(table.fixed) if table is not None else ()
        return self.plan, tuple(sorted(self.switches.items())), fixed

    def enabled(self, ctx) -> Lobes:
        """The lobes that exist and that ctx asks for."""
        if ctx.type_mask == ALL and ctx.component == ANY:         # (the usual context)
            return self.plan.lobes
        d = self.diffuse and ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, self.diffuse_index)
        s = self.specular and ctx.is_enabled(mi.BSDFFlags.GlossyReflection, self.specular_index)
        return Lobes(d, s, self.multiple and (s if self.compensates == "specular" else d))

    def inputs(self, si, active) -> SimpleNamespace:
        """Everything a call needs at ``si``, each texture evaluated once."""
        inp = self.eval_textures(si, active)
        if self.multiple:
            inp.g_i = self.ms_albedo(inp, si.wi)              # g(w_i)
            inp.g_avg = self.ms_average(inp)                  # G_avg
            inp.f_ms = self.ms_colour(inp)                    # C
        return inp

    def f_multiple(self, inp, si, wo):
        return energy.ms_lobe(inp.f_ms, inp.g_i, self.ms_albedo(inp, wo), inp.g_avg,
                              mi.Frame3f.cos_theta(wo))

    def probabilities(self, inp, si, use: Lobes):
        """(p_d, p_s, p_ms): each used lobe picked in proportion to its weight;
        None when a single lobe is used (nothing to choose: nothing traced)."""
        count = sum(use)
        if count <= 1:
            return None
        w_d, w_s = self.selection_weights(inp, si)
        w_ms = mi.Float(0.0)
        if use.multiple:
            w = self.lobe_weights(inp)[0 if self.compensates == "diffuse" else 1]
            w_ms = w * mean(inp.f_ms) * inp.g_i
        weights = [dr.select(u, w, 0.0) if u else mi.Float(0.0)
                   for u, w in zip(use, (w_d, w_s, w_ms))]
        total = weights[0] + weights[1] + weights[2]
        ok = total > 0
        inv = 1.0 / dr.select(ok, total, 1.0)
        return tuple(dr.select(ok, w * inv, (1.0 / count) if u else 0.0)
                     for u, w in zip(use, weights))

    # --- the BSDF interface --------------------------------------------------
    # Each call traces only what it needs: a single lobe is sampled by its own
    # sampler with nothing to pick, and a lobe's value stays colour · shape
    # (Scaled) until the end, so that masks, weights and guards act on one
    # Float per lane. A viewer below (or on) the surface gets no reflection.
    def sample(self, ctx, si, sample1, sample2, active=True):
        sample1, sample2 = as_type(sample1, mi.Float), as_type(sample2, mi.Point2f)
        use = self.enabled(ctx)
        if not any(use):
            return dr.zeros(mi.BSDFSample3f), self.spectrum(mi.UnpolarizedSpectrum(0.0))
        plan = self.plan
        active = facing(si, active)
        inp = self.inputs(si, active)
        probs = self.probabilities(inp, si, use)
        modelled = False                 # wo from the model's own sampler (else a warp of sample2)
        if probs is None:              # one lobe, its own sampler (or cosine): nothing to pick
            glossy = use.specular                            # a Python constant
            if plan.cosine or not (use.specular or plan.uniform):
                wo = mi.warp.square_to_cosine_hemisphere(sample2)
            elif use.specular:
                wo, modelled = self.sample_specular(inp, si, sample2), True
            else:
                wo = mi.warp.square_to_uniform_hemisphere(sample2)
            own = not plan.cosine or not (use.specular or plan.uniform)
        else:
            # Pick a lobe (comparisons, not ~: scalar variants' masks are Python bools).
            p_d, p_s, _ = probs
            wo = mi.warp.square_to_cosine_hemisphere(sample2)      # diffuse and multiple
            if not plan.cosine:
                if use.diffuse and plan.uniform:
                    wo = dr.select(mi.Bool(sample1 < p_d),
                                   mi.warp.square_to_uniform_hemisphere(sample2), wo)
                if use.specular:
                    pick_s = (mi.Bool(sample1 >= p_d) & (sample1 < p_d + p_s)) if use.multiple \
                        else mi.Bool(sample1 >= p_d)
                    wo = dr.select(pick_s, self.sample_specular(inp, si, sample2), wo)
                    modelled = True
            # the multiple-scattering lobe counts as the kind of the lobe it compensates
            glossy = (mi.Bool(sample1 >= p_d) & (sample1 < p_d + p_s)) \
                if self.compensates == "diffuse" and use.multiple else mi.Bool(sample1 >= p_d)
            own = False

        # The sampled direction is a fixed point for the derivatives (as Mitsuba's
        # differentiable integrators treat it): the weight's gradient is that of
        # eval/pdf there, not of the sampler's warping (which depends on the
        # parameters: a warp of sample2 does not).
        if modelled and dr.grad_enabled(wo):
            wo = dr.detach(wo)
        values, pdf, up = self.lobes(use, probs, inp, si, wo, active)
        active = up & (pdf > 0)                         # (a failed sample: pdf 0)
        lone = values[0] if len(values) == 1 and type(values[0]) is Scaled else None
        closed = lone is not None and own and lone.ratio is not None
        if closed:
            # f / pdf in closed form (e.g. Lambert: its colour): no division, no guard
            weight = dr.select(active, lone.colour, 0.0) if one(lone.ratio) \
                else lone.colour * dr.select(active, lone.ratio, 0.0)
        else:
            # A weight beyond WEIGHT_MAX is no sample of the model but float32
            # failing it: a near-mirror lobe at a grazing viewer (alpha 1e-4, cos
            # 1e-30) puts wo = reflect(wi, m) so close to -wi that wi + wo no longer
            # holds m, and eval and pdf are taken about another half vector. Discarded.
            # (A lone lobe is judged by its shape: its colour is a finite factor.)
            value = lone.shape if lone is not None else product(values[0])
            for v in values[1:]:
                value = value + product(v)
            active &= (value if lone is not None else mean(value)) <= WEIGHT_MAX * pdf
            # weight = value / pdf, both scaled by a detached 1/pdf first: the same
            # value, and derivatives without pdf² (which underflows for the tiny pdfs
            # of grazing samples and would turn the gradient into inf - inf).
            p = dr.select(active, pdf, 1.0)
            value = dr.select(active, value, 0.0)
            scale = dr.detach(1.0 / dr.fmax(p, PDF_FLOOR))
            weight = dr.select(active, (value * scale) / (p * scale), 0.0)
            if lone is not None:
                weight = lone.colour * weight
        # no NaN from inactive lanes either (a warp of sample2 has none anywhere)
        bs = mi.BSDFSample3f(dr.select(active, wo, 0.0) if modelled else wo)
        # (0 already wherever a closed-form weight is: the pdf is 0 below the surface)
        bs.pdf = pdf if closed else dr.select(active, pdf, 0.0)
        bs.eta = 1.0
        if type(glossy) is bool:                       # the picked lobe is known
            bs.sampled_type = mi.UInt32(GLOSSY if glossy else DIFFUSE)
            bs.sampled_component = mi.UInt32(self.specular_index if glossy
                                             else self.diffuse_index)
        else:
            bs.sampled_type = dr.select(glossy, mi.UInt32(GLOSSY), mi.UInt32(DIFFUSE))
            bs.sampled_component = dr.select(glossy, mi.UInt32(self.specular_index),
                                             mi.UInt32(self.diffuse_index))
        if type(weight) is not mi.UnpolarizedSpectrum:
            weight = mi.UnpolarizedSpectrum(weight)
        return bs, mi.depolarizer(weight) if mi.is_polarized else weight

    def eval(self, ctx, si, wo, active=True):
        wo = as_type(wo, mi.Vector3f)
        use = self.enabled(ctx)
        if not any(use):
            return self.spectrum(mi.UnpolarizedSpectrum(0.0))
        active = facing(si, active)
        values, _, up = self.lobes(use, None, self.inputs(si, active), si, wo, active, pdf=False)
        value = total(values, active if self.plan.behind else up)
        return mi.depolarizer(value) if mi.is_polarized else value

    def pdf(self, ctx, si, wo, active=True):
        wo = as_type(wo, mi.Vector3f)
        use = self.enabled(ctx)
        if not any(use):
            return mi.Float(0.0)
        active = facing(si, active)
        inp = self.inputs(si, active)
        return self.lobes(use, self.probabilities(inp, si, use), inp, si, wo, active,
                          value=False)[1]

    def eval_pdf(self, ctx, si, wo, active=True):
        wo = as_type(wo, mi.Vector3f)
        use = self.enabled(ctx)
        if not any(use):
            return self.spectrum(mi.UnpolarizedSpectrum(0.0)), mi.Float(0.0)
        active = facing(si, active)
        inp = self.inputs(si, active)
        values, pdf, up = self.lobes(use, self.probabilities(inp, si, use), inp, si, wo, active)
        value = total(values, active if self.plan.behind else up)
        return (mi.depolarizer(value) if mi.is_polarized else value), pdf

    # --- the lobes, summed -------------------------------------------------------
    def lobes(self, use: Lobes, probs, inp, si, wo, active, value=True, pdf=True):
        """(values, pdf, up) of the used lobes at wo, ``active`` holding the
        viewer above the surface: ``values`` the list of the lobes' weighted
        values (:func:`weighted`; summed and masked by :func:`total`), ``pdf``
        the mixture of the lobes' samplers with the selection probabilities
        ``probs`` (None: a single lobe's own density), 0 where the light is
        below the surface; ``up`` where it is above. Either of the first two is
        None when not asked for."""
        plan = self.plan
        up = active & (wo.z > HORIZON)
        w_d, w_s = self.lobe_weights(inp) if value else (None, None)
        values = [] if value else None
        p = None
        lobe_pdfs = pdf
        if pdf and plan.cosine:
            p, lobe_pdfs = mi.warp.square_to_cosine_hemisphere_pdf(wo), False
        p_d, p_s, p_ms = probs if probs is not None else (1.0, 1.0, 1.0)
        if use.diffuse:
            if value:
                values.append(weighted(self.f_diffuse(inp, si, wo), w_d, plan.scanline))
            if lobe_pdfs:
                p = mixed(p, p_d, mi.warp.square_to_uniform_hemisphere_pdf(wo) if plan.uniform
                          else mi.warp.square_to_cosine_hemisphere_pdf(wo))
        if use.specular:
            if value and lobe_pdfs:
                f_s, p_s_wo = self.f_pdf_specular(inp, si, wo)
                values.append(weighted(f_s, w_s, plan.scanline))
                p = mixed(p, p_s, p_s_wo)
            elif value:
                values.append(weighted(self.f_specular(inp, si, wo), w_s, plan.scanline))
            elif lobe_pdfs:
                p = mixed(p, p_s, self.pdf_specular(inp, si, wo))
        if use.multiple:                 # hdr only
            if value:
                values.append(weighted(self.f_multiple(inp, si, wo),
                                       w_s if self.compensates == "specular" else w_d, False))
            if lobe_pdfs:
                p = mixed(p, p_ms, mi.warp.square_to_cosine_hemisphere_pdf(wo))
        return values, (dr.select(up, p, 0.0) if pdf else None), up

    @staticmethod
    def spectrum(value):
        """What eval/sample return: the value itself, or a depolarizing Mueller
        matrix in polarized variants (as Mitsuba's ``diffuse`` does)."""
        return mi.depolarizer(value) if mi.is_polarized else value

    # --- attributes, as Mitsuba's BSDF base class answers them ----------------------
    # A texture parameter is looked up (eval, eval_1, eval_3); a plain number is an
    # attribute whose value only eval_attribute_1 returns (the others give 0, as
    # for a built-in's Float member); an unknown name gives 0 in JIT variants and
    # raises in scalar ones. Written here because in scalar variants the base
    # class sees a plain number as the box traverse hands out, not as a Float.
    def has_attribute(self, name, active=True):
        return mi.Bool(name in self.params)

    def eval_attribute(self, name, si, active=True):
        return self.attribute(name, si, active, "eval", mi.UnpolarizedSpectrum)

    def eval_attribute_1(self, name, si, active=True):
        return self.attribute(name, si, active, "eval_1", mi.Float)

    def eval_attribute_3(self, name, si, active=True):
        return self.attribute(name, si, active, "eval_3", mi.Color3f)

    def attribute(self, name, si, active, method: str, kind: type):
        p = self.params.get(name)
        if p is None:
            if not dr.is_jit_v(mi.Float):
                raise RuntimeError(f"[{type(self).__name__}] Invalid attribute requested {name}.")
            return dr.zeros(kind)
        value = getattr(self, "m_" + name)
        if p.kind != "float":
            return getattr(value, method)(si, active)
        return mi.Float(value) if kind is mi.Float else dr.zeros(kind)

    # --- description -------------------------------------------------------------
    def to_string(self):
        fields = ", ".join(f"{k}={v}" for k, v in self.describe().items())
        return f"{type(self).__name__}[mode={self.mode}, {fields}]"

    def describe(self) -> dict:
        fields = {o.name: getattr(self, o.name) for o in self.options() if o.name != "mode"}
        fields.update({name: getattr(self, "m_" + name) for name in self.params})
        return fields


# ----------------------------------------------------------------------------
#  Registration
# ----------------------------------------------------------------------------

def register_plugin(cls: type) -> None:
    """Register ``cls`` under ``cls.name`` for the active variant."""
    bound = bind(cls)
    mi.register_bsdf(cls.name, lambda props: bound(props))
