"""Energy compensation at run time: the multiple-scattering lobe every compensated model shares.

A single-scattering lobe of directional albedo E(ω) < 1 (per unit colour)
loses the light that, in a real rough surface, scatters more than once before
leaving. Compensation adds a reciprocal lobe whose directional albedo is what
is missing, g(ω) (Kulla & Conty, "Revisiting Physically Based Shading at
Imageworks", SIGGRAPH 2017 course; Turquin, "Practical multiple scattering
compensation for microfacet models", 2019):

    f_ms(ω_i, ω_o) = C · g(ω_i) g(ω_o) / (π G_avg),    G_avg = (1/π) ∫ g(ω) cos θ dω,

whose albedo is C g(ω_i) exactly (∫ g(ω_o) cos θ_o dω_o / (π G_avg) = 1), for
any g >= 0 and any colour C. It is sampled from the cosine hemisphere.

**What g is.** For a lobe that loses energy only by its own shape (Phong,
Blinn and Ward, whose lost light is the part of the lobe cut off at the
horizon) and for a white microfacet surface, g = 1 - E: the surface then
reflects C (E + 1 - E) = C at every angle. For a microfacet conductor with
Schlick's Fresnel F0 + (1 - F0)(1 - cos)^5 at every bounce, the truth is the
random walk on the Smith microsurface of Heitz et al. 2016
(:mod:`mi_brdfs.tools.groundtruth`): its albedo W(μ, α, F0) is tabulated from
the walk, and

    g(μ, α, F0) = W(μ, α, F0) - E_ss(μ, α, F0),
    E_ss = F0 E(μ, α; F = 1) + (1 - F0) E(μ, α; F0 = 0)

is what the model's own single scattering E_ss misses (clamped at 0; E_ss is
linear in F0). This g holds both of what single scattering loses: the light
of bounces k >= 2 and, for the separable Smith G1(ω_i) G1(ω_o), the energy
it loses beyond the real (height-correlated) microsurface's single scattering,
1 / (1 + Λ_i + Λ_o) >= G1 G1 (measured by ``python -m mi_brdfs.tools.groundtruth
--decomposition``: see the documentation's energy guide). For the Blinn D and the V-cavity G,
whose microsurfaces have no random walk, W is that of the nearest Smith
microsurface (Beckmann at the same α for Blinn, whose exponent 2/α² - 2 is
Walter's mapping; the same D with Smith's G for the V-cavity).

**Colours are linear.** A colour that scales a lobe (m_S, m_D) scales its
compensated albedo: C = m_S, so the surface reflects m_S W (microfacets) or
m_S (Phong, Blinn, Ward) — as Mitsuba's ``specular_reflectance`` scales a
lobe; the only per-bounce reflectance is Fresnel's, inside W. The exception
is the energy-preserving Oren-Nayar model (EON, Portsmouth, Kutz & Hill,
JCGT 2025), whose ρ enters as the paper defines it: g = 1 - E_FON and
C = ρ² E_avg / (1 - ρ (1 - E_avg)) (:func:`ms_series`), each extra bounce
taking the colour again.

**Tables.** E is tabulated from each model's own single-scattering formula:
E(μ, p) = ∫ f(ω_i, ω_o; p) dω_o (``f`` in eval convention, colour 1) by a
deterministic quadrature over the model's own sampler (one jittered point u
in each of samples² strata of the unit square, a fixed seed; E = mean of
f / pdf at ω_o = sample(u)). Each :class:`AlbedoSpec` declares the axes: the
direction (cos θ_i, and sin²φ_i for anisotropic lobes), then the model's
parameters (roughness, exponent). E is clamped to [0, 1] (Ward's albedo
exceeds 1 within a fraction of a degree of the horizon; there no light is
added). The node μ = 0 holds E at μ = ``MU_MIN``; a roughness axis reaches α
= ∞ (the ``ratio`` or ``root`` warp), where E = 0. W is tabulated by the random walk
(:class:`WalkSpec`, ``WALK_PATHS`` paths per node on common random numbers)
up to α = 9; beyond, its F0 dependence is held there (the walk's keeps
darkening towards 0 for F0 < 1; a white surface stays exact).

The tables are interpolated linearly along the direction axes and by the
interpolating cubic B-spline (C2) along the parameter axes (:mod:`.grid`),
so that derivatives with respect to roughness, exponent and F0 are
continuous. Its coefficients are clipped at 0, so g~ >= 0 needs no clamp and
G_avg is the exact cosine-weighted integral of the *interpolated* g: the
compensated albedo is C (E_ss + g~) exactly, and the residual is the
interpolation error of g alone (and, against the walk, its Monte-Carlo
noise). The tables are shipped as data (``data/albedo.npz``), built offline
from each model's declared :class:`AlbedoSpec` and :class:`WalkSpec`
(:mod:`mi_brdfs.tools.tables`, which also checks them):

    python -m mi_brdfs.tools.tables          # rebuild every table
    python -m mi_brdfs.tools.tables --check  # their quadrature, noise and interpolation errors

so every variant (scalar ones included) loads them without computing.

**How a model supplies it: one way.** Its ``compensation()`` returns a
:class:`Compensation`: g, G_avg and C as functions of the evaluated inputs,
and the lobe it belongs to. :class:`Tabulated` is the tables' (the model
names the table and which of its parameters are the table's axes); EON's
closed form is an :class:`Analytic` one. At load time and at every update
the plugin prepares it (:meth:`Compensation.prepare`): a table is
specialised at the parameters that are constant over the surface
(:class:`Specialised`: contracted offline, with their first derivatives) and
the rest is looked up per lane in Dr.Jit, so textured parameters and
gradients keep working; the plugin holds the arrays as its member ``m_ms``,
so that a frozen function sees them as inputs.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Callable

import drjit as dr
import mitsuba as mi
import numpy as np

from .grid import Axis, Grid, midpoints

DATA = os.path.join(os.path.dirname(__file__), "data", "albedo.npz")
SAMPLES = 512             # quadrature: SAMPLES² jittered strata per node (by default)
WALK_PATHS = 40_000       # random-walk paths per node of a walk table
ONE_MINUS_MIN = 1e-7      # G_avg is kept above this (G_avg = 0: nothing to add)


# ----------------------------------------------------------------------------
#  The lobe
# ----------------------------------------------------------------------------

def ms_lobe(colour, g_i, g_o, g_avg, cos_o):
    """f_ms(ω_i, ω_o) · cos θ_o (eval convention): C g(ω_i) g(ω_o) / (π G_avg),
    reciprocal, of albedo C g(ω_i) (g >= 0, G_avg its exact average)."""
    shape = g_i * g_o / (dr.pi * dr.fmax(g_avg, ONE_MINUS_MIN))
    return colour * (shape * dr.fmax(cos_o, 0.0))


def ms_series(c, e_avg):
    """C = c² E_avg / (1 - c (1 - E_avg)): the colour of the bounces k >= 2 for
    a per-bounce reflectance c, each bounce escaping with probability E_avg
    (Kulla & Conty's series; EON's ρ_ms; per channel, c clamped to [0, 1])."""
    c = dr.fmin(dr.fmax(c, 0.0), 1.0)
    return dr.square(c) * e_avg / dr.fmax(1.0 - c * (1.0 - e_avg), ONE_MINUS_MIN)


# ----------------------------------------------------------------------------
#  What is tabulated
# ----------------------------------------------------------------------------

@dataclass(frozen=True)
class AlbedoSpec:
    """How one model's single-scattering albedo E is tabulated (by quadrature).

    ``axes``: the direction axes first — ``mu`` (cos θ, 0..1), and for an
    anisotropic lobe ``sin2phi`` (sin²φ, 0..1) or ``phi`` (the azimuth folded
    into [0, π/2]: nodes dense near both ends in sin²φ) — then the model parameters, in
    the order ``f``, ``sample`` and ``pdf`` take them after the directions:
    ``f(wi, wo, *p)`` the lobe in eval convention per unit colour,
    ``sample(wi, sample2, *p)`` a direction from its sampler,
    ``pdf(wi, wo, *p)`` that sampler's density. ``samples``: the quadrature's
    strata per axis (its error falls as ~samples^-2; 512: ~3e-5). ``valid_up_to``:
    the largest value of the first parameter the model accepts (Blinn's α <= 1);
    the nodes beyond hold the quadratic extrapolation (in the axis's warped
    coordinate) of the last three within, clipped to [0, 1], so that the
    smooth interpolation has no kink there (a linear one left errors of 6e-3
    at 85° near α = 1, the quadratic 1e-3).
    """
    name: str
    axes: tuple[Axis, ...]
    f: Callable = field(compare=False)
    sample: Callable = field(compare=False)
    pdf: Callable = field(compare=False)
    samples: int = SAMPLES
    valid_up_to: float | None = None

    @property
    def directions(self) -> int:
        return 2 if len(self.axes) > 1 and self.axes[1].name in AZIMUTHS else 1


@dataclass(frozen=True)
class WalkSpec:
    """The albedo W of the random walk on a Smith microsurface of
    ``distribution`` ("ggx" or "beckmann"), over ``axes``: the direction
    axes (mu, and sin2phi for anisotropic roughness), the roughness axes
    (alpha, or alpha_u along s and alpha_v along t), then f0; built by
    :func:`mi_brdfs.tools.groundtruth.table` (offline). The roughness nodes
    beyond ``alpha_max`` hold the last walked node's W (per roughness axis):
    there W(F0) turns into a step at F0 = 1 (W -> 0 for F0 < 1 as α -> ∞,
    every path bouncing ever longer) that no smooth interpolation in F0
    follows, and a white surface (W = 1 at F0 = 1) must stay exact."""
    name: str
    distribution: str
    axes: tuple[Axis, ...]
    alpha_max: float = 10.5
    paths: int = WALK_PATHS         # per node

    @property
    def directions(self) -> int:
        return 2 if self.axes[1].name in AZIMUTHS else 1


AZIMUTHS = ("sin2phi", "phi")     # the names of a second direction axis


def azimuth(axis: Axis, x) -> np.ndarray:
    """The azimuth φ in [0, π/2] (radians, NumPy) at the coordinate x of the
    direction axis ``axis`` (sin²φ, or φ itself)."""
    x = np.asarray(x, dtype=np.float64)
    return x if axis.name == "phi" else np.arcsin(np.sqrt(np.clip(x, 0.0, 1.0)))


# ----------------------------------------------------------------------------
#  Tables
# ----------------------------------------------------------------------------

SPECIALISED_KEPT = 4     # specialisations kept per table: a fit's least squares and
#   Jacobian update a plugin again at the constants it had (42 % of the calls in the
#   quick fits of gold alpha 0.1's compensated models hit the last 4)


class Table:
    """A function g(ω, p) >= 0 of a direction and parameters, and its
    cosine-weighted average G_avg(p), for the active variant."""

    def __init__(self, axes: tuple[Axis, ...], values: np.ndarray, directions: int = 1,
                 specs: tuple = (), bounds=(0.0, None)):
        self.axes, self.directions = tuple(axes), directions
        self.specs = tuple(specs)           # the shipped tables it is made from
        # B-spline coefficients clipped at 0: the interpolant stays >= 0 with no
        # clamp, so G_avg below is the exact integral of what is looked up. (Not
        # at 1: near F0 = 1 at large alpha, W rises steeply to 1 and a clip there
        # would pull the white surface's g below 1 - E.) ``bounds=None``: no
        # clip, for a table whose spline must pass through its nodes.
        self.grid = Grid(self.axes, values, bounds=bounds)
        weights = []
        for axis in self.axes[:directions]:
            m = 1 << 16
            if axis.name == "mu":          # (1/π) ∫ g cos θ dω = ∫ 2 μ g dμ (isotropic in φ)
                x = midpoints(m)
                w = 2.0 * x / m
            else:                          # the mean over φ in [0, π/2] (g is even in φ)
                x = 0.5 * np.pi * midpoints(m)
                x = x if axis.name == "phi" else np.sin(x) ** 2
                w = np.full(m, 1.0 / m)
            weights.append(axis.quadrature(x, w))
        self.average_grid = Grid(self.axes[directions:], self.grid.integrate(weights),
                                 coefficients=True)

    def coordinates(self, v) -> list:
        """The direction axes' coordinates of the local direction v: cos θ, and
        for an anisotropic table sin²φ or φ folded into [0, π/2]."""
        mu = dr.fmin(dr.fmax(mi.Frame3f.cos_theta(v), 0.0), 1.0)
        coords = [mu]
        if self.directions == 2 and self.axes[1].name == "phi":
            coords.append(dr.atan2(dr.abs(v.y), dr.abs(v.x)))      # 0 for v = n
        elif self.directions == 2:
            rho2 = dr.square(v.x) + dr.square(v.y)
            ok = rho2 > 0
            coords.append(dr.select(ok, dr.square(v.y) / dr.select(ok, rho2, 1.0), 0.0))
        return coords

    def __call__(self, v, *params, data: dict | None = None):
        """g at the local direction v for the parameters (>= 0)."""
        return self.grid(*self.coordinates(v), *params,
                         data=None if data is None else data["values"])

    def specialise(self, constants: tuple[float | None, ...]) -> "Specialised":
        """This table at a plugin's constant parameters (see :class:`Specialised`).
        The last ``SPECIALISED_KEPT`` are kept and handed out again for the
        same constants (they are read only)."""
        kept = self.__dict__.setdefault("_kept", {})         # oldest first
        key = tuple(constants)
        found = kept.pop(key, None)
        if found is None:
            found = Specialised(self, key)
        kept[key] = found
        if len(kept) > SPECIALISED_KEPT:
            del kept[next(iter(kept))]
        return found

    def average(self, *params, data: dict | None = None):
        """G_avg for the parameters (>= 0)."""
        return self.average_grid(*params, data=None if data is None else data["average"])


def _contract(arrays: list[np.ndarray], k: int, axis: Axis, x: float) -> list[np.ndarray]:
    """[value, derivatives...] interpolated along stored axis k at x, and the
    value's derivative with respect to x appended (NumPy). The stencil's nodes
    are read as views, not copied one by one with np.take (3-4x slower for the
    directional tables), and summed term by term, every element in the same
    order: a table symmetric in (μ_i, μ_o) stays exactly symmetric."""
    i, w, dw = axis.stencil(x)
    if i < 0 or i + len(w) > arrays[0].shape[k]:
        raise IndexError(f"stencil {i}..{i + len(w) - 1} outside axis {axis.name}'s "
                         f"{arrays[0].shape[k]} nodes")
    weigh = lambda a, weights: sum(wj * np.moveaxis(a, k, 0)[i + j] for j, wj in enumerate(weights))
    return [weigh(a, w) for a in arrays] + [weigh(arrays[0], dw)]


class Specialised:
    """A :class:`Table` at one plugin's constant parameters (``constants``: a
    float per parameter axis, or None for a parameter that varies per lane,
    e.g. a textured roughness). Those axes are contracted offline (NumPy):
    their values, and the first derivatives with respect to each of them, as
    smaller grids — so a lookup gathers 2 values per direction axis and 4 per
    varying parameter instead of 4 per parameter. A lookup adds
    (p - p0) dg/dp for a constant parameter p whose lane value carries a
    gradient: the value is unchanged (p = p0), the derivative exact."""

    def __init__(self, table: Table, constants: tuple[float | None, ...]):
        self.table, self.constants = table, tuple(constants)
        d = table.directions
        values, average = [table.grid.stored], [table.average_grid.stored]
        kept, kept_average = list(table.axes), list(table.axes[d:])
        self.fixed = [j for j, c in enumerate(constants) if c is not None]
        for j in reversed(self.fixed):              # last axes first: indices stay valid
            values = _contract(values, d + j, kept.pop(d + j), constants[j])
            average = _contract(average, j, kept_average.pop(j), constants[j])
        # derivatives were appended last-axis first: back to the order of self.fixed
        values = values[:1] + values[:0:-1]
        average = average[:1] + average[:0:-1]
        self.values = [Grid(tuple(kept), a, coefficients=True) for a in values]
        self.average_grids = [Grid(tuple(kept_average), a, coefficients=True) for a in average]
        refs = [dr.opaque(mi.Float, constants[j]) if dr.is_jit_v(mi.Float) else constants[j]
                for j in self.fixed]
        self.data = {"values": [g.data for g in self.values],
                     "average": [g.data for g in self.average_grids], "refs": refs}

    def _lookup(self, grids, arrays, coords, params, data):
        varying = [p for j, p in enumerate(params) if self.constants[j] is None]
        out = grids[0](*coords, *varying, data=data[arrays][0])
        for n, j in enumerate(self.fixed, start=1):
            p = params[j]
            if dr.is_array_v(p) and dr.grad_enabled(p):
                out = out + (p - data["refs"][n - 1]) * grids[n](*coords, *varying,
                                                                  data=data[arrays][n])
        return out

    def __call__(self, v, params: tuple, data: dict):
        """g at the local direction v for the model's table parameters (lanes)."""
        return self._lookup(self.values, "values", self.table.coordinates(v), params, data)

    def average(self, params: tuple, data: dict):
        """G_avg for the model's table parameters."""
        return self._lookup(self.average_grids, "average", [], params, data)


