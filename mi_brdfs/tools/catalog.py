"""The configurations the tests, the validation report and the benchmarks run, in one place.

Each plugin of the registry (:data:`mi_brdfs.bsdfs.PLUGINS`) has an
:class:`Entry`, made by the function that :func:`builds` it: the conformance
battery (``tests/bsdfs/test_battery.py``) runs every plugin through it — χ² of
the sampler, weight × pdf = eval, the white furnace, the numerical extremes,
gradients, bad input — and the lobe plots and the benchmarks' model costs come
from it too, so adding a model means adding its entry here (see
CONTRIBUTING.md). Entries are built on first use (:func:`entry`), one model at
a time: a broken entry is an error for its own model only. Configurations are
plugin dictionaries; one without a ``mode`` is run in both modes where that
makes sense (consistency, extremes), one with a ``mode`` as given. Colours are
white (1) where energy is measured, so the albedo is the fraction of light
reflected.

``mi-brdfs validate`` shows the configurations of :data:`FURNACE`,
:func:`report_chi2` (every χ² test of the battery; the representative ones
with ``--quick``), :data:`NEGATIVE` and :data:`LOBES`; ``mi-brdfs bench`` runs
:func:`bench_models` and the ``BENCH_*`` configurations at the end of this module.
"""
from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Callable

from ..bsdfs import BY_NAME

HALF_PI = 0.5 * math.pi
DISTRIBUTIONS = ("blinn", "beckmann", "ggx")
GEOMETRIES = ("cook_torrance", "smith")
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


@dataclass
class Entry:
    """Everything the battery runs for one plugin."""
    chi2: list[Chi2]
    consistency: list[dict]              # sample weight x pdf = eval
    furnace: list[Furnace]
    extremes: list[dict]                 # parameter extremes (directions are the battery's)
    interior: list[dict]                 # gradient checks: values away from clamps and kinks
    negative: tuple[dict, dict, float] | None = None   # (sampled, pdf, theta): must be rejected
    reciprocity: list[dict] = field(default_factory=list)   # beyond ``interior`` (hdr)
    lobe_width: float = 0.3              # where to put light directions for gradient checks
    extra: dict = field(default_factory=dict)
    lobe: dict | None = None             # the lobe plot's configuration (None: the defaults)
    bench: list[tuple[str, dict]] | None = None   # (label, config) whose render cost the
                                                  # bench compares (None: the defaults)


BUILDERS: dict[str, Callable[[str], Entry]] = {}      # plugin name -> what builds its entry
_BUILT: dict[str, Entry] = {}


def builds(*names: str):
    """Decorator: the function (called with the plugin's name) makes the Entry
    of each of these plugins."""
    def register(builder: Callable[[str], Entry]):
        for name in names:
            BUILDERS[name] = builder
            _BUILT.pop(name, None)
        return builder
    return register


def entry(name: str) -> Entry:
    """The Entry of plugin ``name``, built on first use."""
    if name not in _BUILT:
        if name not in BUILDERS:
            raise LookupError(f"plugin {name!r} has no catalog entry: add a function "
                              f"@builds({name!r}) to mi_brdfs/tools/catalog.py (CONTRIBUTING.md)")
        _BUILT[name] = BUILDERS[name](name)
    return _BUILT[name]


class _Entries(Mapping):
    """Every registered plugin's Entry, in the registry's order, each built on
    first use (so that iterating the names builds nothing)."""

    def __getitem__(self, name: str) -> Entry:
        if name not in BY_NAME:
            raise KeyError(name)
        return entry(name)

    def __iter__(self) -> Iterator[str]:
        return iter(BY_NAME)

    def __len__(self) -> int:
        return len(BY_NAME)


ENTRIES: Mapping[str, Entry] = _Entries()


def rgb(c) -> dict:
    return {"type": "rgb", "value": list(map(float, c))}


def toon_ramp(colours, filter_type: str = "bilinear") -> dict:
    """A 1-D ramp texture (one pixel high, left = cosine -1, right = +1)."""
    import mitsuba as mi
    import numpy as np
    data = np.asarray(colours, dtype=np.float32)[None, :, :]
    return {"type": "bitmap", "bitmap": mi.Bitmap(data), "wrap_mode": "clamp",
            "filter_type": filter_type, "raw": True}


# ----------------------------------------------------------------------------
#  lambert
# ----------------------------------------------------------------------------

@builds("lambert")
def _lambert(name: str) -> Entry:
    return Entry(
        chi2=[Chi2({"type": "lambert", "mode": m}, (0, 85), quick=m == "hdr")
              for m in ("hdr", "scanline")],
        consistency=[{"type": "lambert"},
                     {"type": "lambert", "mode": "scanline", "reflectance": rgb([1.7, 0.6, 0.2])}],
        furnace=[Furnace("m_D = 1", {"type": "lambert", "reflectance": 1.0}, lo=1.0, hi=1.0,
                         tol=0.01)],
        extremes=[{"type": "lambert"}, {"type": "lambert", "reflectance": 0.0}],
        interior=[{"type": "lambert", "reflectance": 0.4}],
        lobe={"type": "lambert", "reflectance": 0.8},
        bench=[("lambert", {"type": "lambert", "reflectance": 0.6})],
    )


# ----------------------------------------------------------------------------
#  oren_nayar
# ----------------------------------------------------------------------------

