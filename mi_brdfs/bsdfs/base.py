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
  by the lobes, the selection weights, the sampler and the pdf.

A model subclasses :class:`BRDF` and supplies:

``PARAMS``
    its :class:`Param` declarations (``read()`` may be overridden for options
    and parameters that exclude each other; it then calls ``reader.read(p)``);
``has_diffuse()``, ``has_specular()``
    whether a lobe can matter, through :meth:`BRDF.off`;
``evaluate(si, active)``
    the textures evaluated at ``si``, as a :class:`types.SimpleNamespace`;
``f_diffuse(inp, si, wo)``, ``f_specular(inp, si, wo)``
    each lobe in eval convention (the lecture's clamp(d·n) in scanline mode,
    cos θ_o in hdr mode), before the per-lobe clamp; lanes with ``wi`` or ``wo``
    below the surface are zeroed by the base, unless ``lit_from_behind()``;
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


class ParameterError(ValueError):
    """A plugin parameter has a bad value (raised at load time or at update())."""


# ----------------------------------------------------------------------------
#  Parameters: declaration, reading, checking
# ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Param:
    """One plugin parameter: how it is read, checked, exposed and tested.

    ``kind``: ``"spectrum"`` (float, rgb or any texture, evaluated per colour
    channel), ``"scalar"`` (float or texture, evaluated as one value, e.g. a
    roughness) or ``"float"`` (a plain number, an opaque Float; its traverse
    key is the bare name). ``role``: ``"colour"`` and ``"weight"`` scale a lobe
    (their gradients are checked at their bounds too), ``"shape"`` shapes it.
    ``upper`` is the upper end of the range the tests probe when ``hi`` is
    unbounded (colours: 1, a white surface).
    """
    name: str
    default: float
    lo: float | None = 0.0
    hi: float | None = None
    kind: str = "spectrum"
    role: str = "colour"
    upper: float | None = None

    def valid(self) -> str:
        return f"[{_fmt(self.lo, '-inf')}, {_fmt(self.hi, 'inf')}]"

    def probe_hi(self) -> float:
        """The largest value the tests try (hi, or ``upper``, or 1)."""
        return self.hi if self.hi is not None else (self.upper if self.upper is not None else 1.0)


@dataclass(frozen=True)
class Option:
    """A non-differentiable choice: one of ``choices`` (strings), or a boolean
    when ``default`` is a bool. Read at load time into ``self.<name>``."""
    name: str
    default: str | bool
    choices: tuple[str, ...] = ()

    def valid(self) -> str:
        if isinstance(self.default, bool):
            return "true or false"
        return "one of " + ", ".join(f'"{c}"' for c in self.choices)


def _fmt(x: float | None, none: str) -> str:
    return none if x is None else f"{x:g}"


def parameter_error(plugin: str, name: str, value, valid: str) -> ParameterError:
    """The one-line message of every bad parameter value."""
    return ParameterError(f"{plugin}: parameter '{name}' = {value!r} is invalid; valid: {valid}")


def check_value(plugin: str, name: str, value: float, lo: float | None, hi: float | None,
                valid: str | None = None) -> None:
    """Raise ParameterError unless lo <= value <= hi (NaN is never valid)."""
    lo_ok = lo is None or value >= lo
    hi_ok = hi is None or value <= hi
    if not (lo_ok and hi_ok) or (isinstance(value, float) and math.isnan(value)):
        raise parameter_error(plugin, name, value,
                              valid or f"[{_fmt(lo, '-inf')}, {_fmt(hi, 'inf')}]")


def _arrays(obj) -> list:
    """The numeric arrays of a texture's parameters (or of a plain Float)."""
    if isinstance(obj, mi.Object):
        out = []
        for _, value in mi.traverse(obj).items():
            if isinstance(value, (float, int)) or (dr.is_array_v(value) and not dr.is_integral_v(value)
                                                   and not dr.is_mask_v(value)):
                out.append(value)
        return out
    return [obj]


def value_range(obj) -> tuple[float, float] | None:
    """(min, max) over every numeric parameter of a texture (or a Float); NaN if
    any value is NaN; None if it has none. Reduced in Dr.Jit, without copies."""
    lo, hi = math.inf, -math.inf
    found = False
    for a in _arrays(obj):
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