class TableError(RuntimeError):
    """The shipped tables are missing or do not match their specification."""


_data: dict[str, np.ndarray] | None = None
_tables: dict[tuple[str, str], Table] = {}


def shipped(spec) -> np.ndarray:
    """The shipped node values of ``spec`` (an AlbedoSpec or a WalkSpec)."""
    global _data
    if _data is None:
        if not os.path.exists(DATA):
            raise TableError(f"{DATA} is missing: run python -m mi_brdfs.tools.tables")
        with np.load(DATA) as f:
            _data = {k: f[k] for k in f.files}
    values = _data.get(spec.name)
    shape = tuple(a.n for a in spec.axes)
    if values is None or values.shape != shape:
        raise TableError(f"albedo table {spec.name!r} in {DATA} does not match its axes "
                         f"{shape}: run python -m mi_brdfs.tools.tables")
    return values.astype(np.float64)


def _cached(name: str, make: Callable[[], Table]) -> Table:
    key = (mi.variant(), name)
    if key not in _tables:
        _tables[key] = make()
    return _tables[key]


def table(spec: AlbedoSpec) -> Table:
    """The shipped single-scattering albedo E of ``spec`` and its average E_avg."""
    return _cached(spec.name, lambda: Table(spec.axes, shipped(spec), spec.directions, (spec,)))