@builds("oren_nayar")
def _oren_nayar(name: str) -> Entry:
    on = {"type": "oren_nayar"}
    eon = {**on, "energy_compensation": True}
    return Entry(
        chi2=[Chi2({**on, "sigma": s, "method": m}, res=101, quick=s == 0.5)
              for s, m in [(0.0, "exact"), (0.5, "table"), (HALF_PI, "exact")]]
        + [Chi2({**on, "sigma": 1.0, "mode": "scanline", "reflectance": rgb([2.0, 0.5, 0.1])},
                (60,), res=101),
           Chi2({**eon, "sigma": 0.8, "reflectance": rgb([0.9, 0.5, 0.2])}, (0, 60), res=101)],
        consistency=[{**on, "sigma": 0.7}, {**on, "sigma": HALF_PI, "method": "table"},
                     {**on, "sigma": 0.4, "mode": "scanline", "reflectance": rgb([1.8, 0.6, 0.2])},
                     {**eon, "sigma": 1.2, "reflectance": rgb([0.9, 0.5, 0.2])}],
        furnace=[Furnace("σ = 0", {**on, "reflectance": 1.0, "sigma": 0.0}, lo=1.0, tol=0.01),
                 # the lecture's qualitative model: below 1 except near grazing at small σ
                 Furnace("σ = 0.2 (exceeds 1 near grazing: the model's own)",
                         {**on, "reflectance": 1.0, "sigma": 0.2}, hi=1.03),
                 Furnace("σ = π/2", {**on, "reflectance": 1.0, "sigma": HALF_PI})]
        + [preserves(f"EON, σ = {s:g}", {**eon, "reflectance": 1.0, "sigma": s})
           for s in (0.0, 0.2, 0.8, HALF_PI)],
        extremes=[{**on, "sigma": s, "method": m} for s in (0.0, HALF_PI)
                  for m in ("exact", "table")]
        + [{**eon, "sigma": s} for s in (0.0, HALF_PI)],
        interior=[{**on, "sigma": 0.4, "reflectance": 0.6, "method": m}
                  for m in ("exact", "table")]
        + [{**eon, "sigma": 0.4, "reflectance": 0.6}],
        reciprocity=[{**on, "sigma": s, "method": m, "reflectance": rgb([0.9, 0.5, 0.2])}
                     for m in ("exact", "table") for s in (0.3, 1.2)]
        + [{**eon, "sigma": s, "reflectance": rgb([0.9, 0.5, 0.2])} for s in (0.3, 1.2)],
        lobe={**on, "reflectance": 0.8, "sigma": 0.8},
        bench=[(f"oren_nayar {m}", {**on, "sigma": 0.5, "method": m}) for m in ("exact", "table")],
    )


# ----------------------------------------------------------------------------
#  toon
# ----------------------------------------------------------------------------

TOON_RAMP = [[0.1, 0.1, 0.1], [0.4, 0.3, 0.2], [1.0, 0.9, 0.8]]
TOON_SPEC_RAMP = [[0.2, 0.2, 0.2]] * 3 + [[1.5, 1.5, 1.5]]


def _toon_chi2_configs() -> list[dict]:
    configs = []
    for m in ("phong", "blinn"):
        t = {"type": "toon", "specular_model": m}
        configs += [
            t,
            {**t, "smoothness": 0.2, "specular_shade": 0.3, "specular_threshold": 0.7},
            {**t, "specular_threshold": 0.97, "diffuse_reflectance": 0.0, "diffuse_shade": 0.0},
            {**t, "specular_threshold": 0.2, "smoothness": 1.0, "diffuse_reflectance": 0.0,
             "diffuse_shade": 0.0},
        ]
    configs.append({"type": "toon", "diffuse_ramp": toon_ramp(TOON_RAMP),
                    "specular_ramp": toon_ramp(TOON_SPEC_RAMP), "specular_model": "blinn"})
    configs.append({"type": "toon", "mode": "scanline", "diffuse_reflectance": rgb([1.5, 0.5, 0.2]),
                    "specular_reflectance": 3.0, "specular_threshold": 0.8})
    return configs


@builds("toon")
def _toon(name: str) -> Entry:
    t = {"type": "toon"}
    chi2_configs = _toon_chi2_configs()
    return Entry(
        chi2=[Chi2(c, (0, 30, 60, 85), ires=32,
                   quick=c == {**t, "specular_model": "phong"} or "diffuse_ramp" in c)
              for c in chi2_configs],
        consistency=chi2_configs + [{**t, "specular_threshold": 1.0},
                                    {**t, "smoothness": 2.0, "specular_shade": 0.1}],
        furnace=[
            # hdr: each lobe reflects at most its brightest colour (here 0.8 + 1)
            Furnace("defaults", dict(t), hi=1.8),
            Furnace("defaults, blinn", {**t, "specular_model": "blinn"}, hi=1.8),
            Furnace("white diffuse only: exactly 1", {**t, "diffuse_reflectance": 1.0,
                                                      "diffuse_shade": 1.0,
                                                      "specular_reflectance": 0.0},
                    lo=1.0, hi=1.0, tol=0.01),
        ],
        extremes=[dict(t, specular_model=m, mode=mode, smoothness=w, diffuse_threshold=td,
                       specular_threshold=ts, specular_shade=ss)
                  for m in ("phong", "blinn") for mode in ("hdr", "scanline") for w in (0.0, 2.0)
                  for td, ts in ((0.5, 0.9), (-1.0, 1.0), (1.0, -1.0), (0.0, 0.0))
                  for ss in (0.0, 0.4)],
        interior=[dict(t, specular_model=m, diffuse_reflectance=0.7, diffuse_shade=0.25,
                       diffuse_threshold=0.4, specular_reflectance=0.9, specular_shade=0.1,
                       specular_threshold=0.6, smoothness=0.3) for m in ("phong", "blinn")],
        negative=({**t, "diffuse_reflectance": 0.0, "diffuse_shade": 0.0,
                   "specular_threshold": 0.95},
                  {**t, "diffuse_reflectance": 0.0, "diffuse_shade": 0.0,
                   "specular_threshold": 0.94}, 30),
        lobe_width=0.6,
        lobe={**t, "smoothness": 0.1},
        bench=[("toon", dict(t)),
               ("toon with ramps", {**t, "diffuse_ramp": toon_ramp([[0.1] * 3, [0.1] * 3,
                                                                    [0.4] * 3, [0.8] * 3]),
                                    "specular_ramp": toon_ramp([[0.0] * 3] * 7 + [[1.0] * 3])})],
    )


