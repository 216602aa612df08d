r"""The directional multiple-scattering lobe: the random walk's bounces k >= 2, tabulated by pair of directions.

The separable lobe of :mod:`.compensation` gives a rough surface the light
its single scattering misses, but spreads it as g(ω_i) g(ω_o): it lights
retro-reflection and side-on grazing pairs where the Smith microsurface's
multiple scattering has nothing, and misses most of what it has near the
grazing mirror pair (``python -m mi_brdfs.tools.groundtruth --grazing``).
This lobe puts the light where the microsurface puts it. For the Smith
microsurface of a GGX or Beckmann distribution (isotropic roughness) the
specular lobe becomes

.. math::

    f = f_1 + f_{ms}, \qquad
    f_1\cos\theta_o = \frac{F(\omega_i\cdot h)\,D(h)\,\cos\theta_o}
        {4\,(\cos\theta_o\,A(-\omega_i) + \cos\theta_i\,A(\omega_o))},

f_1 the height-correlated single scattering in closed form (Heitz 2014,
"Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs",
eq. 99; :func:`.walk.single`), which the random walk's first bounce is, and
f_ms the walk's bounces k >= 2 (Heitz, Hanika, d'Eon & Dachsbacher 2016),
tabulated. The separable Smith G1(ω_i) G1(ω_o) of the uncompensated lobe
(``roughconductor``'s) is not the walk's first bounce: near the grazing
mirror pair it falls far short of f_1, and no smooth table of what is left
could hold that narrow a difference, so the closed form carries it.

**The table.** S = f_ms (cos θ_i + cos θ_o) over five axes: cos θ_i and
cos θ_o (13 nodes each, denser towards grazing), the half vector's place u
between the mirror azimuth and retro-reflection (13 nodes, denser towards
both ends), α (17 nodes, log-spaced from ``ALPHA_START`` to ``ALPHA_END``)
and Schlick's F0 (6 nodes); read as its magnitude times its shape, times a
factor per direction that gives it the walk's albedo (:class:`PairTable`).
With θ_h the angle of h = (ω_i + ω_o)/|ω_i + ω_o| from the normal,

.. math::

    u = \frac{\theta_h - |\theta_i - \theta_o|/2}
             {(\theta_i + \theta_o)/2 - |\theta_i - \theta_o|/2} \in [0, 1],

0 at the mirror azimuth (where θ_h is least) and 1 at retro-reflection (where
it is largest). At grazing pairs the retro-reflection half of the azimuths
is a sliver of u (80°/80°: u from 0.95 side on to 1), where Beckmann's k >= 2
at large α falls off a cliff; with 9 nodes denser only near the mirror the
table gave 0.07 of the walk there (α 2, 80°/80° side on), with 13 denser
towards both ends 0.8 and more. At small α the walk's multiple scattering
follows the half vector, a ridge a few degrees wide about the mirror
azimuth; an axis of the plain azimuth smears it, this one resolves it (the
study in the issue that asked for this lobe: 8-52 % there with the azimuth,
0.4-1.8 % with u).
S, not f_ms, is stored: it stays bounded at grazing pairs, where f_ms grows
as 1/cos (the walk's next-event estimator from both ends is S's, see
:mod:`.walk`), and f_ms cos θ_o = S cos θ_o / (cos θ_i + cos θ_o).

**Reciprocal by construction.** The stored S is symmetrised,
S(μ_i, μ_o) = S(μ_o, μ_i), both μ axes are one axis, and u is symmetric in
the two directions: the lookup at (ω_o, ω_i) takes the same nodes with the
same weights as at (ω_i, ω_o), to float precision.

**Built** by ``python -m mi_brdfs.tools.tables --only directional/ggx
directional/beckmann``: at each node the walk's next-event estimate from both
ends (:func:`.walk.scattered`, ``PAIR_PATHS`` paths, every F0 node on the same
paths), Schlick's F at every bounce. Its F0 is read as the separable lobe's
is: per colour channel, at Schlick's F0 of the same hemispherical average
F_avg for another Fresnel form (:func:`.fresnel.schlick_equivalent`). Beyond
``ALPHA_END`` the table would hold α = ``ALPHA_END`` and lose light (a
white GGX α 3 reflects 0.78-0.96): a plugin whose roughness is one value
above it takes the separable lobe instead (``cook_torrance``'s
``uses_directional``), which is exact in albedo to α = ∞; a textured or
differentiated roughness beyond it keeps the held table.

**Sampled** as the separable lobe is: picked in proportion to its directional
albedo (the table ``directional/<D>/albedo``, the cosine-weighted integral of
the interpolated S over ω_o, computed offline) and drawn from the cosine
hemisphere; f_1 by the visible normals as before.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from .compensation import Compensation, Table, coloured, per_channel, shipped
from .grid import Axis, Grid

FLOOR = 1e-4               # S is interpolated as log(S + FLOOR x its largest at that α)
DARK = 1.5                 # and read as 0 where the interpolated R + floor is below DARK floors
ALPHA_START = 0.01         # below it the table holds α 0.01 (its bounces k >= 2: < 1e-3 of white)
ALPHA_END = 2.0            # the roughness up to which the walk is tabulated (held beyond)
PAIR_PATHS = 1 << 14       # walk paths per node and per end
MU_AXIS_I = Axis("mu_i", 0.0, 1.0, 13, "sqrt")
MU_AXIS_O = Axis("mu_o", 0.0, 1.0, 13, "sqrt")
U_AXIS = Axis("u", 0.0, 1.0, 13, "sine")
ALPHA_AXIS = Axis("alpha", ALPHA_START, ALPHA_END, 17, "log", smooth=True)
F0_AXIS = Axis("f0", 0.0, 1.0, 6, smooth=True)           # the walk's F0 nodes
SHAPE_F0_AXIS = Axis("f0", 0.2, 1.0, 5, smooth=True)     # the shape's (held below 0.2)
STORED_AXES = (MU_AXIS_I, MU_AXIS_O, U_AXIS, ALPHA_AXIS, F0_AXIS)   # the walked S
PAIR_AXES = (MU_AXIS_I, MU_AXIS_O, U_AXIS, ALPHA_AXIS, SHAPE_F0_AXIS)   # its shape's lookup
ALBEDO_AXES = (Axis("mu", 0.0, 1.0, 13, "sqrt"), ALPHA_AXIS, F0_AXIS)
SCALE_AXES = (Axis("mu", 0.0, 1.0, 25, "sqrt"), ALPHA_AXIS, Axis("f0", 0.0, 1.0, 11, smooth=True))
SCALE_PATHS = 1 << 19      # walk paths per node of the scale's target


@dataclass(frozen=True)
class _Spec:
    """A shipped table of the directional lobe of ``distribution``'s Smith
    microsurface: named ``directional/<distribution>`` and its ``part``, over
    ``AXES``."""
    distribution: str
    part = ""
    AXES = ()

    @property
    def name(self) -> str:
        return f"directional/{self.distribution}" + (f"/{self.part}" if self.part else "")

    @property
    def axes(self) -> tuple[Axis, ...]:
        return type(self).AXES


@dataclass(frozen=True)
class PairSpec(_Spec):
    """The walk's bounces k >= 2 by pair of directions, S = f_ms (μ_i + μ_o),
    over :data:`STORED_AXES`; built by
    :func:`mi_brdfs.tools.tables.build_pairs`."""
    paths: int = PAIR_PATHS
    AXES = STORED_AXES


@dataclass(frozen=True)
class ScaleSpec(_Spec):
    """c(μ, α, F0) over :data:`SCALE_AXES`: the lobe read as f_ms c(μ_i)
    c(μ_o) has, at every node, the directional albedo of the walk's bounces
    k >= 2 (see :class:`PairTable`); built by
    :func:`mi_brdfs.tools.tables.calibrate`."""
    paths: int = SCALE_PATHS
    part = "scale"
    AXES = SCALE_AXES


@dataclass(frozen=True)
class PairAlbedoSpec(_Spec):
    """The directional albedo of a :class:`PairSpec`'s lobe over
    :data:`ALBEDO_AXES`, ∫ f_ms cos θ_o dω_o of the interpolated table (its
    sampling weight), computed with it."""
    part = "albedo"
    AXES = ALBEDO_AXES


# ----------------------------------------------------------------------------
#  The half vector's coordinate (NumPy and Dr.Jit)
# ----------------------------------------------------------------------------

def u_coordinate_np(wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """u of local directions (N, 3) each (NumPy, float64): 0 at the mirror
    azimuth, 1 at retro-reflection (0 where the two coincide)."""
    ti = np.arccos(np.clip(wi[..., 2], -1.0, 1.0))
    to = np.arccos(np.clip(wo[..., 2], -1.0, 1.0))
    h = wi + wo
    h = h / np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-300)
    th = np.arccos(np.clip(h[..., 2], -1.0, 1.0))
    lo, span = 0.5 * np.abs(ti - to), 0.5 * (ti + to) - 0.5 * np.abs(ti - to)
    return np.clip((th - lo) / np.maximum(span, 1e-12), 0.0, 1.0)


def azimuth_at(mu_i: np.ndarray, mu_o: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The azimuth of ω_o from ω_i's (0: the same side, retro-reflection; π:
    the mirror side) at which the coordinate is u (NumPy; by bisection, u
    falls monotonically from 1 to 0 as the azimuth goes from 0 to π)."""
    lo, hi = np.zeros_like(u), np.full_like(u, math.pi)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        wi, wo = pair_directions(mu_i, mu_o, mid)
        above = u_coordinate_np(wi, wo) > u
        lo, hi = np.where(above, mid, lo), np.where(above, hi, mid)
    return 0.5 * (lo + hi)