def complement(spec: AlbedoSpec) -> Table:
    """g = 1 - E: the compensation of a lobe that reflects all it does not
    lose (its average is 1 - E_avg)."""
    return _cached("1 - " + spec.name,
                   lambda: Table(spec.axes, 1.0 - shipped(spec), spec.directions, (spec,)))


def walk_residual(white: AlbedoSpec, black: AlbedoSpec, walk: WalkSpec) -> Table:
    """g(ω, α, F0) = W - (F0 E(F = 1) + (1 - F0) E(F0 = 0)), clamped at 0: what a
    microfacet model's single scattering misses of the random walk (the
    walk's axes are those of ``white`` and ``black``, then F0)."""
    def make() -> Table:
        e1, e0, w = shipped(white), shipped(black), shipped(walk)
        f0 = walk.axes[-1].nodes()
        single = f0 * e1[..., None] + (1.0 - f0) * e0[..., None]
        return Table(walk.axes, np.clip(w - single, 0.0, 1.0), walk.directions,
                     (white, black, walk))
    return _cached(f"{walk.name} - {white.name}", make)




# ----------------------------------------------------------------------------
#  What a model supplies: a Compensation
# ----------------------------------------------------------------------------

class Compensation:
    """The multiple-scattering lobe of one plugin instance: g(ω), G_avg and the
    colour C as functions of the model's evaluated inputs ``inp`` (traced),
    and the lobe it belongs to (``"diffuse"`` or ``"specular"``: the lobe whose
    weight it takes, whose kind a sample of it reports, and without which it
    is not traced). ``data`` is what the plugin holds as its member ``m_ms``
    (Dr.Jit arrays a frozen function must see as inputs, or None).

    The plugin holds its Compensation, so nothing here may hold the plugin
    (a lambda over ``self``, a bound method): the cycle would keep the plugin
    and its Dr.Jit arrays alive until Python's cyclic garbage collector runs,
    and when that happens inside a differentiable render, Dr.Jit's AD raises
    ("tried to forward-propagate derivatives across edge ... outside of the
    current dr.isolate_grad() scope"). What a callable needs comes in ``inp``;
    tests/bsdfs/test_registry.py checks that every plugin is freed by
    reference counting alone."""

    lobe = "specular"

    def prepare(self, plugin) -> dict | None:
        """At load time and at every update: fix what is constant over the
        surface; returns the arrays the plugin holds as ``m_ms``."""
        return None

    def albedo(self, inp, v, data):
        """g(v) >= 0 per unit colour at the local direction v."""
        raise NotImplementedError

    def average(self, inp, data):
        """G_avg, the cosine-weighted average of g."""
        raise NotImplementedError

    def colour(self, inp):
        """C, the colour that scales the lobe."""
        raise NotImplementedError

    def value(self, inp, wi, wo, ms, data):
        """f_ms·cos θ_o at (wi, wo), the colour included; ``ms`` = (g(ω_i),
        G_avg, C) as :meth:`.mixture.Mixture.inputs` gives them. The separable
        lobe (:func:`ms_lobe`) unless a model's compensation is shaped
        otherwise (:class:`.directional.Directional`)."""
        g_i, g_avg, colour = ms
        return ms_lobe(colour, g_i, self.albedo(inp, wo, data), g_avg, mi.Frame3f.cos_theta(wo))

    def key(self) -> tuple:
        """What a traced call depends on beyond the plugin's own plan (a frozen
        function records again when it changes)."""
        return ()