def to_float(x) -> float:
    """A Python float from an opaque Float (JIT variants) or a float (scalar ones)."""
    return float(x[0]) if dr.is_array_v(x) else float(x)


class Reader:
    """Reads one plugin's properties and raises ParameterError on bad values."""

    def __init__(self, plugin: str, props: mi.Properties):
        self.plugin, self.props = plugin, props

    def error(self, name: str, value, valid: str) -> ParameterError:
        return parameter_error(self.plugin, name, value, valid)

    def check(self, name: str, value, lo: float | None, hi: float | None) -> None:
        check_value(self.plugin, name, value, lo, hi)

    def read(self, p: Param):
        """The value of parameter ``p``: a texture, or an opaque Float for kind "float"."""
        props = self.props
        if p.kind == "float":
            value = float(props.get(p.name, p.default))
            self.check(p.name, value, p.lo, p.hi)
            return dr.opaque(mi.Float, value)
        if p.name not in props:
            self.check(p.name, p.default, p.lo, p.hi)
            return mi.load_dict({"type": "uniform", "value": p.default})
        value = props[p.name]
        if isinstance(value, (int, float)):
            self.check(p.name, float(value), p.lo, p.hi)
            return mi.load_dict({"type": "uniform", "value": float(value)})
        if not isinstance(value, mi.Object):      # an rgb colour
            rgb = [float(c) for c in value]
            for c in rgb:
                self.check(p.name, c, p.lo, p.hi)
            # Colours above 1 are accepted (``unbounded``): the scanline clamp limits them.
            return mi.load_dict({"type": "srgb", "color": rgb, "unbounded": True})
        tex = props.get_texture(p.name)            # a nested texture
        self.check_texture(p, tex)
        return tex

    def check_texture(self, p: Param, tex) -> None:
        # Its parameters are its values in RGB and mono variants; spectral
        # variants store spectral-upsampling coefficients instead (unchecked).
        rng = None if mi.is_spectral else value_range(tex)
        if rng is not None:
            self.check(p.name, rng[0], p.lo, p.hi)
            self.check(p.name, rng[1], p.lo, p.hi)

    def option(self, o: Option):
        """The value of option ``o`` (a string among its choices, or a bool)."""
        value = self.props.get(o.name, o.default)
        if isinstance(o.default, bool):
            if not isinstance(value, bool):
                raise self.error(o.name, value, o.valid())
            return value
        value = str(value)
        if value not in o.choices:
            raise self.error(o.name, value, o.valid())
        return value


def mean(spectrum) -> mi.Float:
    """Channel mean of a spectrum: the scalar weight used for lobe selection."""
    return dr.mean(spectrum, axis=0)


def clamp01(x):
    """The lecture's clamp() per colour channel; NaN-free (fmin drops NaN). At
    x = 0 (a black colour) the derivative is the one from above, 1: an
    optimiser starting from black can leave it."""
    return dr.fmin(dr.select(x >= 0.0, x, 0.0), 1.0)