# ----------------------------------------------------------------------------
#  phong and blinn
# ----------------------------------------------------------------------------

@builds("phong", "blinn")
def _exponent_model(name: str) -> Entry:
    b = {"type": name}
    chi2 = [Chi2({**b, "exponent": g, "diffuse_reflectance": m_d}, (0, 30, 60, 85), ires=64,
                 quick=(g, m_d) in ((100.0, 0.5), (1e3, 0.0)))
            for g in (0.0, 1.0, 10.0, 100.0, 1e3) for m_d in (0.0, 0.5)]
    chi2 += [Chi2({**b, "exponent": 1e4, "diffuse_reflectance": 0.0}, (30, 60, 85), ires=64),
             # scanline weights pick the lobes differently; coloured lobes
             Chi2({**b, "mode": "scanline", "exponent": 10.0,
                   "diffuse_reflectance": rgb([1.5, 0.3, 0.0]),
                   "specular_reflectance": rgb([0.9, 0.9, 2.0])}, (45,), ires=64),
             Chi2({**b, "mode": "scanline", "exponent": 200.0}, (70,), ires=64),
             # a textured exponent (looked up at uv = 0.5, 0.5)
             Chi2({**b, "exponent": {"type": "checkerboard", "color0": 5.0, "color1": 50.0}},
                  (20,), ires=64),
             # the compensation lobe, sampled in proportion to its weight
             Chi2({**b, "exponent": 20.0, "diffuse_reflectance": 0.2,
                   "energy_compensation": True}, (0, 60), ires=64)]
    white = {**b, "diffuse_reflectance": 0.0, "specular_reflectance": 1.0}
    return Entry(
        chi2=chi2,
        consistency=[{**b, "exponent": 0.0}, {**b, "exponent": 1.0},
                     {**b, "exponent": 50.0, "diffuse_reflectance": 0.0}, {**b, "exponent": 1e4},
                     {**b, "exponent": 1e6, "diffuse_reflectance": 0.0},
                     {**b, "mode": "scanline", "exponent": 30.0,
                      "diffuse_reflectance": rgb([1.5, 0.3, 0.0]),
                      "specular_reflectance": rgb([0.9, 0.9, 2.0])},
                     {**b, "specular_reflectance": 0.0},
                     {**b, "exponent": 8.0, "energy_compensation": True,
                      "specular_reflectance": rgb([0.9, 0.6, 0.3]), "diffuse_reflectance": 0.1}],
        furnace=[Furnace("m_D = 0, m_S = 1, γ = 1", {**white, "exponent": 1.0}),
                 Furnace("m_D = 0.5, m_S = 0.5, γ = 50",
                         {**b, "diffuse_reflectance": 0.5, "specular_reflectance": 0.5,
                          "exponent": 50.0})]
        + [preserves(f"compensated, γ = {g:g}", {**white, "exponent": g,
                                                  "energy_compensation": True},
                     points=2048 if g >= 1e3 else 1024)
           for g in (1.0, 10.0, 100.0, 1e4)]
        + [preserves(f"compensated, m_S = 0.5, γ = {g:g}: reflects 0.5",
                     {**white, "specular_reflectance": 0.5, "exponent": g,
                      "energy_compensation": True}, value=0.5) for g in (10.0, 100.0)],
        extremes=[{**b, "exponent": g, "mode": mode, "diffuse_reflectance": m_d,
                   "specular_reflectance": m_s}
                  for g in (0.0, 1.0, 1e4, 1e6, 1e8) for mode in ("hdr", "scanline")
                  for m_d, m_s in ((0.5, 0.5), (0.0, 1.0), (1.0, 0.0))]
        + [{**b, "exponent": g, "energy_compensation": True} for g in (0.0, 1e8)],
        interior=[{**b, "diffuse_reflectance": 0.4, "specular_reflectance": 0.6,
                   "exponent": 20.0},
                  {**b, "diffuse_reflectance": 0.4, "specular_reflectance": 0.6,
                   "exponent": 20.0, "energy_compensation": True}],
        negative=({**b, "diffuse_reflectance": 0.0, "exponent": 100.0},
                  {**b, "diffuse_reflectance": 0.0, "exponent": 110.0}, 30),
        lobe_width=0.25,
        reciprocity=[{**b, "diffuse_reflectance": rgb([1.4, 0.5, 0.2]), "exponent": g,
                      "specular_reflectance": rgb([0.9, 2.0, 0.3])}
                     for g in (0.0, 1.0, 30.0, 1e3)],
        lobe={**b, "diffuse_reflectance": 0.3, "specular_reflectance": 0.6, "exponent": 30},
        bench=[(name, {**b, "exponent": 50})],
    )