def pair_directions(mu_i, mu_o, dphi):
    """ω_i at azimuth 0 and ω_o at azimuth ``dphi`` (NumPy, (N, 3) each)."""
    si, so = np.sqrt(np.maximum(1.0 - mu_i ** 2, 0.0)), np.sqrt(np.maximum(1.0 - mu_o ** 2, 0.0))
    wi = np.stack([si, np.zeros_like(si), mu_i], axis=-1)
    wo = np.stack([so * np.cos(dphi), so * np.sin(dphi), mu_o], axis=-1)
    return wi, wo


def _angle(cos, sin):
    """The angle of (cos, sin) >= 0 (sin >= 0), accurate at both ends."""
    return dr.atan2(sin, cos)


def u_coordinate(wi, wo):
    """u of two local directions (Dr.Jit; see the module doc)."""
    sin_i = dr.safe_sqrt(dr.fma(-wi.z, wi.z, 1.0))
    sin_o = dr.safe_sqrt(dr.fma(-wo.z, wo.z, 1.0))
    ti, to = _angle(wi.z, sin_i), _angle(wo.z, sin_o)
    h = wi + wo
    hz, hr = h.z, dr.sqrt(dr.square(h.x) + dr.square(h.y))
    th = _angle(hz, hr)
    lo = 0.5 * dr.abs(ti - to)
    span = 0.5 * (ti + to) - lo
    ok = span > 1e-6
    return dr.select(ok, dr.clip((th - lo) / dr.select(ok, span, 1.0), 0.0, 1.0), 0.0)


