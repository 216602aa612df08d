"""The ``mi.BSDF`` glue every mi_brdfs plugin shares, written once.

A model subclasses :class:`BRDF` and supplies its declarations and hooks
(its parameters, its lobes' formulas and samplers, its cases; each hook is
documented on its default: :class:`BRDF` and :class:`.mixture.Mixture`).
This module does the rest, alike for every model:

- **loading**: every option and parameter read and checked by
  :class:`.params.Reader` (one line naming the plugin, the parameter, the
  value and the valid range), the same checks again at ``params.update()``;
  ``traverse`` exposes every parameter as differentiable (and a roughness as
  discontinuous too, as Mitsuba does);
- **modes**: ``"scanline"`` clamps each lobe per colour channel to [0, 1]
  (the lecture's scan-line BRDFs), ``"hdr"`` keeps them unclamped;
- **model only what a scene requires**: a lobe whose colour or weight is the
  constant that switches it off (a colour 0, ``k`` = 0 or 1) is not declared
  in the flags and not traced. A parameter counts as switched off only while
  it is a constant, is not grad-enabled and was never changed through
  ``params.update()``; once updated or differentiated its lobe stays traced
  (a gradient at the bound 0 is then exact). The lobes are decided again in
  ``parameters_changed``;
- **the BSDF interface** over the lobes: inherited from :class:`.mixture.Mixture`
  (each lobe picked in proportion to an estimate of its albedo, ``pdf`` the
  exact mixture, the sample weight eval / pdf or its closed form, the
  multiple-scattering lobe of energy compensation attached to the lobe it
  belongs to); this module decides what a call may trace (Dr.Jit traces every
  material of a scene at every render, so each traced operation costs per
  material);
- **every variant**: scalar and JIT, RGB, mono and spectral; polarized
  variants get the plugins as depolarizers (as Mitsuba's ``diffuse``).

An instance keeps two kinds of attributes: its ``m_*`` members (textures,
Floats, tables: what Dr.Jit must see, e.g. as inputs of a frozen function) and
two plain objects, ``self.options`` (the option values) and ``self.state``
(what the base decided: the parameters read, the lobes, the plan of a call),
which Dr.Jit does not traverse (measured: 200 lambert instances, 25.6 ms per
replay of a frozen render with that state as attributes, 16.4 ms without).
"""
from __future__ import annotations

from typing import NamedTuple

import drjit as dr
import mitsuba as mi
import numpy as np

from .._binding import bind, create
from .compensation import Compensation
from .mixture import Lobes, Mixture, Plan
from .params import (DeclarationError, Option, Param, Reader, check_value, grad_enabled,
                     value_range)

MODES = ("scanline", "hdr")
SAMPLINGS = ("lobe", "cosine")    # each lobe's own importance sampling, or cosine for all

MODE = Option("mode", "hdr", MODES,
              doc='``"hdr"``: physically normalised and unclamped, for path tracing; '
                  '``"scanline"``: the lecture\'s scan-line formulas, each lobe clamped per '
                  'colour channel to [0, 1] (not energy conserving, on purpose).')
SAMPLING = Option("sampling", "lobe", SAMPLINGS,
                  doc='``"lobe"``: each lobe importance-sampled by its own sampler; '
                      '``"cosine"``: every lobe from the cosine hemisphere, to measure what '
                      'importance sampling gains (``mi-brdfs bench``), not for rendering.')
ENERGY_COMPENSATION = Option(
    "energy_compensation", False,
    doc='hdr only (with ``mode="scanline"`` a load-time error): adds the multiple-'
        'scattering lobe of :mod:`mi_brdfs.bsdfs.compensation`, which returns the light a '
        'single-scattering lobe loses; see *Energy compensation* below.')


class Options:
    """A plugin's option values, by name (``self.options.mode``): plain Python,
    fixed at load time."""

    def __init__(self, values: dict):
        self.__dict__.update(values)


class State:
    """What the base decided for an instance (plain Python; see the module doc)."""

    def __init__(self):
        self.params: dict[str, Param] = {}    # the parameters read, by name
        self.live: set[str] = set()           # parameters updated or differentiated
        self.boxes: dict = {}                 # scalar variants: plain numbers' C++ holders
        self.switches: dict[str, float] = {}  # plain numbers folded while 0 or 1
        self.compensation: Compensation | None = None   # the multiple-scattering lobe
        self.plan: Plan | None = None         # what a call traces
        self.index = {"diffuse": 0, "specular": 0}   # each lobe's component index