# ----------------------------------------------------------------------------
#  ward
# ----------------------------------------------------------------------------

WARD_ALPHAS = [(1e-3, 0.5), (0.5, 1e-3), (0.0, 0.0), (1e-4, 1e-4), (1.0, 1.0), (0.2, 0.2)]


@builds("ward")
def _ward(name: str) -> Entry:
    w = {"type": "ward"}
    # viewers at azimuth 30°, not along t or b: the anisotropic lobe is asymmetric
    chi2 = [Chi2({**w, "alpha_u": at, "alpha_v": ab, "diffuse_reflectance": m_d},
                 (0, 30, 60, 85), phi=30.0,
                 quick=(at, ab, m_d) in ((0.05, 0.3, 0.5), (0.05, 0.05, 0.0)))
            for at, ab in ((0.1, 0.1), (0.05, 0.3), (0.3, 0.05), (0.5, 0.5), (0.05, 0.05))
            for m_d in (0.0, 0.5)]
    chi2 += [Chi2({**w, "alpha_u": 0.15, "alpha_v": 0.04, "mode": "scanline",
                   "formula": "angles", "diffuse_reflectance": rgb([0.9, 0.2, 0.1]),
                   "specular_reflectance": rgb([1.5, 0.5, 0.5])}, (45,), phi=30.0),
             Chi2({**w, "alpha": 0.2, "formula": "angles"}, (75,), phi=30.0),
             Chi2({**w, "alpha_u": 0.1, "alpha_v": 0.3, "energy_compensation": True,
                   "diffuse_reflectance": 0.2}, (0, 60), phi=30.0)]
    white = {**w, "diffuse_reflectance": 0.0, "specular_reflectance": 1.0}
    return Entry(
        chi2=chi2,
        consistency=[dict(w), {**w, "alpha_u": 0.05, "alpha_v": 0.4, "diffuse_reflectance": 0.0},
                     {**w, "alpha_u": 1e-3, "alpha_v": 0.5, "formula": "angles"},
                     {**w, "alpha": 0.7, "diffuse_reflectance": 0.3, "specular_reflectance": 0.7},
                     {**w, "mode": "scanline", "alpha_u": 0.2, "alpha_v": 0.05,
                      "diffuse_reflectance": rgb([1.5, 0.3, 0.0]),
                      "specular_reflectance": rgb([0.9, 0.9, 2.0])},
                     {**w, "alpha_u": 0.05, "alpha_v": 0.3, "energy_compensation": True}],
        furnace=[Furnace("m_S = 1, α 0.2 × 0.2", {**white, "alpha": 0.2},
                         thetas=THETAS_LOW + (80, 85, 88)),
                 Furnace("m_S = 1, α 0.05 × 0.3", {**white, "alpha_u": 0.05, "alpha_v": 0.3},
                         thetas=THETAS_LOW + (80, 85, 88), phis=(0.0, 90.0))]
        + [preserves(f"compensated, α {label}", {**white, **alpha, "energy_compensation": True},
                     phis=(0.0, 90.0) if "alpha_u" in alpha else (0.0,))
           for label, alpha in (("0.05", {"alpha": 0.05}), ("0.3", {"alpha": 0.3}),
                                ("0.05 × 0.3", {"alpha_u": 0.05, "alpha_v": 0.3}),
                                ("2 (beyond 1)", {"alpha": 2.0}),
                                ("0.3 × 3 (beyond 1)", {"alpha_u": 0.3, "alpha_v": 3.0}))]
        + [preserves("compensated, m_S = 0.5, α 0.3: reflects 0.5",
                     {**white, "specular_reflectance": 0.5, "alpha": 0.3,
                      "energy_compensation": True}, value=0.5)],
        extremes=[{**w, "alpha_u": at, "alpha_v": ab, "mode": mode, "formula": formula,
                   "diffuse_reflectance": m_d, "specular_reflectance": 1.0}
                  for at, ab in WARD_ALPHAS for mode in ("hdr", "scanline")
                  for formula in ("vectors", "angles") for m_d in (0.0, 0.5)]
        + [{**w, "alpha_u": at, "alpha_v": ab, "energy_compensation": True}
           for at, ab in WARD_ALPHAS],
        interior=[{**w, "alpha_u": 0.15, "alpha_v": 0.3, "diffuse_reflectance": 0.5,
                   "specular_reflectance": 0.7, "formula": f} for f in ("vectors", "angles")]
        + [{**w, "alpha": 0.2, "diffuse_reflectance": 0.5, "specular_reflectance": 0.7},
           {**w, "alpha_u": 0.15, "alpha_v": 0.3, "diffuse_reflectance": 0.5,
            "specular_reflectance": 0.7, "energy_compensation": True}],
        negative=({**w, "alpha_u": 0.05, "alpha_v": 0.3, "diffuse_reflectance": 0.0},
                  {**w, "alpha_u": 0.05, "alpha_v": 0.315, "diffuse_reflectance": 0.0}, 45),
        extra={"negative_phi": 30.0},
        lobe_width=0.3,
        reciprocity=[{**w, "alpha_u": 0.05, "alpha_v": 0.3, "formula": f,
                      "diffuse_reflectance": rgb([0.5, 0.2, 0.1])} for f in ("vectors", "angles")]
        + [{**w, "alpha": 0.3, "energy_compensation": True}],
        lobe={**w, "diffuse_reflectance": 0.3, "specular_reflectance": 0.6, "alpha_u": 0.1,
              "alpha_v": 0.3},
        bench=[(f"ward {f}", {**w, "alpha_u": 0.1, "alpha_v": 0.3, "formula": f})
               for f in ("vectors", "angles")],
    )


