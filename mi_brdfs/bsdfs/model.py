"""The model contract: what a course model supplies to the base, in one place.

A model is one module (``lambert.py``, ..., ``cook_torrance.py``): its pure
formulas, then a subclass of :class:`mi_brdfs.bsdfs.base.BRDF` that declares
its parameters and implements the hooks below, then its :class:`~.cases.Cases`
(what the tests, the validation report, the bench, the fit and the
documentation run of it). The base does everything else: reading and checking
the parameters, the two modes, which lobes a scene requires, the mixture of
the lobes, the BSDF interface, energy compensation.

Every hook is listed here with its inputs and outputs, and when it runs:

- **declared**: read from the class (no instance);
- **load**: once when the plugin is loaded, and again at ``params.update()``;
- **traced**: inside ``sample``/``eval``/``pdf``/``eval_pdf``, which Dr.Jit
  traces symbolically: Dr.Jit arithmetic only (no ``dr.any``, no printing, no
  NumPy), and masks with ``dr.select``; Python-side decisions may read only
  what was fixed at load time (options, the lobes present, ``self.switch``).

Local directions throughout: ``si.wi`` the viewer, ``wo`` the light, n = +z
(the shading frame; x = s, y = t).

A hook the base implements (its default is the behaviour described) needs no
override; the others a model with that lobe must implement.
"""
from __future__ import annotations

from typing import Any, ClassVar, Protocol

from .cases import Cases
from .compensation import AlbedoSpec, Compensation, WalkSpec
from .lobes import Scaled
from .params import Option, Param, Reader

Spectrum = Any           # an mi.UnpolarizedSpectrum (per colour channel)
Float = Any              # an mi.Float (one value per lane)
Inputs = Any             # the model's own namespace of evaluated textures (eval_textures)


class Model(Protocol):
    # --- declared ---------------------------------------------------------------
    name: ClassVar[str]
    """The plugin's name in scene files (``<bsdf type="NAME">``)."""
    PARAMS: ClassVar[tuple[Param, ...]]
    """Its parameters: colours, weights and shapes (:class:`.params.Param`)."""
    OPTIONS: ClassVar[tuple[Option, ...]]
    """Its choices (the base adds ``mode``, ``sampling`` and, for a model with
    :meth:`compensation`, ``energy_compensation``)."""
    reciprocal: ClassVar[bool]
    """hdr mode: f(ω_i, ω_o) = f(ω_o, ω_i) (the battery checks it). Default True."""

    @classmethod
    def cases(cls) -> Cases:
        """declared: the configurations the tests, the validation report, the
        bench, the fit and the documentation run (:mod:`.cases`)."""

    @classmethod
    def tables(cls) -> list[AlbedoSpec | WalkSpec]:
        """declared: the albedo tables its compensation reads (built offline by
        ``python -m mi_brdfs.tools.tables``). Default: none."""

    # --- load ---------------------------------------------------------------------
    def read(self, reader: Reader) -> None:
        """Read every parameter: ``self.read_param(reader, p)`` per Param (the
        default), with a model's own rules where parameters exclude each other
        or an option changes a range."""

    def has_diffuse(self) -> bool:
        """Whether the diffuse lobe can matter: use ``self.off(name)`` (a
        parameter that is the constant that switches the lobe off and cannot
        change). Default False."""

    def has_glossy(self) -> bool:
        """Whether the glossy lobe (the model's highlight) can matter. Default False."""

    def compensation(self) -> Compensation | None:
        """The multiple-scattering lobe of energy compensation (:mod:`.compensation`):
        a model that defines this hook has the option ``energy_compensation``."""

    def diffuse_sampling(self) -> str:
        """``"cosine"`` (the default: a lobe carrying cos θ_o) or ``"uniform"``
        (a lobe constant over the hemisphere, whose cosine-sampled weights
        1/cos θ_o would have infinite variance)."""

    def lit_from_behind(self) -> bool:
        """True if ``eval`` must see lights below the surface (the lobes then
        zero what must be zero); default False: the base zeroes them."""

    # --- traced -------------------------------------------------------------------
    def eval_textures(self, si, active) -> Inputs:
        """Every texture the lobes need, evaluated once per call at ``si``: a
        namespace of the model's own (``self.colours(si, active, **shape)``
        for a model with ``diffuse_reflectance`` and ``specular_reflectance``)."""

    def f_diffuse(self, inp: Inputs, si, wo) -> Spectrum | Scaled:
        """The diffuse lobe in eval convention (f·cos θ_o in hdr mode, the
        lecture's clamp(d·n) factor in scan-line mode), before the per-lobe
        clamp: a spectrum, or a colour times a shape (:class:`.lobes.Scaled`)."""

    def f_glossy(self, inp: Inputs, si, wo) -> Spectrum | Scaled:
        """The glossy lobe, likewise."""

    def lobe_weights(self, inp: Inputs) -> tuple[Any, Any]:
        """The factors multiplying the (clamped) diffuse and glossy lobes, e.g.
        Cook-Torrance's k and 1 - k; Python numbers where constant. Default (1, 1)."""

    def selection_weights(self, inp: Inputs, si) -> tuple[Float, Float]:
        """Estimates of each lobe's albedo (weights included): a sample picks a
        lobe in proportion. Default (1, 1)."""

    def sample_glossy(self, inp: Inputs, si, sample2) -> Any:
        """A light direction from the glossy lobe's own sampler."""

    def pdf_glossy(self, inp: Inputs, si, wo) -> Float:
        """The density of :meth:`sample_glossy` at ``wo``."""

    def f_pdf_glossy(self, inp: Inputs, si, wo) -> tuple[Spectrum | Scaled, Float]:
        """Both at once, where they share work. Default: the two hooks."""