# ----------------------------------------------------------------------------
#  The lobe
# ----------------------------------------------------------------------------

LOW_F0 = 0.2                     # below it S is S(0) plus S(0.2)'s F0-dependent part


class ShapeTable(Table):
    """log(R + floor) of a shape R over the pair (ω_i, ω_o) and the
    parameters ``axes[3:]``: a :class:`.compensation.Table` whose direction is
    the pair, so that :class:`.compensation.Specialised` contracts constant
    parameters as it does a table's of one direction."""

    def __init__(self, axes, logged: np.ndarray, spec):
        self.axes, self.directions, self.specs = tuple(axes), 3, (spec,)
        self.grid = Grid(self.axes, logged)
        # (no average: the lobe is normalised by its table, not by G_avg)
        self.average_grid = Grid(self.axes[3:], np.zeros(tuple(a.n for a in self.axes[3:])))

    def coordinates(self, pair) -> list:
        wi, wo = pair
        clamp = lambda mu: dr.fmin(dr.fmax(mu, 0.0), 1.0)
        return [clamp(wi.z), clamp(wo.z), u_coordinate(wi, wo)]


class ScaleTable(Table):
    """A function of the parameters alone (α, and F0 on ``f0_axis``) beside a
    :class:`ShapeTable` (a magnitude, a floor): a table of no direction,
    specialised as the shape is."""

    def __init__(self, values: np.ndarray, f0_axis: Axis | None = None):
        self.axes = (ALPHA_AXIS,) + ((f0_axis,) if f0_axis is not None else ())
        self.directions, self.specs = 0, ()
        self.grid = Grid(self.axes, values)
        self.average_grid = self.grid

    def coordinates(self, v) -> list:
        return []