# ----------------------------------------------------------------------------
#  cook_torrance
# ----------------------------------------------------------------------------

@builds("cook_torrance")
def _cook_torrance(name: str) -> Entry:
    c = {"type": "cook_torrance"}
    chi2 = [Chi2({**c, "distribution": d, "alpha": a, "k": k}, (0, 45, 85),
                 quick=(d, a, k) in (("ggx", 0.1, 0.5), ("beckmann", 0.5, 0.0)))
            for d in DISTRIBUTIONS for a in (0.1, 0.5) for k in (0.0, 0.5)]
    chi2 += [
        # The Smith term and the scanline clamp change the weights, not the sampler.
        Chi2({**c, "distribution": "ggx", "alpha": 0.5, "k": 0.0, "geometry": "smith"}, (60,)),
        Chi2({**c, "distribution": "beckmann", "alpha": 0.1, "k": 0.5, "geometry": "smith"},
             (85,)),
        Chi2({**c, "distribution": "blinn", "alpha": 0.3, "k": 0.5, "geometry": "smith",
              "mode": "scanline", "diffuse_reflectance": rgb([0.9, 0.2, 0.1]), "f0": 0.5}, (30,)),
        # The other samplers: full-distribution microfacet sampling and cosine sampling.
        *[Chi2({**c, "distribution": d, "alpha": 0.3, "k": 0.3, "sample_visible": False}, (60,))
          for d in ("beckmann", "ggx")],
        Chi2({**c, "distribution": "ggx", "alpha": 0.3, "k": 0.3, "sampling": "cosine"}, (45,)),
        # The compensation lobe, picked in proportion to its weight.
        Chi2({**c, "distribution": "ggx", "geometry": "smith", "alpha": 0.6, "k": 0.0,
              "energy_compensation": True}, (0, 45, 85)),
        Chi2({**c, "distribution": "blinn", "alpha": 0.8, "k": 0.3,
              "energy_compensation": True}, (60,)),
    ]
    # As a perfect conductor (k = 0, F0 = 1, Smith: roughconductor's lobe), at the
    # settings of Mitsuba 3.9.1's own roughconductor χ² tests: a viewer along
    # (1, 1, 1) (θ = 54.74°, φ = 45°), α 0.05 at res 140, ires 32; both samplers of
    # Beckmann and GGX at α 0.2 and 0.05 (the axes of its anisotropic lobe; ours is
    # isotropic), res 101, ires 16 (Beckmann) and 8 (GGX).
    conductor = {**c, "k": 0.0, "f0": 1.0, "geometry": "smith"}
    diagonal = math.degrees(math.acos(1.0 / math.sqrt(3.0)))
    chi2 += [Chi2({**conductor, "distribution": "beckmann", "alpha": 0.05}, (diagonal,), phi=45.0,
                  res=140, ires=32)]
    chi2 += [Chi2({**conductor, "distribution": d, "alpha": a, "sample_visible": v}, (diagonal,),
                  phi=45.0, res=101, ires=16 if d == "beckmann" else 8)
             for d in ("beckmann", "ggx") for v in (False, True) for a in (0.2, 0.05)]
    consistency = [{**c, "distribution": d, "geometry": g, "alpha": a, "k": k}
                   for d in DISTRIBUTIONS for g in GEOMETRIES
                   for a, k in ((0.1, 0.0), (0.5, 0.5), (1.0, 0.3))]
    consistency += [
        {**c, "mode": "scanline", "distribution": "beckmann", "alpha": 0.2, "k": 0.4, "f0": 0.8,
         "diffuse_reflectance": rgb([1.5, 0.3, 0.0]),
         "specular_reflectance": rgb([0.9, 0.9, 2.0])},
        {**c, "distribution": "ggx", "alpha": 0.3, "k": 1.0},          # diffuse only
        {**c, "distribution": "ggx", "alpha": 0.0, "k": 0.0},          # alpha clamped
        {**c, "distribution": "beckmann", "alpha": 0.4, "k": 0.2, "sample_visible": False},
        {**c, "distribution": "ggx", "alpha": 0.2, "k": 0.0, "sampling": "cosine"},
        {**c, "distribution": "ggx", "geometry": "smith", "alpha": 0.7, "k": 0.2, "f0": 0.5,
         "specular_reflectance": rgb([0.95, 0.64, 0.54]), "energy_compensation": True},
    ]
    furnace = []
    for d in DISTRIBUTIONS:
        for g in GEOMETRIES:
            for a in (0.1, 0.3, 0.6, 1.0):
                for f0 in (1.0, None):          # None: the default f0 (0.04)
                    for k in (0.0, 0.5):
                        config = {**c, "distribution": d, "geometry": g, "alpha": a, "k": k,
                                  "diffuse_reflectance": 1.0, "specular_reflectance": 1.0,
                                  **({} if f0 is None else {"f0": f0})}
                        for group, thetas in (("low", THETAS_LOW), ("grazing", THETAS_GRAZING)):
                            label = (f"{d}, {g}, α = {a}, F0 = {f0 or 'default'}, k = {k}, "
                                     f"{group} angles")
                            # the diffuse lobe alone reflects k: the bound is [k, 1]
                            furnace.append(Furnace(label, config, lo=k, thetas=thetas))
    for d in DISTRIBUTIONS:
        for g in GEOMETRIES:
            for a in (0.05, 0.2, 0.6, 1.0):
                furnace.append(preserves(
                    f"compensated, {d}, {g}, α = {a}",
                    {**c, "distribution": d, "geometry": g, "alpha": a, "k": 0.0, "f0": 1.0,
                     "specular_reflectance": 1.0, "energy_compensation": True}))
    for d in ("beckmann", "ggx"):                  # the roughness they accept beyond 1
        for g in GEOMETRIES:
            for a in (1.5, 3.0, 10.0, 30.0, 1e3):
                furnace.append(preserves(
                    f"compensated, {d}, {g}, α = {a} (beyond 1)",
                    {**c, "distribution": d, "geometry": g, "alpha": a, "k": 0.0, "f0": 1.0,
                     "specular_reflectance": 1.0, "energy_compensation": True}))
    furnace.append(preserves("compensated, ggx, smith, α = 0.5, f0 = 1, m_S = 0.5: reflects 0.5",
                             {**c, "distribution": "ggx", "geometry": "smith", "alpha": 0.5,
                              "k": 0.0, "f0": 1.0, "specular_reflectance": 0.5,
                              "energy_compensation": True}, value=0.5))
    furnace.append(preserves("compensated, ggx, smith, α = 0.5, k = 0.5, m_D = m_S = 1",
                             {**c, "distribution": "ggx", "geometry": "smith", "alpha": 0.5,
                              "k": 0.5, "f0": 1.0, "diffuse_reflectance": 1.0,
                              "specular_reflectance": 1.0, "energy_compensation": True}))
    extremes = [{**c, "alpha": a, "f0": f0, "k": k, "mode": mode, "distribution": d,
                 "geometry": g}
                for a in (0.0, 1e-4, 1.0) for f0 in (0.0, 1.0) for k in (0.0, 0.5)
                for mode in ("hdr", "scanline") for d in DISTRIBUTIONS for g in GEOMETRIES]
    extremes += [{**c, "alpha": a, "k": 0.0, "distribution": d, "geometry": g,
                  "energy_compensation": True}
                 for a in (0.0, 1.0, 1e3) for d in DISTRIBUTIONS for g in GEOMETRIES
                 if a <= 1.0 or d != "blinn"]
    return Entry(
        chi2=chi2, consistency=consistency, furnace=furnace, extremes=extremes,
        interior=[{**c, "distribution": d, "geometry": "smith", "alpha": 0.4, "k": 0.4,
                   "f0": 0.3, "diffuse_reflectance": 0.5, "specular_reflectance": 0.7}
                  for d in ("ggx", "blinn")]
        + [{**c, "distribution": "beckmann", "alpha": 0.4, "k": 0.4, "f0": 0.3,
            "diffuse_reflectance": 0.5, "specular_reflectance": 0.7,
            "energy_compensation": True}],
        negative=({**c, "distribution": "ggx", "k": 0.0, "alpha": 0.1},
                  {**c, "distribution": "ggx", "k": 0.0, "alpha": 0.105}, 45),
        lobe_width=0.35,
        reciprocity=[{**c, "distribution": d, "geometry": g, "alpha": 0.3, "k": 0.2}
                     for d in DISTRIBUTIONS for g in GEOMETRIES]
        + [{**c, "distribution": d, "geometry": "smith", "alpha": 0.6, "k": 0.0,
            "energy_compensation": True, "specular_reflectance": rgb([0.95, 0.64, 0.54])}
           for d in DISTRIBUTIONS],
        lobe={**c, "distribution": "ggx", "alpha": 0.3, "k": 0.3, "f0": 0.5,
              "diffuse_reflectance": 0.8},
        bench=[(f"cook_torrance {d} {g}", {**c, "distribution": d, "geometry": g, "alpha": 0.3})
               for d in DISTRIBUTIONS for g in GEOMETRIES],
    )