class Lobes(NamedTuple):
    """Which lobes a call evaluates (Python booleans: decided at trace time)."""
    diffuse: bool
    specular: bool
    multiple: bool


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
         "specular_index", "energy_compensation")      # what the base keeps per instance


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
        self.read(reader)
        self.update_lobes()

    def __init_subclass__(cls, **kwargs):     # (no super(): bind() copies this body)
        # Options and the base's state as properties: read at every traced call,
        # ~0.07 us each against ~0.5 us through __getattr__.
        for name in STATE + tuple(o.name for o in cls.options()):
            if not any(name in vars(k) for k in cls.__mro__):
                setattr(cls, name, property(lambda self, n=name: getattr(self._s, n)))

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
        setattr(self, "m_" + p.name, value)
        self.params[p.name] = p
        if grad_enabled(value):
            self.live.add(p.name)
        return value

    def traverse(self, cb):
        for name in self.params:
            cb.put(name, getattr(self, "m_" + name), mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys=[]):
        """Check the changed parameters as at load time, mark them live, and
        decide again which lobes the scene requires."""
        names = {key.split(".")[0] for key in keys}
        for name in names or self.params:
            p = self.params.get(name)
            if p is None:
                continue
            if name in names:
                self.live.add(name)
            rng = None if (mi.is_spectral and p.kind != "float") else value_range(
                getattr(self, "m_" + name))
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

    # --- what a model provides -------------------------------------------------
    def has_diffuse(self) -> bool:
        return False

    def has_specular(self) -> bool:
        return False

    def evaluate(self, si, active) -> SimpleNamespace:
        return SimpleNamespace()

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
        inp = self.evaluate(dr.zeros(mi.SurfaceInteraction3f), True)
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

    def enabled(self, ctx) -> Lobes:
        """The lobes that exist and that ctx asks for."""
        d = self.diffuse and ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, self.diffuse_index)
        s = self.specular and ctx.is_enabled(mi.BSDFFlags.GlossyReflection, self.specular_index)
        return Lobes(d, s, self.multiple and (s if self.compensates == "specular" else d))

    def inputs(self, si, active) -> SimpleNamespace:
        """Everything a call needs at ``si``, each texture evaluated once."""
        inp = self.evaluate(si, active)
        if self.multiple:
            inp.g_i = self.ms_albedo(inp, si.wi)              # g(w_i)
            inp.g_avg = self.ms_average(inp)                  # G_avg
            inp.f_ms = self.ms_colour(inp)                    # C
        return inp

    def f_multiple(self, inp, si, wo):
        return energy.ms_lobe(inp.f_ms, inp.g_i, self.ms_albedo(inp, wo), inp.g_avg,
                              mi.Frame3f.cos_theta(wo))

    def probabilities(self, inp, si, use: Lobes):
        """(p_d, p_s, p_ms): each used lobe picked in proportion to its weight."""
        count = sum(use)
        if count <= 1:                     # nothing to choose: constants, not traced
            return tuple(mi.Float(1.0 if u else 0.0) for u in use)
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
    def sample(self, ctx, si, sample1, sample2, active=True):
        use = self.enabled(ctx)
        bs = dr.zeros(mi.BSDFSample3f)
        cos_i = mi.Frame3f.cos_theta(si.wi)
        active = mi.Bool(active) & (cos_i > HORIZON)
        if not any(use):
            return bs, self.spectrum(mi.UnpolarizedSpectrum(0.0))
        inp = self.inputs(si, active)
        probs = self.probabilities(inp, si, use)
        # Pick a lobe (comparisons, not ~: scalar variants' masks are Python bools).
        if sum(use) == 1:
            pick_d, pick_s = use.diffuse, use.specular        # Python constants
        else:
            p_d, p_s, _ = probs
            pick_d = mi.Bool(sample1 < p_d)
            pick_s = (mi.Bool(sample1 >= p_d) & (sample1 < p_d + p_s)) if use.multiple \
                else mi.Bool(sample1 >= p_d)
        if self.sampling == "cosine" or not (use.specular or self.diffuse_sampling() == "uniform"):
            wo = mi.warp.square_to_cosine_hemisphere(sample2)
        else:
            wo = mi.warp.square_to_cosine_hemisphere(sample2)   # diffuse and multiple
            if use.diffuse and self.diffuse_sampling() == "uniform":
                wo = dr.select(pick_d, mi.warp.square_to_uniform_hemisphere(sample2), wo)
            if use.specular:
                wo = dr.select(pick_s, self.sample_specular(inp, si, sample2), wo)

        # The sampled direction is a fixed point for the derivatives (as Mitsuba's
        # differentiable integrators treat it): the weight's gradient is that of
        # eval/pdf there, not of the sampler's warping.
        wo = dr.detach(wo)
        value, pdf = self.lobes(use, probs, inp, si, wo, active)
        active &= (pdf > 0) & (mi.Frame3f.cos_theta(wo) > HORIZON)    # (a failed sample: pdf 0)
        # A weight beyond WEIGHT_MAX is no sample of the model but float32 failing
        # it: a near-mirror lobe at a grazing viewer (alpha 1e-4, cos 1e-30) puts
        # wo = reflect(wi, m) so close to -wi that wi + wo no longer holds m, and
        # eval and pdf are taken about another half vector. Discarded.
        active &= mean(value) <= WEIGHT_MAX * pdf
        glossy = (pick_s if self.compensates == "diffuse" else
                  (not pick_d if isinstance(pick_d, bool) else mi.Bool(sample1 >= probs[0])))
        bs.wo = dr.select(active, wo, 0.0)      # no NaN from inactive lanes either
        bs.pdf = dr.select(active, pdf, 0.0)
        bs.eta = 1.0
        bs.sampled_type = dr.select(glossy, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                                    mi.UInt32(+mi.BSDFFlags.DiffuseReflection))
        bs.sampled_component = dr.select(glossy, mi.UInt32(self.specular_index),
                                         mi.UInt32(self.diffuse_index))
        # weight = value / pdf, both scaled by a detached 1/pdf first: the same
        # value, and derivatives without pdf² (which underflows for the tiny pdfs
        # of grazing samples and would turn the gradient into inf - inf).
        pdf = dr.select(active, pdf, 1.0)
        value = dr.select(active, value, 0.0)
        scale = dr.detach(1.0 / dr.fmax(pdf, PDF_FLOOR))
        weight = (value * scale) / (pdf * scale)
        return bs, self.spectrum(dr.select(active, weight, 0.0))

    def eval(self, ctx, si, wo, active=True):
        use = self.enabled(ctx)
        if not any(use):
            return self.spectrum(mi.UnpolarizedSpectrum(0.0))
        inp = self.inputs(si, active)
        return self.spectrum(self.lobes(use, None, inp, si, wo, active, pdf=False)[0])

    def pdf(self, ctx, si, wo, active=True):
        use = self.enabled(ctx)
        if not any(use):
            return mi.Float(0.0)
        inp = self.inputs(si, active)
        return self.lobes(use, self.probabilities(inp, si, use), inp, si, wo, active,
                          value=False)[1]

    def eval_pdf(self, ctx, si, wo, active=True):
        use = self.enabled(ctx)
        if not any(use):
            return self.spectrum(mi.UnpolarizedSpectrum(0.0)), mi.Float(0.0)
        inp = self.inputs(si, active)
        value, pdf = self.lobes(use, self.probabilities(inp, si, use), inp, si, wo, active)
        return self.spectrum(value), pdf

    # --- the lobes, summed -------------------------------------------------------
    def lobes(self, use: Lobes, probs, inp, si, wo, active, value=True, pdf=True):
        """(eval, pdf) of the used lobes at wo (either None when not asked for):
        each lobe's value clamped in scanline mode and weighted; the pdf the
        mixture of the lobes' samplers with the selection probabilities."""
        cos_o = mi.Frame3f.cos_theta(wo)
        # A viewer or light below (or on) the surface gets no reflection.
        active = mi.Bool(active) & (mi.Frame3f.cos_theta(si.wi) > HORIZON)
        up = active & (cos_o > HORIZON)
        f, p = mi.UnpolarizedSpectrum(0.0), mi.Float(0.0)
        want_pdf = pdf
        if pdf and self.sampling == "cosine":
            p, pdf = mi.warp.square_to_cosine_hemisphere_pdf(wo), False
        w_d, w_s = self.lobe_weights(inp) if value else (None, None)
        clamp = clamp01 if self.mode == "scanline" else (lambda x: x)
        p_d, p_s, p_ms = probs if pdf else (None, None, None)
        if use.diffuse:
            if value:
                f += w_d * clamp(self.f_diffuse(inp, si, wo))
            if pdf:
                p += p_d * (mi.warp.square_to_uniform_hemisphere_pdf(wo)
                            if self.diffuse_sampling() == "uniform"
                            else mi.warp.square_to_cosine_hemisphere_pdf(wo))
        if use.specular:
            if value and pdf:
                f_s, p_s_wo = self.f_pdf_specular(inp, si, wo)
                f += w_s * clamp(f_s)
                p += p_s * p_s_wo
            elif value:
                f += w_s * clamp(self.f_specular(inp, si, wo))
            elif pdf:
                p += p_s * self.pdf_specular(inp, si, wo)
        if use.multiple:                 # hdr only
            if value:
                f += (w_s if self.compensates == "specular" else w_d) \
                    * self.f_multiple(inp, si, wo)
            if pdf:
                p += p_ms * mi.warp.square_to_cosine_hemisphere_pdf(wo)
        f = dr.select(active if self.lit_from_behind() else up, f, 0.0) if value else None
        return f, (dr.select(up, p, 0.0) if want_pdf else None)

    @staticmethod
    def spectrum(value):
        """What eval/sample return: the value itself, or a depolarizing Mueller
        matrix in polarized variants (as Mitsuba's ``diffuse`` does)."""
        return mi.depolarizer(value) if mi.is_polarized else value

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