class PairTable:
    """S over (μ_i, μ_o, u, α, F0) as the lookup reads it (:meth:`Reader.s`):
    its magnitude M(α, F0), the mean of S over the direction nodes, times its
    shape R = S / M, of which log(R + floor) is interpolated.

    - M is smooth in α and F0 (a C2 spline of it in F0 is within 0.3 % of the
      walk's albedo between F0 nodes, where S grows as F0²).
    - log R: near the grazing mirror pair S spans decades between α nodes (3e3
      at α 0.017, 0.28 at α 0.26) and falls off a cliff side on (Beckmann α 1:
      0.044 sr⁻¹ at 60°/60°, 2e-9 at 80°/80°), where a spline of S itself rang
      (12 sr⁻¹ for the walk's 0.28 at 87°/87°, α 0.3) and linear steps lit pairs
      the walk leaves dark. The floor, FLOOR times R's largest at each α node,
      takes what is far below the largest about linearly (no log of 0).
    - R is read as exp(interpolated log(R + floor)) - floor where that is
      above DARK floors, else 0 (a step of half a floor, 5e-5 of the
      largest). Without the step the pairs the walk leaves dark kept a
      trace: up to 1.1e-4 (1.1e-6 on average) of radiance on the dark side
      of a gold α 0.1 sphere whose highlight reaches 31, which HDR-FLIP,
      exposing for the dark pixels, read as 0.43 and 0.62 in the fit's two
      point-lit views (0.000 with it, as the walk). Subtracting more than
      the floor everywhere instead took light from the peaked tables of
      small α (a white GGX α 0.05 at 85°: 0.971 with twice the floor, 0.989
      with the floor, 0.985 with the step).
    - R over F0 from ``LOW_F0`` up; below, S(F0) = S(0) + (M(F0) - M(0)) /
      (M(LOW_F0) - M(0)) · (S(LOW_F0) - S(0)): at F0 0 the light that is left,
      the grazing bounces' Fresnel alone, has another shape, which no spline of
      log R joins to the rest (with one, 9-12 % off the walk's albedo at F0 0.1,
      30 times it at F0 0, normal incidence).
    - Times c(μ_i) c(μ_o) (``scale``, over :data:`SCALE_AXES`; None: 1), which
      gives the interpolated lobe the walk's albedo of bounces k >= 2 at every
      node (:func:`mi_brdfs.tools.tables.calibrate`): between the μ nodes the
      interpolation takes light from the narrow ridge near the mirror pair of
      small α (white Beckmann α 0.05 reflected 0.974 at 85°), and below
      F0 ``LOW_F0`` the blend above gives the k >= 2 too much (Beckmann α 1,
      F0 0.1: 3.6 % too bright at normal incidence). A product of one factor
      per direction keeps the lobe symmetric, and its zeros zero."""

    def __init__(self, values: np.ndarray, spec: PairSpec, scale: np.ndarray | None = None):
        values = np.maximum(values, 0.0)
        self.specs = (spec,)
        # (not clipped at 0: a clip would take the spline off its nodes)
        self.scale = None if scale is None else Table(
            SCALE_AXES, scale, 1, (ScaleSpec(spec.distribution),), bounds=None)
        magnitude = np.maximum(values.mean(axis=(0, 1, 2)), 1e-30)          # (α, F0)
        shape = values / magnitude[None, None, None]
        floor = FLOOR * np.maximum(shape.max(axis=(0, 1, 2)), 1e-30)        # (α, F0)
        logged = np.log(shape + floor[None, None, None])
        self.shape = ShapeTable(PAIR_AXES, logged[..., 1:], spec)
        self.shape0 = ShapeTable(PAIR_AXES[:4], logged[..., 0], spec)
        self.floor = ScaleTable(np.log(floor[:, 1:]), SHAPE_F0_AXIS)
        self.floor0 = ScaleTable(np.log(floor[:, 0]))
        self.magnitude = ScaleTable(magnitude, F0_AXIS)

    @staticmethod
    def value(logged, log_floor, magnitude):
        """S from the interpolated log(R + floor), log(floor) and M (>= 0)."""
        lifted, floor = dr.exp(logged), dr.exp(log_floor)
        return dr.fmax(magnitude, 0.0) * dr.select(lifted > DARK * floor, lifted - floor, 0.0)