# ----------------------------------------------------------------------------
#  What the validation report shows
# ----------------------------------------------------------------------------
#
# FURNACE, NEGATIVE and LOBES are derived from the entries on first use (module
# __getattr__ below): importing the catalog builds no entry.

# White furnace: for each model, its first three uncompensated configurations
# (label, config without mode). The report runs each in both modes and, for a
# compensable model, in hdr mode with energy compensation beside them.
def _report_furnace(name: str) -> list[tuple[str, dict]]:
    rows = [(f.label, f.config) for f in ENTRIES[name].furnace]
    return [r for r in rows if not r[1].get("energy_compensation")][:3]


def promises_one(name: str, config: dict) -> bool:
    """True if the catalog promises albedo 1 for this configuration (a furnace
    entry of ``name`` with lo = hi = 1, e.g. :func:`preserves`), in hdr mode."""
    def hdr(c):
        return {**c, "mode": c.get("mode", "hdr")}
    return any(f.lo == f.hi == 1.0 and hdr(f.config) == hdr(config)
               for f in ENTRIES[name].furnace)


def _furnace() -> dict[str, list[tuple[str, dict]]]:
    furnace = {name: _report_furnace(name) for name in ENTRIES}
    furnace["cook_torrance"] = [
        ("GGX, Smith, alpha = 1, k = 0, F0 = 1",
         {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith", "alpha": 1.0,
          "k": 0.0, "f0": 1.0, "specular_reflectance": 1.0}),
        ("Blinn D, Smith (Blinn G1), alpha = 1, k = 0, F0 = 1",
         {"type": "cook_torrance", "distribution": "blinn", "geometry": "smith", "alpha": 1.0,
          "k": 0.0, "f0": 1.0, "specular_reflectance": 1.0}),
        ("Beckmann, V-cavity, alpha = 0.3, k = 0.5, F0 = 1",
         {"type": "cook_torrance", "distribution": "beckmann", "alpha": 0.3, "k": 0.5,
          "f0": 1.0, "diffuse_reflectance": 1.0, "specular_reflectance": 1.0}),
    ]
    return furnace