class BRDF(Mixture):
    """Base of every mi_brdfs plugin (plain Python; bound onto a variant's
    ``mi.BSDF`` by :func:`register_plugin`).

    A model is one module: its pure formulas, then a subclass of this class
    that declares what it is and implements the hooks it needs, each
    documented on its default: the declarations below and the load-time hooks
    here (run when the plugin is loaded and again at ``params.update()``), the
    traced hooks in :class:`.mixture.Mixture` (run inside ``sample``,
    ``eval``, ``pdf``, ``eval_pdf``). This class and its parent do the rest:
    reading and checking the parameters, the two modes, which lobes a scene
    requires, the mixture of the lobes, energy compensation."""

    name = "brdf"                     # the plugin's name in scene files (<bsdf type="NAME">)
    OPTIONS: tuple[Option, ...] = ()  # its choices (the base adds mode, sampling and,
    #                                   with compensation(), energy_compensation)
    PARAMS: tuple[Param, ...] = ()    # its parameters: colours, weights and shapes
    reciprocal = True                 # hdr mode: f(wi, wo) = f(wo, wi) (the tests check it)
    compensable = False               # derived: the model defines compensation()

    def __init__(self, props: mi.Properties):
        super().__init__(props)
        self.state = State()
        reader = Reader(self.name, props)
        self.options = Options({o.name: reader.option(o) for o in self.all_options()})
        if getattr(self.options, "energy_compensation", False) and self.options.mode == "scanline":
            raise reader.error("energy_compensation", True,
                               'false with mode="scanline" (the lecture\'s scan-line '
                               'formulas are not normalised; compensation is for mode="hdr")')
        self.read(reader)
        self.update_lobes()

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        cls.compensable = cls.compensation.__code__ is not BRDF.compensation.__code__
        # The declarations, checked when the class is defined.
        for what, items, kind in (("PARAMS", cls.PARAMS, Param), ("OPTIONS", cls.OPTIONS, Option)):
            for item in items:
                if not isinstance(item, kind):
                    raise DeclarationError(f"{cls.__name__}.{what}: {item!r} is not a "
                                           f"{kind.__name__}")
        names = [p.name for p in cls.PARAMS] + [o.name for o in cls.all_options()]
        for name in names:
            if names.count(name) > 1:
                raise DeclarationError(f"{cls.__name__}: {name!r} is declared twice")

    # --- declared -----------------------------------------------------------------
    @classmethod
    def all_options(cls) -> tuple[Option, ...]:
        """Every option: the base's (mode, sampling, energy_compensation) and the model's."""
        return (MODE, SAMPLING) + ((ENERGY_COMPENSATION,) if cls.compensable else ()) \
            + cls.OPTIONS

    @classmethod
    def cases(cls):
        """The configurations the tests, the validation report, the bench, the
        fit and the documentation run (:mod:`.cases`). Every model declares them."""
        raise NotImplementedError(f"{cls.__name__} declares no cases()")

    @classmethod
    def effective(cls, values: dict, cos_theta: float) -> Effective:
        """What parameter values mean to a user looking at the surface (the fit
        reports it): the diffuse colour, the specular colour seen at incidence
        cos θ (the highlight's colour), each an RGB list or None where the
        model has no such lobe, and notes on parameters that have no effect.
        ``values``: plain numbers and RGB lists by parameter name. Default:
        ``reflectance`` or ``diffuse_reflectance`` as the diffuse colour,
        ``specular_reflectance`` as the specular one at every angle."""
        diffuse = values.get("diffuse_reflectance", values.get("reflectance"))
        specular = values.get("specular_reflectance")
        return Effective(None if diffuse is None else rgb_list(diffuse),
                         None if specular is None else rgb_list(specular))

    @classmethod
    def tables(cls) -> list:
        """The albedo tables its compensation reads (built offline by ``python -m
        mi_brdfs.tools.tables``). Default: none."""
        return []

    # --- parameters ---------------------------------------------------------------
    def read_param(self, reader: Reader, p: Param):
        """Read ``p`` into ``self.m_<name>`` and remember it as present."""
        value = reader.read(p)
        if p.kind == "float" and not dr.is_jit_v(mi.Float):
            # Scalar variants: a plain number is a Python float, as a built-in's;
            # traverse hands out a writable float held by a C++ object (see traverse).
            self.state.boxes[p.name] = Box(value)
        setattr(self, "m_" + p.name, value)
        self.state.params[p.name] = p
        if grad_enabled(value):
            self.state.live.add(p.name)
        return value

    @staticmethod
    def traverse_flags(p: Param) -> mi.ParamFlags:
        """The flags ``traverse`` puts parameter ``p`` with (the plugin pages'
        flags column reads them): differentiable; a roughness also moves the
        sampler, so discontinuous too, as Mitsuba flags roughconductor's alpha."""
        return mi.ParamFlags.Differentiable | (mi.ParamFlags.Discontinuous if p.discontinuous
                                               else mi.ParamFlags(0))

    def traverse(self, cb):
        for name, p in self.state.params.items():
            flags = self.traverse_flags(p)
            box = self.state.boxes.get(name)
            if box is None:
                cb.put(name, getattr(self, "m_" + name), flags)
            else:
                cb.put(name, box.pointer, flags, box.type)

    def parameters_changed(self, keys=[]):
        """Check the changed parameters as at load time, mark them live, and
        decide again which lobes the scene requires."""
        names = {key.split(".")[0] for key in keys}
        for name, box in self.state.boxes.items():     # scalar variants' plain numbers
            setattr(self, "m_" + name, box.value())
        for name in names or self.state.params:
            p = self.state.params.get(name)
            if p is None:
                continue
            if name in names:
                self.state.live.add(name)
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
        if name not in self.state.params or name in self.state.live or not self.uniform(name):
            return False
        rng = value_range(getattr(self, "m_" + name))
        return rng is not None and rng == (value, value)

    def uniform(self, name: str) -> bool:
        """True if parameter ``name`` is one value over the surface and not
        differentiated (it may still be updated: what is derived from it is
        then derived again with the lobes)."""
        obj = getattr(self, "m_" + name)
        return not grad_enabled(obj) and not (isinstance(obj, mi.Object)
                                              and obj.is_spatially_varying())

    def switch(self, name: str):
        """Plain-number parameter ``name`` as the formulas take it: the Python
        number 0 or 1 while it is that constant (as :meth:`off` decides), so
        that a weight of 1 or a factor that switches a term off folds away when
        the call is traced (decided again with the lobes); its member otherwise."""
        value = self.state.switches.get(name)
        return getattr(self, "m_" + name) if value is None else value

    # --- the model's load-time hooks (its traced ones: mixture.Mixture) ------------
    def read(self, reader: Reader) -> None:
        """Read every parameter: ``self.read_param(reader, p)`` per Param (the
        default), with a model's own rules where parameters exclude each other
        or an option changes a range."""
        for p in self.PARAMS:
            self.read_param(reader, p)

    def has_diffuse(self) -> bool:
        """Whether the diffuse lobe can matter: use ``self.off(name)`` (a
        parameter that is the constant that switches the lobe off and cannot
        change). Default False."""
        return False

    def has_specular(self) -> bool:
        """Whether the specular lobe (the model's highlight) can matter. Default False."""
        return False

    def compensation(self) -> Compensation | None:
        """The multiple-scattering lobe of energy compensation (:mod:`.compensation`):
        a model that defines this hook has the option ``energy_compensation``."""
        return None

    def diffuse_sampling(self) -> str:
        """``"cosine"`` (the default: a lobe carrying cos θ_o) or ``"uniform"``
        (a lobe constant over the hemisphere, whose cosine-sampled weights
        1/cos θ_o would have infinite variance)."""
        return "cosine"

    def lit_from_behind(self) -> bool:
        """True if ``eval`` must see lights below the surface (the lobes then
        zero what must be zero); default False: the base zeroes them."""
        return False

    # --- lobes and flags ----------------------------------------------------------
    def update_lobes(self) -> None:
        """Declare exactly the lobes present: an absent lobe is never traced."""
        state, options = self.state, self.options
        state.switches = {p.name: v for p in state.params.values() if p.kind == "float"
                          for v in (0.0, 1.0) if self.off(p.name, v)}
        diffuse, specular = self.has_diffuse(), self.has_specular()
        state.compensation = None
        if getattr(options, "energy_compensation", False):
            ms = self.compensation()
            if diffuse if ms.lobe == "diffuse" else specular:
                state.compensation = ms
        components = []
        if diffuse:
            components.append(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
        if specular:
            components.append(mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide)
        flags = mi.BSDFFlags.Empty
        for c in components:
            flags |= c
        self.m_components, self.m_flags = components, flags
        state.index = {"diffuse": 0, "specular": len(components) - 1}
        # the plan first: the compensation's preparation evaluates the textures
        state.plan = Plan(Lobes(diffuse, specular, state.compensation is not None),
                          options.mode == "scanline", options.sampling == "cosine",
                          self.diffuse_sampling() == "uniform", self.lit_from_behind())
        if state.compensation is not None:
            self.m_ms = state.compensation.prepare(self)      # traversed with the plugin

    def trace_key(self) -> tuple:
        """The Python-side choices that decide what a call traces beyond the
        flags: the plan, the parameters folded as numbers and the compensation's
        own. A frozen function keys on it (:mod:`mi_brdfs.render.frozen`)."""
        ms = self.state.compensation
        return (self.state.plan, tuple(sorted(self.state.switches.items())),
                ms.key() if ms is not None else ())

    # --- attributes, as Mitsuba's BSDF base class answers them ----------------------
    # A texture parameter is looked up (eval, eval_1, eval_3); a plain number is an
    # attribute whose value only eval_attribute_1 returns (the others give 0, as
    # for a built-in's Float member); an unknown name gives 0 in JIT variants and
    # raises in scalar ones. Written here because in scalar variants the base
    # class sees a plain number as a Python float, not as a Float.
    def has_attribute(self, name, active=True):
        return mi.Bool(name in self.state.params)

    def eval_attribute(self, name, si, active=True):
        return self.attribute(name, si, active, "eval", mi.UnpolarizedSpectrum)

    def eval_attribute_1(self, name, si, active=True):
        return self.attribute(name, si, active, "eval_1", mi.Float)

    def eval_attribute_3(self, name, si, active=True):
        return self.attribute(name, si, active, "eval_3", mi.Color3f)

    def attribute(self, name, si, active, method: str, kind: type):
        p = self.state.params.get(name)
        if p is None:
            if not dr.is_jit_v(mi.Float):
                raise RuntimeError(f"[{type(self).__name__}] Invalid attribute requested {name}.")
            return dr.zeros(kind)
        value = getattr(self, "m_" + name)
        if p.kind != "float":
            return getattr(value, method)(si, active)
        return mi.Float(value) if kind is mi.Float else dr.zeros(kind)

    # --- description --------------------------------------------------------------
    def to_string(self):
        fields = ", ".join(f"{k}={v}" for k, v in self.describe().items())
        return f"{type(self).__name__}[mode={self.options.mode}, {fields}]"

    def describe(self) -> dict:
        fields = {o.name: getattr(self.options, o.name) for o in self.all_options()
                  if o.name != "mode"}
        fields.update({name: getattr(self, "m_" + name) for name in self.state.params})
        return fields


class Effective(NamedTuple):
    """What a model's parameter values look like (:meth:`BRDF.effective`)."""
    diffuse: list[float] | None
    specular: list[float] | None
    notes: tuple[str, ...] = ()


def rgb_list(value, scale: float = 1.0) -> list[float]:
    """A plain number or an RGB triple as an RGB list, times ``scale``."""
    channels = value if isinstance(value, (list, tuple)) else (value, value, value)
    return [float(c) * scale for c in channels]


def schlick(f0, c: float):
    """Schlick's F0 + (1 - F0)(1 - c)^5 of plain numbers (a number or a list)."""
    if isinstance(f0, (list, tuple)):
        return [schlick(x, c) for x in f0]
    return f0 + (1.0 - f0) * (1.0 - c) ** 5


class Box:
    """Scalar variants: a plain-number parameter held by a C++ object, so that
    ``mi.traverse`` hands it out as a Python float that can be written and
    updated, as a built-in's (``dielectric``'s ``eta``): its (pointer, type)
    as Mitsuba's own traversal reports them for a ``uniform`` texture's value."""

    def __init__(self, value: float):
        self.holder = create("uniform", {"value": float(value)})
        self.pointer, self.type = _pointer(self.holder, "value")

    def value(self) -> float:
        return float(mi.get_property(self.pointer, self.type, self.holder))


def _pointer(obj, name: str):
    """(pointer, type) of ``obj``'s parameter ``name``, as its traverse puts them."""
    found = {}

    class Catch(mi.TraversalCallback):
        def put(self, key, value, flags, cpptype=None):
            found[key] = (value, cpptype)

    catch = Catch()
    obj.traverse(catch)
    return found[name]


# ----------------------------------------------------------------------------
#  Registration
# ----------------------------------------------------------------------------

def register_plugin(cls: type) -> None:
    """Register ``cls`` under ``cls.name`` for the active variant."""
    bound = bind(cls)
    mi.register_bsdf(cls.name, lambda props: bound(props))