class Reader:
    """One channel's view of a :class:`PairTable` (every channel alike unless
    F0 is a constant colour): its tables specialised at the constant α and F0
    (None: read per lane). A constant F0 at or above ``LOW_F0`` reads one shape;
    below, S(0) and S(LOW_F0) too; one read per lane, all three."""

    def __init__(self, table: PairTable, albedos: Table, alpha, f0):
        self.low = None if f0 is None else f0 < LOW_F0          # None: per lane
        at = (alpha, f0)
        parts = {} if albedos is None else {"albedo": albedos.specialise(at)}
        if self.low is not True:
            parts.update(shape=table.shape.specialise(at), floor=table.floor.specialise(at),
                         magnitude=table.magnitude.specialise(at))
        if self.low is not False:
            parts.update(shape0=table.shape0.specialise((alpha,)),
                         floor0=table.floor0.specialise((alpha,)),
                         shape_low=table.shape.specialise((alpha, LOW_F0)),
                         floor_low=table.floor.specialise((alpha, LOW_F0)),
                         magnitude=table.magnitude.specialise(at),
                         magnitude0=table.magnitude.specialise((alpha, 0.0)),
                         magnitude_low=table.magnitude.specialise((alpha, LOW_F0)))
        if table.scale is not None:
            parts["scale"] = table.scale.specialise(at)
        self.parts = parts
        self.fixed = tuple(parts["magnitude"].fixed)

    def data(self) -> dict:
        return {name: part.data for name, part in self.parts.items()}

    def s(self, pair, alpha, f0, data):
        """S at the pair for the lane's α and F0 (see :class:`PairTable`)."""
        read = lambda name, at, params: self.parts[name](at, params, data[name])
        m = read("magnitude", None, (alpha, f0))
        high = low = None
        if self.low is not True:
            high = PairTable.value(read("shape", pair, (alpha, f0)),
                                   read("floor", None, (alpha, f0)), m)
        if self.low is not False:
            s0 = PairTable.value(read("shape0", pair, (alpha,)), read("floor0", None, (alpha,)),
                                 read("magnitude0", None, (alpha, None)))
            m0 = read("magnitude0", None, (alpha, None))
            m_low = read("magnitude_low", None, (alpha, None))
            s_low = PairTable.value(read("shape_low", pair, (alpha, None)),
                                    read("floor_low", None, (alpha, None)), m_low)
            span = m_low - m0
            t = (m - m0) / dr.select(span > 0.0, span, 1.0)
            low = s0 + t * (s_low - s0)
        s = low if high is None else high if low is None else dr.select(f0 < LOW_F0, low, high)
        if "scale" not in self.parts:
            return s
        wi, wo = pair        # (c_i c_o first: the same bits in either order)
        return s * (read("scale", wi, (alpha, f0)) * read("scale", wo, (alpha, f0)))


def read_s(table: PairTable, pair, alpha: float, f0: float):
    """S of ``table`` at the pair (ω_i, ω_o) for one α and F0, as the plugin
    reads it (the tables command integrates it into the albedo table)."""
    reader = Reader(table, None, alpha, f0)
    return reader.s(pair, alpha, f0, reader.data())