def label(config: dict) -> str:
    """A configuration's parameters as one line (a texture by its type)."""
    def shown(v):
        if isinstance(v, dict):
            return v["value"] if v.get("type") == "rgb" else v.get("type", "texture")
        return v
    return ", ".join(f"{k} = {shown(v)}" for k, v in config.items() if k != "type") or "defaults"


def report_chi2(quick: bool = False) -> dict[str, list[tuple[str, Chi2]]]:
    """The χ² tests of the validation report, (label, test) per model: every
    one of the catalog (the battery's set), or with ``quick`` the ones marked
    representative of their model (phong and blinn at γ = 100 and 1000, sharp
    and anisotropic Ward lobes, ...)."""
    return {name: [(label(c.config), c) for c in entry.chi2 if c.quick or not quick]
            for name, entry in ENTRIES.items()}


def _negative() -> dict[str, tuple[dict, dict, float, float]]:
    """Negative controls of the χ² test: the sampler of one configuration
    against the pdf of a slightly different one, which the test must reject."""
    return {name: (*entry.negative, entry.extra.get("negative_phi", 0.0))
            for name, entry in ENTRIES.items() if entry.negative}


def _lobes() -> dict[str, dict]:
    """Lobe plots: one representative, readable configuration per model."""
    return {name: entry(name).lobe or {"type": name} for name in BY_NAME}


_DERIVED = {"FURNACE": _furnace, "NEGATIVE": _negative, "LOBES": _lobes}


def __getattr__(name: str):
    if name in _DERIVED:
        value = globals()[name] = _DERIVED[name]()
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def quick(entries: dict, n: int = 1) -> dict:
    """The first n configurations of each model (for --quick runs)."""
    return {name: configs[:n] for name, configs in entries.items()}


# ----------------------------------------------------------------------------
#  What the benchmarks run
# ----------------------------------------------------------------------------

def bench_models() -> list[tuple[str, dict]]:
    """Every model and variant whose render cost is compared (label, config):
    each registered plugin's ``Entry.bench`` (its defaults if it has none)."""
    return [row for name in BY_NAME for row in entry(name).bench or [(name, {"type": name})]]


# The scene of the in-process groups (bench/measure.py scene_dict): a sphere
# on this floor, point lights and a dim constant environment.
BENCH_FLOOR = {"type": "lambert", "reflectance": 0.5}

# Plugin against Mitsuba's built-in, the same BSDF (up to float error, or
# Mitsuba's G1 fit): (name, plugin, built-in). The groups builtin (renders),
# kernels (BSDF calls) and tracing (tracing one call) compare each pair.
BENCH_BUILTIN: list[tuple[str, dict, dict]] = [
    ("cook_torrance ggx vs roughconductor ggx",
     {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith", "f0": 1.0, "k": 0.0,
      "alpha": 0.3},
     {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3}),
    ("cook_torrance beckmann vs roughconductor beckmann",
     {"type": "cook_torrance", "distribution": "beckmann", "geometry": "smith", "f0": 1.0,
      "k": 0.0, "alpha": 0.3},
     {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.3}),
    ("lambert vs diffuse", {"type": "lambert", "reflectance": 0.6},
     {"type": "diffuse", "reflectance": 0.6}),
]
# Two lobes against Mitsuba's two-lobe plastic (not the same BSDF: what a
# second lobe costs to trace; the tracing group).
BENCH_TWO_LOBES: tuple[str, dict, dict] = (
    "cook_torrance ggx k=0.5 vs roughplastic ggx",
    {"type": "cook_torrance", "distribution": "ggx", "geometry": "smith", "k": 0.5, "alpha": 0.3},
    {"type": "roughplastic", "distribution": "ggx", "alpha": 0.3})

# The Oren-Nayar table against the exact formulas (method and table_resolution added).
BENCH_OREN_NAYAR = {"type": "oren_nayar", "sigma": 0.5, "reflectance": 0.8}

# Sampling strategies per glossy lobe: (name, config, [(strategy, options), ...]);
# the first strategy is the plugin's default.
BENCH_SAMPLING: list[tuple[str, dict, list[tuple[str, dict]]]] = [
    *[(f"phong gamma {g}",
       {"type": "phong", "exponent": g, "diffuse_reflectance": 0.0, "specular_reflectance": 0.9},
       [("lobe", {}), ("cosine", {"sampling": "cosine"})])
      for g in (10, 100, 1000)],
    *[(f"cook_torrance ggx alpha {a}",
       {"type": "cook_torrance", "distribution": "ggx", "alpha": a, "k": 0.0, "f0": 0.9},
       [("visible normals", {}), ("full distribution", {"sample_visible": False}),
        ("cosine", {"sampling": "cosine"})])
      for a in (0.05, 0.3)],
    ("ward anisotropic 0.05 x 0.3",
     {"type": "ward", "alpha_u": 0.05, "alpha_v": 0.3, "diffuse_reflectance": 0.0,
      "specular_reflectance": 0.9},
     [("lobe", {}), ("cosine", {"sampling": "cosine"})]),
]

