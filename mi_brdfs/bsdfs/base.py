"""The ``mi.BSDF`` glue every mi_brdfs plugin shares, written once.

A model subclasses :class:`BRDF` and supplies what :mod:`.model` lists (its
parameters, its lobes' formulas and samplers, its cases). This module does the
rest, alike for every model:

- **loading**: every option and parameter read and checked by
  :class:`.params.Reader` (one line naming the plugin, the parameter, the
  value and the valid range), the same checks again at ``params.update()``;
  ``traverse`` exposes every parameter as differentiable;
- **modes**: ``"scanline"`` clamps each lobe per colour channel to [0, 1]
  (the lecture's scan-line BRDFs), ``"hdr"`` keeps them unclamped;
- **model only what a scene requires**: a lobe whose colour or weight is the
  constant that switches it off (a colour 0, ``k`` = 0 or 1) is not declared
  in the flags and not traced. A parameter counts as switched off only while
  it is a constant, is not grad-enabled and was never changed through
  ``params.update()``; once updated or differentiated its lobe stays traced
  (a gradient at the bound 0 is then exact). The lobes are decided again in
  ``parameters_changed``;
- **the BSDF interface** over the lobes (:mod:`.lobes`): each lobe picked in
  proportion to an estimate of its albedo, ``pdf`` the exact mixture, the
  sample weight eval / pdf (or its closed form), the multiple-scattering lobe
  of energy compensation (:mod:`.compensation`) attached to the lobe it
  belongs to; a call traces only what it needs (Dr.Jit traces every material
  of a scene at every render, so each traced operation costs per material);
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

import drjit as dr
import mitsuba as mi
import numpy as np

from .._binding import bind, create
from .compensation import Compensation, ms_lobe
from .lobes import (ALL, ANY, DIFFUSE, GLOSSY, HORIZON, PDF_FLOOR, WEIGHT_MAX, Lobes, Plan,
                    Scaled, as_type, facing, mean, mixed, one, product, total, weighted)
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
        self.index = {"diffuse": 0, "glossy": 0}   # each lobe's component index


class BRDF:
    """Base of every mi_brdfs plugin (plain Python; bound onto a variant's
    ``mi.BSDF`` by :func:`register_plugin`). The hooks a model implements, and
    their defaults here: :mod:`.model`."""

    name = "brdf"                     # the registered plugin name
    OPTIONS: tuple[Option, ...] = ()
    PARAMS: tuple[Param, ...] = ()
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
        raise NotImplementedError(f"{cls.__name__} declares no cases() (see bsdfs/model.py)")

    @classmethod
    def tables(cls) -> list:
        return []

    # --- parameters ---------------------------------------------------------------
    def read(self, reader: Reader) -> None:
        for p in self.PARAMS:
            self.read_param(reader, p)

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

    def traverse(self, cb):
        for name in self.state.params:
            box = self.state.boxes.get(name)
            if box is None:
                cb.put(name, getattr(self, "m_" + name), mi.ParamFlags.Differentiable)
            else:
                cb.put(name, box.pointer, mi.ParamFlags.Differentiable, box.type)

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
        if name not in self.state.params or name in self.state.live:
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
        value = self.state.switches.get(name)
        return getattr(self, "m_" + name) if value is None else value

    def colours(self, si, active, **shape):
        """``eval_textures`` of a model with ``diffuse_reflectance`` and
        ``specular_reflectance``: its evaluated shape parameters (``shape``) and
        the lecture's m_D, m_S for the lobes present (``colour_d``, ``colour_s``)."""
        inp = Inputs(**shape)
        lobes = self.state.plan.lobes
        if lobes.diffuse:
            inp.colour_d = self.m_diffuse_reflectance.eval(si, active)
        if lobes.glossy:
            inp.colour_s = self.m_specular_reflectance.eval(si, active)
        return inp

    # --- the model's hooks: defaults (see bsdfs/model.py) -------------------------
    def has_diffuse(self) -> bool:
        return False

    def has_glossy(self) -> bool:
        return False

    def compensation(self) -> Compensation | None:
        return None

    def diffuse_sampling(self) -> str:
        return "cosine"

    def lit_from_behind(self) -> bool:
        return False

    def eval_textures(self, si, active):
        return Inputs()

    def lobe_weights(self, inp):
        return 1.0, 1.0

    def selection_weights(self, inp, si):
        return mi.Float(1.0), mi.Float(1.0)

    def f_pdf_glossy(self, inp, si, wo):
        return self.f_glossy(inp, si, wo), self.pdf_glossy(inp, si, wo)

    # --- lobes and flags ----------------------------------------------------------
    def update_lobes(self) -> None:
        """Declare exactly the lobes present: an absent lobe is never traced."""
        state, options = self.state, self.options
        state.switches = {p.name: v for p in state.params.values() if p.kind == "float"
                          for v in (0.0, 1.0) if self.off(p.name, v)}
        diffuse, glossy = self.has_diffuse(), self.has_glossy()
        state.compensation = None
        if getattr(options, "energy_compensation", False):
            ms = self.compensation()
            if diffuse if ms.lobe == "diffuse" else glossy:
                state.compensation = ms
        components = []
        if diffuse:
            components.append(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
        if glossy:
            components.append(mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide)
        flags = mi.BSDFFlags.Empty
        for c in components:
            flags |= c
        self.m_components, self.m_flags = components, flags
        state.index = {"diffuse": 0, "glossy": len(components) - 1}
        # the plan first: the compensation's preparation evaluates the textures
        state.plan = Plan(Lobes(diffuse, glossy, state.compensation is not None),
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

    def enabled(self, ctx) -> Lobes:
        """The lobes that exist and that ctx asks for."""
        lobes = self.state.plan.lobes
        if ctx.type_mask == ALL and ctx.component == ANY:         # (the usual context)
            return lobes
        index = self.state.index
        d = lobes.diffuse and ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, index["diffuse"])
        g = lobes.glossy and ctx.is_enabled(mi.BSDFFlags.GlossyReflection, index["glossy"])
        ms = self.state.compensation
        return Lobes(d, g, lobes.multiple and (g if ms.lobe == "glossy" else d))

    def inputs(self, si, active):
        """Everything a call needs at ``si``, each texture evaluated once: the
        model's inputs and, with compensation, (g(ω_i), G_avg, C)."""
        inp = self.eval_textures(si, active)
        ms = self.state.compensation
        if ms is None or not self.state.plan.lobes.multiple:
            return inp, None
        return inp, (ms.albedo(inp, si.wi, self.m_ms), ms.average(inp, self.m_ms),
                     ms.colour(inp))

    def probabilities(self, inp, ms, si, use: Lobes):
        """(p_d, p_g, p_ms): each used lobe picked in proportion to its weight;
        None when a single lobe is used (nothing to choose: nothing traced)."""
        count = sum(use)
        if count <= 1:
            return None
        w_d, w_g = self.selection_weights(inp, si)
        w_ms = mi.Float(0.0)
        if use.multiple:
            g_i, _, colour = ms
            w = self.lobe_weights(inp)[0 if self.state.compensation.lobe == "diffuse" else 1]
            w_ms = w * mean(colour) * g_i
        weights = [w if u else mi.Float(0.0) for u, w in zip(use, (w_d, w_g, w_ms))]
        total_w = weights[0] + weights[1] + weights[2]
        ok = total_w > 0
        inv = 1.0 / dr.select(ok, total_w, 1.0)
        return tuple(dr.select(ok, w * inv, (1.0 / count) if u else 0.0)
                     for u, w in zip(use, weights))

    # --- the BSDF interface -------------------------------------------------------
    # Each call traces only what it needs: a single lobe is sampled by its own
    # sampler with nothing to pick, and a lobe's value stays colour · shape
    # (Scaled) until the end, so that masks, weights and guards act on one
    # Float per lane. A viewer below (or on) the surface gets no reflection.
    def sample(self, ctx, si, sample1, sample2, active=True):
        sample1, sample2 = as_type(sample1, mi.Float), as_type(sample2, mi.Point2f)
        use = self.enabled(ctx)
        if not any(use):
            return dr.zeros(mi.BSDFSample3f), self.spectrum(mi.UnpolarizedSpectrum(0.0))
        plan = self.state.plan
        active = facing(si, active)
        inp, ms = self.inputs(si, active)
        probs = self.probabilities(inp, ms, si, use)
        modelled = False                 # wo from the model's own sampler (else a warp of sample2)
        if probs is None:              # one lobe, its own sampler (or cosine): nothing to pick
            glossy = use.glossy                              # a Python constant
            if plan.cosine or not (use.glossy or plan.uniform):
                wo = mi.warp.square_to_cosine_hemisphere(sample2)
            elif use.glossy:
                wo, modelled = self.sample_glossy(inp, si, sample2), True
            else:
                wo = mi.warp.square_to_uniform_hemisphere(sample2)
            own = not plan.cosine or not (use.glossy or plan.uniform)
        else:
            # Pick a lobe (comparisons, not ~: scalar variants' masks are Python bools).
            p_d, p_g, _ = probs
            wo = mi.warp.square_to_cosine_hemisphere(sample2)      # diffuse and multiple
            if not plan.cosine:
                if use.diffuse and plan.uniform:
                    wo = dr.select(mi.Bool(sample1 < p_d),
                                   mi.warp.square_to_uniform_hemisphere(sample2), wo)
                if use.glossy:
                    pick_g = (mi.Bool(sample1 >= p_d) & (sample1 < p_d + p_g)) if use.multiple \
                        else mi.Bool(sample1 >= p_d)
                    wo = dr.select(pick_g, self.sample_glossy(inp, si, sample2), wo)
                    modelled = True
            # the multiple-scattering lobe counts as the kind of the lobe it belongs to
            glossy = (mi.Bool(sample1 >= p_d) & (sample1 < p_d + p_g)) \
                if use.multiple and self.state.compensation.lobe == "diffuse" \
                else mi.Bool(sample1 >= p_d)
            own = False

        # The sampled direction is a fixed point for the derivatives (as Mitsuba's
        # differentiable integrators treat it): the weight's gradient is that of
        # eval/pdf there, not of the sampler's warping (which depends on the
        # parameters: a warp of sample2 does not).
        if modelled and dr.grad_enabled(wo):
            wo = dr.detach(wo)
        values, pdf, up = self.lobes(use, probs, inp, ms, si, wo, active)
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
        index = self.state.index
        if type(glossy) is bool:                       # the picked lobe is known
            bs.sampled_type = mi.UInt32(GLOSSY if glossy else DIFFUSE)
            bs.sampled_component = mi.UInt32(index["glossy"] if glossy else index["diffuse"])
        else:
            bs.sampled_type = dr.select(glossy, mi.UInt32(GLOSSY), mi.UInt32(DIFFUSE))
            bs.sampled_component = dr.select(glossy, mi.UInt32(index["glossy"]),
                                             mi.UInt32(index["diffuse"]))
        if type(weight) is not mi.UnpolarizedSpectrum:
            weight = mi.UnpolarizedSpectrum(weight)
        return bs, self.spectrum(weight)

    def eval(self, ctx, si, wo, active=True):
        wo = as_type(wo, mi.Vector3f)
        use = self.enabled(ctx)
        if not any(use):
            return self.spectrum(mi.UnpolarizedSpectrum(0.0))
        active = facing(si, active)
        inp, ms = self.inputs(si, active)
        values, _, up = self.lobes(use, None, inp, ms, si, wo, active, pdf=False)
        return self.spectrum(total(values, active if self.state.plan.behind else up))

    def pdf(self, ctx, si, wo, active=True):
        wo = as_type(wo, mi.Vector3f)
        use = self.enabled(ctx)
        if not any(use):
            return mi.Float(0.0)
        active = facing(si, active)
        inp, ms = self.inputs(si, active)
        return self.lobes(use, self.probabilities(inp, ms, si, use), inp, ms, si, wo, active,
                          value=False)[1]

    def eval_pdf(self, ctx, si, wo, active=True):
        wo = as_type(wo, mi.Vector3f)
        use = self.enabled(ctx)
        if not any(use):
            return self.spectrum(mi.UnpolarizedSpectrum(0.0)), mi.Float(0.0)
        active = facing(si, active)
        inp, ms = self.inputs(si, active)
        values, pdf, up = self.lobes(use, self.probabilities(inp, ms, si, use), inp, ms, si, wo,
                                     active)
        return self.spectrum(total(values, active if self.state.plan.behind else up)), pdf

    # --- the lobes, summed --------------------------------------------------------
    def lobes(self, use: Lobes, probs, inp, ms, si, wo, active, value=True, pdf=True):
        """(values, pdf, up) of the used lobes at wo, ``active`` holding the
        viewer above the surface: ``values`` the list of the lobes' weighted
        values (:func:`.lobes.weighted`; summed and masked by
        :func:`.lobes.total`), ``pdf`` the mixture of the lobes' samplers with
        the selection probabilities ``probs`` (None: a single lobe's own
        density), 0 where the light is below the surface; ``up`` where it is
        above. Either of the first two is None when not asked for."""
        plan = self.state.plan
        up = active & (wo.z > HORIZON)
        w_d, w_g = self.lobe_weights(inp) if value else (None, None)
        values = [] if value else None
        p = None
        lobe_pdfs = pdf
        if pdf and plan.cosine:
            p, lobe_pdfs = mi.warp.square_to_cosine_hemisphere_pdf(wo), False
        p_d, p_g, p_ms = probs if probs is not None else (1.0, 1.0, 1.0)
        if use.diffuse:
            if value:
                values.append(weighted(self.f_diffuse(inp, si, wo), w_d, plan.scanline))
            if lobe_pdfs:
                p = mixed(p, p_d, mi.warp.square_to_uniform_hemisphere_pdf(wo) if plan.uniform
                          else mi.warp.square_to_cosine_hemisphere_pdf(wo))
        if use.glossy:
            if value and lobe_pdfs:
                f_g, p_g_wo = self.f_pdf_glossy(inp, si, wo)
                values.append(weighted(f_g, w_g, plan.scanline))
                p = mixed(p, p_g, p_g_wo)
            elif value:
                values.append(weighted(self.f_glossy(inp, si, wo), w_g, plan.scanline))
            elif lobe_pdfs:
                p = mixed(p, p_g, self.pdf_glossy(inp, si, wo))
        if use.multiple:                 # hdr only
            if value:
                g_i, g_avg, colour = ms
                g_o = self.state.compensation.albedo(inp, wo, self.m_ms)
                f_ms = ms_lobe(colour, g_i, g_o, g_avg, mi.Frame3f.cos_theta(wo))
                values.append(weighted(f_ms, w_d if self.state.compensation.lobe == "diffuse"
                                       else w_g, False))
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


class Inputs:
    """A model's evaluated textures at one call (its own fields: the base reads none)."""

    def __init__(self, **fields):
        self.__dict__.update(fields)


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