def coloured(x) -> bool:
    """True for a colour (or spectrum) of channels, False for one number per lane."""
    return dr.is_array_v(x) and dr.size_v(x) > 0


def per_channel(lookup: Callable, params: tuple):
    """``lookup(params)``, or, where a parameter is a colour (an F0 per colour
    channel or wavelength), one lookup per channel gathered into that colour:
    the table's axes are numbers, its g per channel then."""
    colour = next((p for p in params if coloured(p)), None)
    if colour is None:
        return lookup(params)
    return type(colour)(*(lookup(tuple(p[c] if coloured(p) else p for p in params))
                          for c in range(dr.size_v(colour))))


class Tabulated(Compensation):
    """g from a :class:`Table` over (directions, p_1, ..., p_k): ``parameters(inp)``
    gives the p_j at a lane, ``sources`` names the plugin parameter each comes
    from (a constant one is contracted away at :meth:`prepare`), ``colour(inp)``
    is C."""

    def __init__(self, table: Table, parameters: Callable, sources: tuple[str, ...],
                 colour: Callable, lobe: str = "specular"):
        self.table, self.parameters, self.sources = table, parameters, tuple(sources)
        self.colour_of, self.lobe = colour, lobe
        self.specialised: Specialised | None = None

    def prepare(self, plugin) -> dict:
        inp = plugin.eval_textures(dr.zeros(mi.SurfaceInteraction3f), True)
        members = [None if name is None else getattr(plugin, "m_" + name)
                   for name in self.sources]
        constants = tuple(None if obj is None or coloured(x)
                          or (isinstance(obj, mi.Object) and obj.is_spatially_varying())
                          else float(x[0]) if dr.is_array_v(x) else float(x)
                          for obj, x in zip(members, self.parameters(inp)))
        self.specialised = self.table.specialise(constants)
        return self.specialised.data

    def albedo(self, inp, v, data):
        return per_channel(lambda p: self.specialised(v, p, data), self.parameters(inp))

    def average(self, inp, data):
        return per_channel(lambda p: self.specialised.average(p, data), self.parameters(inp))

    def colour(self, inp):
        return self.colour_of(inp)

    def key(self) -> tuple:
        return tuple(self.specialised.fixed) if self.specialised is not None else ()


class Analytic(Compensation):
    """g, G_avg and C in closed form (e.g. EON's)."""

    def __init__(self, albedo: Callable, average: Callable, colour: Callable,
                 lobe: str = "diffuse"):
        self.albedo_of, self.average_of, self.colour_of, self.lobe = albedo, average, colour, lobe

    def albedo(self, inp, v, data):
        return self.albedo_of(inp, v)

    def average(self, inp, data):
        return self.average_of(inp)

    def colour(self, inp):
        return self.colour_of(inp)
