"""What runs of each model: its cases, declared in its own module.

Every model's ``cases()`` (see :meth:`.base.BRDF.cases`) returns a :class:`Cases`: the
configurations the conformance battery runs it through (χ² of its sampler,
sample weight × pdf = eval, the white furnace, numerical extremes, gradients,
reciprocity), the lobe its plots show, the configurations the bench times and
compares with Mitsuba's built-ins, and the settings of its documentation's
pictures. The battery (``tests/bsdfs/test_battery.py``), ``mi-brdfs validate``,
``mi-brdfs bench``, the fit and the documentation read them from here; no
other module knows a model's configurations.

Configurations are plugin dictionaries (``mi.load_dict``). One without a
``mode`` runs in both modes where that makes sense (consistency, extremes);
one with a ``mode`` as given. Colours are white (1) where energy is measured,
so that the albedo is the fraction of light reflected.
"""
from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Callable

import mitsuba as mi
import numpy as np

HALF_PI = 0.5 * math.pi
THETAS_LOW = (0, 15, 30, 45, 60, 75)
THETAS_GRAZING = (80, 85, 88, 89)
THETAS_COMPENSATED = (0, 30, 60, 75, 85)      # where compensation promises albedo 1


@dataclass(frozen=True)
class Chi2:
    """A χ² test of the sampler against the pdf, at each incident angle."""
    config: dict
    thetas: tuple[float, ...] = (0, 45, 85)
    ires: int = 16                 # pdf sub-samples per cell and axis (sharp lobes: more)
    res: int = 201
    phi: float = 0.0               # the viewer's azimuth
    quick: bool = False            # in ``validate --quick``: representative of its model


@dataclass(frozen=True)
class Furnace:
    """The directional albedo of a white configuration must lie in [lo, hi]
    (± tol, the quadrature's error) at every incident angle (and azimuth)."""
    label: str
    config: dict
    lo: float = 0.0
    hi: float = 1.0
    tol: float = 3e-3
    thetas: tuple[float, ...] = THETAS_LOW + THETAS_GRAZING
    phis: tuple[float, ...] = (0.0,)
    points: int = 1024             # the quadrature's n x n strata


def preserves(label: str, config: dict, thetas=THETAS_COMPENSATED, value: float = 1.0,
              **kw) -> Furnace:
    """Albedo ``value`` within 1 % (energy preserving: 1 for a white surface,
    m_S for a compensated lobe of colour m_S, whose colour scales it linearly)."""
    return Furnace(label, config, lo=value, hi=value, tol=0.01 * value, thetas=thetas, **kw)


@dataclass(frozen=True)
class Twin:
    """The model configured as a Mitsuba built-in that computes the same BSDF
    (up to float error, or the built-in's own fits): tests, validation and
    the bench compare the two. ``floor``: the bench's bare-Python version of
    the built-in (``tools/bench/floor.py``), if any; ``spread(t)``: the
    parameters of the t-th of many materials (t in [0, 1]), for the bench's
    many-materials scene, the same for both."""
    label: str
    ours: dict
    builtin: dict
    floor: dict | None = None
    spread: Callable[[float], dict] | None = field(default=None, compare=False)


@dataclass(frozen=True)
class Pictures:
    """The renders of the plugin's documentation page: ``parameter`` swept over
    ``values`` on the configuration ``config`` (the rest at its defaults)."""
    parameter: str
    values: tuple
    config: dict = field(default_factory=dict)


@dataclass
class Cases:
    """Everything that runs of one model (see the module docstring)."""
    chi2: list[Chi2]
    consistency: list[dict]              # sample weight x pdf = eval
    furnace: list[Furnace]
    extremes: list[dict]                 # parameter extremes (directions are the battery's)
    interior: list[dict]                 # gradient checks: values away from clamps and kinks
    negative: tuple[dict, dict, float] | None = None   # (sampled, pdf, theta): must be rejected
    negative_phi: float = 0.0            # the viewer's azimuth in the negative control
    reciprocity: list[dict] = field(default_factory=list)   # beyond ``interior`` (hdr)
    lobe_width: float = 0.3              # where to put light directions for gradient checks
    lobe: dict | None = None             # the lobe plot's configuration (None: the defaults)
    report_furnace: list[tuple[str, dict]] | None = None   # the validation report's rows
    # --- the bench --------------------------------------------------------------------
    costs: list[tuple[str, dict]] | None = None    # (label, config) whose render cost the
                                                   # bench measures (None: the defaults)
    twins: list[Twin] = field(default_factory=list)
    related: list[tuple[str, dict, dict]] = field(default_factory=list)  # (label, ours,
                                                   # built-in): not the same BSDF, the nearest
    energy: list[tuple[str, dict]] = field(default_factory=list)   # compensation on vs off
    sampling: list[tuple[str, dict, list[tuple[str, dict]]]] = field(default_factory=list)
    lobes_off: list[tuple[str, dict, dict]] = field(default_factory=list)  # (label, a lobe
                                                   # switched off, the model without it)
    variants: list[tuple[str, dict]] = field(default_factory=list)   # (label, config) its
                                                   # options are compared on
    # --- the fit ------------------------------------------------------------------------
    fits: list[dict] = field(default_factory=list)   # parameter values a fit of the model
                                                   # to itself recovers: coloured, away from
                                                   # every bound (a hard step has no gradient)
    anisotropic: list[tuple[str, dict]] = field(default_factory=list)   # (the fit's name,
                                                   # its properties): what is fitted once more
                                                   # to an anisotropic target
    # --- the documentation ---------------------------------------------------------------
    pictures: Pictures | tuple[Pictures, ...] | None = None   # one row of renders each
    hdr_exposure: float = 0.0            # EV of its bundled scene's hdr render (README)
    mitsuba: tuple[str, ...] = ()        # Mitsuba's related plugins (links on the page)
    checked: str = ""                    # what it is checked against beyond the battery
                                         # (the README's table, Markdown)

    def picture_sets(self) -> list[Pictures]:
        """The page's sweeps of renders, each a :class:`Pictures`."""
        if self.pictures is None:
            return []
        return [self.pictures] if isinstance(self.pictures, Pictures) else list(self.pictures)