# The glossy sphere the integrators and convergence groups render, and the
# integrator of their converged reference.
BENCH_GLOSSY = {"type": "cook_torrance", "distribution": "ggx", "alpha": 0.3, "k": 0.5}
BENCH_REFERENCE_INTEGRATOR = {"type": "path", "max_depth": 16}
BENCH_INTEGRATORS: list[tuple[str, dict]] = [
    ("scanline", {"type": "scanline", "clamp": False, "shadows": True}),
    ("direct", {"type": "direct"}),
    ("path depth 2", {"type": "path", "max_depth": 2}),
    ("path depth 3", {"type": "path", "max_depth": 3}),
    ("path depth 8", {"type": "path", "max_depth": 8}),
]

# Scan-line cost against resolution and number of lights: (BSDF, integrator).
BENCH_SCALING = ({"type": "lambert", "mode": "scanline"}, {"type": "scanline"})

# A lobe switched off against the model without it: (name, lobe off, reference).
BENCH_LOBES_OFF: list[tuple[str, dict, dict]] = [
    ("cook_torrance k=1 vs lambert",
     {"type": "cook_torrance", "k": 1.0, "diffuse_reflectance": 0.6},
     {"type": "lambert", "reflectance": 0.6}),
    ("phong m_S=0 vs lambert",
     {"type": "phong", "specular_reflectance": 0.0, "diffuse_reflectance": 0.6},
     {"type": "lambert", "reflectance": 0.6}),
    ("ward m_D=0 vs ward m_D=0.5",
     {"type": "ward", "diffuse_reflectance": 0.0, "alpha_u": 0.1, "alpha_v": 0.3},
     {"type": "ward", "diffuse_reflectance": 0.5, "alpha_u": 0.1, "alpha_v": 0.3}),
]

# Energy compensation on against off: (name, configuration without
# energy_compensation); every compensable plugin at least once.
BENCH_ENERGY: list[tuple[str, dict]] = [
    ("cook_torrance ggx smith", {"type": "cook_torrance", "distribution": "ggx",
                                 "geometry": "smith", "alpha": 0.5, "k": 0.3}),
    ("cook_torrance beckmann cook_torrance", {"type": "cook_torrance", "alpha": 0.5, "k": 0.3}),
    ("cook_torrance blinn smith", {"type": "cook_torrance", "distribution": "blinn",
                                   "geometry": "smith", "alpha": 0.5, "k": 0.3}),
    ("phong", {"type": "phong", "exponent": 10.0}),
    ("blinn", {"type": "blinn", "exponent": 10.0}),
    ("ward", {"type": "ward", "alpha": 0.3}),
    ("ward anisotropic", {"type": "ward", "alpha_u": 0.05, "alpha_v": 0.3}),
    ("oren_nayar (EON)", {"type": "oren_nayar", "sigma": 0.8}),
]

# Many spheres, each with its own material (materials, frozen): kind -> the
# material of the sphere at place t in [0, 1] of the grid; and the pairs
# (plugin, built-in) compared, each with its floor: the same BSDF as a bare
# Python mi.BSDF (tools/bench/floor.py).
BENCH_MATERIALS: dict[str, Callable[[float], dict]] = {
    "cook_torrance": lambda t: {"type": "cook_torrance", "distribution": "ggx",
                                "geometry": "smith", "f0": 1.0, "k": 0.0,
                                "alpha": 0.05 + 0.5 * t},
    "roughconductor": lambda t: {"type": "roughconductor", "distribution": "ggx",
                                 "alpha": 0.05 + 0.5 * t},
    "lambert": lambda t: {"type": "lambert",
                          "reflectance": {"type": "rgb", "value": [0.2 + 0.6 * t, 0.5, 0.8 - 0.6 * t]}},
    "diffuse": lambda t: {"type": "diffuse",
                          "reflectance": {"type": "rgb", "value": [0.2 + 0.6 * t, 0.5, 0.8 - 0.6 * t]}},
    "floor_ggx": lambda t: {"type": "bench_floor_ggx", "alpha": 0.05 + 0.5 * t},
    "floor_diffuse": lambda t: {"type": "bench_floor_diffuse",
                                "reflectance": {"type": "rgb", "value": [0.2 + 0.6 * t, 0.5, 0.8 - 0.6 * t]}},
}
BENCH_MATERIAL_PAIRS = [("cook_torrance", "roughconductor"), ("lambert", "diffuse")]
BENCH_FLOORS = {"cook_torrance": "floor_ggx", "lambert": "floor_diffuse"}    # plugin -> floor
# The floor beside a BENCH_BUILTIN pair in the tracing group (the same BSDF).
BENCH_TRACING_FLOORS: dict[str, dict] = {
    BENCH_BUILTIN[0][0]: {"type": "bench_floor_ggx", "alpha": 0.3},
    BENCH_BUILTIN[2][0]: {"type": "bench_floor_diffuse", "reflectance": 0.6},
}