class Directional(Compensation):
    """The directional lobe of a ``cook_torrance`` with Smith's G and a GGX or
    Beckmann distribution (isotropic): f_ms cos θ_o from :class:`PairTable`,
    its albedo (for picking it) from :class:`PairAlbedoSpec`'s table; the
    colour m_S, the F0 per channel as the separable lobe reads it."""

    lobe = "specular"
    directional = True

    def __init__(self, distribution: str, parameters, sources: tuple[str, ...], colour):
        self.pairs = _pair_table(distribution)
        self.albedos = _albedo_table(distribution)
        self.parameters, self.sources, self.colour_of = parameters, tuple(sources), colour
        self.readers: list[Reader] = []

    def prepare(self, plugin) -> dict:
        """Contract the parameters that are constant over the surface, a colour
        one (an F0 per channel, RGB variants) per channel: a shape lookup then
        gathers 8 values (32 with F0 read per lane)."""
        inp = plugin.eval_textures(dr.zeros(mi.SurfaceInteraction3f), True)
        # a source: a parameter's name, or the names of those it is computed from
        # (another Fresnel form's F0: constant where they are, differentiated or not)
        members = [[] if name is None else [getattr(plugin, "m_" + n) for n in
                                            ((name,) if isinstance(name, str) else name)]
                   for name in self.sources]
        varies = lambda obj: isinstance(obj, mi.Object) and obj.is_spatially_varying()
        constants = []
        for objs, x in zip(members, self.parameters(inp)):
            if not objs or any(varies(obj) for obj in objs) \
                    or (coloured(x) and mi.is_spectral):     # (per sampled wavelength)
                constants.append(None)
            elif coloured(x):
                constants.append([_number(x[c]) for c in range(dr.size_v(x))])
            else:
                constants.append(_number(x))
        count = max((len(c) for c in constants if isinstance(c, list)), default=0)
        alpha, f0 = constants
        self.readers = [Reader(self.pairs, self.albedos, alpha,
                               f0[c] if isinstance(f0, list) else f0)
                        for c in range(max(count, 1))]
        self.per_channel = count > 0
        return {"channels": [reader.data() for reader in self.readers]}

    def _each(self, inp, one):
        """``one(reader, its data, (alpha, f0))`` per channel where F0 is a
        constant colour, else per channel of the lane's F0 (:func:`per_channel`)."""
        params = self.parameters(inp)
        if not self.per_channel:
            return per_channel(lambda p: one(self.readers[0], 0, p), params)
        colour = next(p for p in params if coloured(p))
        return type(colour)(*(one(reader, c, tuple(p[c] if coloured(p) else p for p in params))
                              for c, reader in enumerate(self.readers)))

    def albedo(self, inp, v, data):
        return self._each(inp, lambda r, c, p: dr.fmax(
            r.parts["albedo"](v, p, data["channels"][c]["albedo"]), 0.0))

    def average(self, inp, data):
        return 1.0                       # (unused: value() is the lobe)

    def colour(self, inp):
        return self.colour_of(inp)

    def value(self, inp, wi, wo, ms, data):
        """C f_ms cos θ_o (f_ms per channel for a coloured F0), 0 below the horizon."""
        cos_i, cos_o = dr.fmax(wi.z, 0.0), dr.fmax(wo.z, 0.0)
        scale = cos_o / dr.fmax(cos_i + cos_o, 1e-30)
        s = self._each(inp, lambda r, c, p: r.s((wi, wo), p[0], p[1], data["channels"][c]))
        return ms[2] * (s * scale)

    def key(self) -> tuple:
        return ("directional",) + tuple((r.low, r.fixed) for r in self.readers)


def _number(x) -> float:
    """A lane-0 value as a Python float (a Float of one lane, or a number)."""
    return float(x[0]) if dr.is_array_v(x) else float(x)


_cache: dict = {}


def _pair_table(distribution: str) -> PairTable:
    key = (mi.variant(), "pairs", distribution)
    if key not in _cache:
        spec = PairSpec(distribution)
        _cache[key] = PairTable(shipped(spec), spec, shipped(ScaleSpec(distribution)))
    return _cache[key]


def _albedo_table(distribution: str) -> Table:
    key = (mi.variant(), "albedo", distribution)
    if key not in _cache:
        spec = PairAlbedoSpec(distribution)
        _cache[key] = Table(spec.axes, shipped(spec), 1, (spec,))
    return _cache[key]