def rgb(c) -> dict:
    return {"type": "rgb", "value": list(map(float, c))}


def ramp(colours, filter_type: str = "bilinear") -> dict:
    """A 1-D ramp texture (one pixel high, left = cosine -1, right = +1)."""
    data = np.asarray(colours, dtype=np.float32)[None, :, :]
    return {"type": "bitmap", "bitmap": mi.Bitmap(data), "wrap_mode": "clamp",
            "filter_type": filter_type, "raw": True}


def label(config: dict) -> str:
    """A configuration's parameters as one line (a texture by its type)."""
    def shown(v):
        if isinstance(v, dict):
            return v["value"] if v.get("type") == "rgb" else v.get("type", "texture")
        return v
    return ", ".join(f"{k} = {shown(v)}" for k, v in config.items() if k != "type") or "defaults"


# ----------------------------------------------------------------------------
#  Every model's cases
# ----------------------------------------------------------------------------

_models: dict[str, type] = {}        # the registry's models by name (see use())
_built: dict[str, Cases] = {}


def use(models: dict[str, type]) -> None:
    """The registry (:mod:`mi_brdfs.bsdfs`) hands its models down, in its order."""
    _models.clear()
    _models.update(models)
    _built.clear()


def of(name: str) -> Cases:
    """The cases of plugin ``name``, built on first use (a model's own: a broken
    one fails its own model only)."""
    if name not in _built:
        _built[name] = _models[name].cases()
    return _built[name]


class _All(Mapping):
    """Every registered plugin's cases, in the registry's order, each built on
    first use (iterating the names builds nothing)."""

    def __getitem__(self, name: str) -> Cases:
        if name not in _models:
            raise KeyError(name)
        return of(name)

    def __iter__(self) -> Iterator[str]:
        return iter(_models)

    def __len__(self) -> int:
        return len(_models)


ALL: Mapping[str, Cases] = _All()


def promises_one(name: str, config: dict) -> bool:
    """True if ``name``'s furnace cases promise albedo 1 for this configuration
    (lo = hi = 1, e.g. :func:`preserves`), in hdr mode."""
    def hdr(c):
        return {**c, "mode": c.get("mode", "hdr")}
    return any(f.lo == f.hi == 1.0 and hdr(f.config) == hdr(config) for f in of(name).furnace)


def report_furnace(name: str) -> list[tuple[str, dict]]:
    """The validation report's furnace rows of a model: its own choice, or its
    first three uncompensated furnace cases (label, config)."""
    cases = of(name)
    if cases.report_furnace is not None:
        return cases.report_furnace
    rows = [(f.label, f.config) for f in cases.furnace]
    return [r for r in rows if not r[1].get("energy_compensation")][:3]


def report_chi2(quick: bool = False) -> dict[str, list[tuple[str, Chi2]]]:
    """The χ² tests of the validation report, (label, test) per model: every
    one (the battery's set), or with ``quick`` the ones marked representative."""
    return {name: [(label(c.config), c) for c in cases.chi2 if c.quick or not quick]
            for name, cases in ALL.items()}


def negative_controls() -> dict[str, tuple[dict, dict, float, float]]:
    """Negative controls of the χ² test: the sampler of one configuration
    against the pdf of a slightly different one, which the test must reject."""
    return {name: (*cases.negative, cases.negative_phi)
            for name, cases in ALL.items() if cases.negative}


def lobe_configs() -> dict[str, dict]:
    """Lobe plots: one representative, readable configuration per model."""
    return {name: cases.lobe or {"type": name} for name, cases in ALL.items()}


def costs() -> list[tuple[str, dict]]:
    """Every model and variant whose render cost the bench measures."""
    return [row for name, cases in ALL.items() for row in cases.costs or [(name, {"type": name})]]


def twins() -> list[Twin]:
    """Every model's twins (the model as a Mitsuba built-in computing the same BSDF)."""
    return [t for cases in ALL.values() for t in cases.twins]


def twin(label: str) -> Twin:
    """The twin of that label."""
    return next(t for t in twins() if t.label == label)


def every(part: str) -> list:
    """A list part of every model's cases, concatenated in the registry's order
    (e.g. ``every("energy")``: compensation on against off)."""
    return [row for cases in ALL.values() for row in getattr(cases, part)]
