"""The configurations the tests, the validation report and the benchmarks run, in one place.

Each registered plugin has an :class:`Entry`: the conformance battery
(``tests/bsdfs/test_battery.py``) runs every plugin through it — χ² of the
sampler, weight × pdf = eval, the white furnace, the numerical extremes,
gradients, bad input — so adding a model means adding its entry here (see
CONTRIBUTING.md). Configurations are plugin dictionaries; one without a
``mode`` is run in both modes where that makes sense (consistency, extremes),
one with a ``mode`` as given. Colours are white (1) where energy is measured,
so the albedo is the fraction of light reflected.

``mi-brdfs validate`` shows the first configurations of :data:`FURNACE`,
:data:`CHI2` and :data:`LOBES`; ``mi-brdfs bench`` runs :func:`bench_models`
and :data:`BENCH_SAMPLING`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

HALF_PI = 0.5 * math.pi
DISTRIBUTIONS = ("blinn", "beckmann", "ggx")
GEOMETRIES = ("cook_torrance", "smith")
THETAS_LOW = (0, 15, 30, 45, 60, 75)
THETAS_GRAZING = (80, 85, 88, 89)
THETAS_COMPENSATED = (0, 30, 60, 75, 85)      # the range, 0°–85°


@dataclass(frozen=True)
class Chi2:
    """A χ² test of the sampler against the pdf, at each incident angle."""
    config: dict
    thetas: tuple[float, ...] = (0, 45, 85)
    ires: int = 16                 # pdf sub-samples per cell and axis (sharp lobes: more)
    res: int = 201
    phi: float = 0.0               # the viewer's azimuth


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

def _lambert() -> Entry:
    return Entry(
        chi2=[Chi2({"type": "lambert", "mode": m}, (0, 85)) for m in ("hdr", "scanline")],
        consistency=[{"type": "lambert"},
                     {"type": "lambert", "mode": "scanline", "reflectance": rgb([1.7, 0.6, 0.2])}],
        furnace=[Furnace("m_D = 1", {"type": "lambert", "reflectance": 1.0}, lo=1.0, hi=1.0,
                         tol=0.01)],
        extremes=[{"type": "lambert"}, {"type": "lambert", "reflectance": 0.0}],
        interior=[{"type": "lambert", "reflectance": 0.4}],
    )


# ----------------------------------------------------------------------------
#  oren_nayar
# ----------------------------------------------------------------------------

def _oren_nayar() -> Entry:
    on = {"type": "oren_nayar"}
    eon = {**on, "energy_compensation": True}
    return Entry(
        chi2=[Chi2({**on, "sigma": s, "method": m}, res=101)
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


def _toon() -> Entry:
    t = {"type": "toon"}
    chi2_configs = _toon_chi2_configs()
    return Entry(
        chi2=[Chi2(c, (0, 30, 60, 85), ires=32) for c in chi2_configs],
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
    )


# ----------------------------------------------------------------------------
#  phong and blinn
# ----------------------------------------------------------------------------

def _exponent_model(name: str) -> Entry:
    b = {"type": name}
    chi2 = [Chi2({**b, "exponent": g, "diffuse_reflectance": m_d}, (0, 30, 60, 85), ires=64)
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
    )


# ----------------------------------------------------------------------------
#  ward
# ----------------------------------------------------------------------------

WARD_ALPHAS = [(1e-3, 0.5), (0.5, 1e-3), (0.0, 0.0), (1e-4, 1e-4), (1.0, 1.0), (0.2, 0.2)]


def _ward() -> Entry:
    w = {"type": "ward"}
    # viewers at azimuth 30°, not along t or b: the anisotropic lobe is asymmetric
    chi2 = [Chi2({**w, "alpha_u": at, "alpha_v": ab, "diffuse_reflectance": m_d},
                 (0, 30, 60, 85), phi=30.0)
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
    )


# ----------------------------------------------------------------------------
#  cook_torrance
# ----------------------------------------------------------------------------

def _cook_torrance() -> Entry:
    c = {"type": "cook_torrance"}
    chi2 = [Chi2({**c, "distribution": d, "alpha": a, "k": k}, (0, 45, 85))
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
    )


ENTRIES: dict[str, Entry] = {
    "lambert": _lambert(), "oren_nayar": _oren_nayar(), "toon": _toon(),
    "phong": _exponent_model("phong"), "blinn": _exponent_model("blinn"),
    "ward": _ward(), "cook_torrance": _cook_torrance(),
}


# ----------------------------------------------------------------------------
#  What the validation report shows
# ----------------------------------------------------------------------------

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


FURNACE: dict[str, list[tuple[str, dict]]] = {name: _report_furnace(name) for name in ENTRIES}
FURNACE["cook_torrance"] = [
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

# Sampling: (label, config, incident angles in degrees) per model.
CHI2: dict[str, list[tuple[str, dict, tuple[float, ...]]]] = {
    name: [(", ".join(f"{k} = {v}" for k, v in c.config.items()
                      if k != "type" and not isinstance(v, dict)) or "defaults",
            c.config, tuple(c.thetas)) for c in entry.chi2]
    for name, entry in ENTRIES.items()
}

# Lobe plots: one representative, readable configuration per model.
LOBES: dict[str, dict] = {
    "lambert": {"type": "lambert", "reflectance": 0.8},
    "oren_nayar": {"type": "oren_nayar", "reflectance": 0.8, "sigma": 0.8},
    "toon": {"type": "toon", "smoothness": 0.1},
    "phong": {"type": "phong", "diffuse_reflectance": 0.3, "specular_reflectance": 0.6,
              "exponent": 30},
    "blinn": {"type": "blinn", "diffuse_reflectance": 0.3, "specular_reflectance": 0.6,
              "exponent": 30},
    "ward": {"type": "ward", "diffuse_reflectance": 0.3, "specular_reflectance": 0.6,
             "alpha_u": 0.1, "alpha_v": 0.3},
    "cook_torrance": {"type": "cook_torrance", "distribution": "ggx", "alpha": 0.3, "k": 0.3,
                      "f0": 0.5, "diffuse_reflectance": 0.8},
}


def quick(entries: dict, n: int = 1) -> dict:
    """The first n configurations of each model (for --quick runs)."""
    return {name: configs[:n] for name, configs in entries.items()}


# ----------------------------------------------------------------------------
#  What the benchmarks run
# ----------------------------------------------------------------------------

def bench_models() -> list[tuple[str, dict]]:
    """Every model and variant whose render cost is compared (name, config)."""
    return [
        ("lambert", {"type": "lambert", "reflectance": 0.6}),
        ("oren_nayar exact", {"type": "oren_nayar", "sigma": 0.5, "method": "exact"}),
        ("oren_nayar table", {"type": "oren_nayar", "sigma": 0.5, "method": "table"}),
        ("toon", {"type": "toon"}),
        ("toon with ramps", {"type": "toon",
                             "diffuse_ramp": toon_ramp([[0.1] * 3, [0.1] * 3, [0.4] * 3, [0.8] * 3]),
                             "specular_ramp": toon_ramp([[0.0] * 3] * 7 + [[1.0] * 3])}),
        ("phong", {"type": "phong", "exponent": 50}),
        ("blinn", {"type": "blinn", "exponent": 50}),
        *[(f"cook_torrance {d} {g}",
           {"type": "cook_torrance", "distribution": d, "geometry": g, "alpha": 0.3})
          for d in DISTRIBUTIONS for g in GEOMETRIES],
        ("ward vectors", {"type": "ward", "alpha_u": 0.1, "alpha_v": 0.3, "formula": "vectors"}),
        ("ward angles", {"type": "ward", "alpha_u": 0.1, "alpha_v": 0.3, "formula": "angles"}),
    ]


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
