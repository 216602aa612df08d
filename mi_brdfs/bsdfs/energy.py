"""Energy compensation: the multiple-scattering lobe every compensated model shares.

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
--decomposition``: see ``docs/guide/energy.md``). For the Blinn D and the V-cavity G,
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
noise). The tables are shipped as data (``data/albedo.npz``), made by

    python -m mi_brdfs.tools.tables          # rebuild every table
    python -m mi_brdfs.tools.tables --check  # their quadrature, noise and interpolation errors

so every variant (scalar ones included) loads them without computing. A
plugin specialises its table at the parameters that are constant over its
surface (:class:`Specialised`: contracted offline, with their first
derivatives) and looks the rest up per lane in Dr.Jit, so textured
parameters and gradients keep working; it holds the arrays as its member
``m_ms``, so that a frozen function sees them as inputs.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Callable

import drjit as dr
import mitsuba as mi
import numpy as np

from .._jit import from_numpy
from .grid import Axis, Grid, hemisphere_direction, midpoints

DATA = os.path.join(os.path.dirname(__file__), "data", "albedo.npz")
MU_MIN = 1e-4             # the cos θ at which the μ = 0 node is computed
SAMPLES = 512             # quadrature: SAMPLES² jittered strata per node (by default)
SEED = 20261130           # of the jitter
WALK_PATHS = 40_000       # random-walk paths per node of a walk table
WALK_SEED = 20160701      # of the walk
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
    anisotropic lobe ``sin2phi`` (sin²φ, 0..1) — then the model parameters, in
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
        return 2 if len(self.axes) > 1 and self.axes[1].name == "sin2phi" else 1


@dataclass(frozen=True)
class WalkSpec:
    """The albedo W(μ, α, F0) of the random walk on a Smith microsurface of
    ``distribution`` ("ggx" or "beckmann"), over ``axes`` (mu, alpha, f0);
    built by :func:`mi_brdfs.tools.groundtruth.table`. The α nodes beyond
    ``alpha_max`` hold the last walked node's W: there W(F0) turns into a
    step at F0 = 1 (W -> 0 for F0 < 1 as α -> ∞, every path bouncing ever
    longer) that no smooth interpolation in F0 follows, and a white surface
    (W = 1 at F0 = 1) must stay exact."""
    name: str
    distribution: str
    axes: tuple[Axis, ...]
    alpha_max: float = 10.5
    directions = 1


# ----------------------------------------------------------------------------
#  Tables
# ----------------------------------------------------------------------------

class Table:
    """A function g(ω, p) >= 0 of a direction and parameters, and its
    cosine-weighted average G_avg(p), for the active variant."""

    def __init__(self, axes: tuple[Axis, ...], values: np.ndarray, directions: int = 1):
        self.axes, self.directions = tuple(axes), directions
        # B-spline coefficients clipped at 0: the interpolant stays >= 0 with no
        # clamp, so G_avg below is the exact integral of what is looked up. (Not
        # at 1: near F0 = 1 at large alpha, W rises steeply to 1 and a clip there
        # would pull the white surface's g below 1 - E.)
        self.grid = Grid(self.axes, values, bounds=(0.0, None))
        weights = []
        for axis in self.axes[:directions]:
            m = 1 << 16
            if axis.name == "mu":          # (1/π) ∫ g cos θ dω = ∫ 2 μ g dμ (isotropic in φ)
                x = midpoints(m)
                w = 2.0 * x / m
            else:                          # the mean over φ in [0, π/2] (g is even in φ)
                x = np.sin(0.5 * np.pi * midpoints(m)) ** 2
                w = np.full(m, 1.0 / m)
            weights.append(axis.quadrature(x, w))
        self.average_grid = Grid(self.axes[directions:], self.grid.integrate(weights),
                                 coefficients=True)

    def coordinates(self, v) -> list:
        """The direction axes' coordinates of the local direction v: cos θ, and
        sin²φ for an anisotropic table."""
        mu = dr.fmin(dr.fmax(mi.Frame3f.cos_theta(v), 0.0), 1.0)
        coords = [mu]
        if self.directions == 2:
            rho2 = dr.square(v.x) + dr.square(v.y)
            ok = rho2 > 0
            coords.append(dr.select(ok, dr.square(v.y) / dr.select(ok, rho2, 1.0), 0.0))
        return coords

    def __call__(self, v, *params, data: dict | None = None):
        """g at the local direction v for the parameters (>= 0)."""
        return self.grid(*self.coordinates(v), *params,
                         data=None if data is None else data["values"])

    def specialise(self, constants: tuple[float | None, ...]) -> "Specialised":
        """This table at a plugin's constant parameters (see :class:`Specialised`)."""
        return Specialised(self, constants)

    def average(self, *params, data: dict | None = None):
        """G_avg for the parameters (>= 0)."""
        return self.average_grid(*params, data=None if data is None else data["average"])


def _contract(arrays: list[np.ndarray], k: int, axis: Axis, x: float) -> list[np.ndarray]:
    """[value, derivatives...] interpolated along stored axis k at x, and the
    value's derivative with respect to x appended (NumPy)."""
    i, w, dw = axis.stencil(x)
    take = lambda a, weights: sum(wj * np.take(a, i + j, axis=k) for j, wj in enumerate(weights))
    return [take(a, w) for a in arrays] + [take(arrays[0], dw)]


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
    return _cached(spec.name, lambda: Table(spec.axes, shipped(spec), spec.directions))


def complement(spec: AlbedoSpec) -> Table:
    """g = 1 - E: the compensation of a lobe that reflects all it does not
    lose (its average is 1 - E_avg)."""
    return _cached("1 - " + spec.name,
                   lambda: Table(spec.axes, 1.0 - shipped(spec), spec.directions))


def microfacet(white: AlbedoSpec, black: AlbedoSpec, walk: WalkSpec) -> Table:
    """g(μ, α, F0) = W - (F0 E(F = 1) + (1 - F0) E(F0 = 0)), clamped at 0: what a
    microfacet model's single scattering misses of the random walk (the
    walk's (μ, α) axes are those of ``white`` and ``black``)."""
    def make() -> Table:
        e1, e0, w = shipped(white), shipped(black), shipped(walk)
        f0 = walk.axes[2].nodes()
        single = f0 * e1[..., None] + (1.0 - f0) * e0[..., None]
        return Table(walk.axes, np.clip(w - single, 0.0, 1.0), 1)
    return _cached(f"{walk.name} - {white.name}", make)


# ----------------------------------------------------------------------------
#  Building the single-scattering tables (JIT variants)
# ----------------------------------------------------------------------------

def build(spec: AlbedoSpec, samples: int | None = None, batch: int = 1 << 22) -> np.ndarray:
    """E at every node of ``spec``, by quadrature over the model's sampler
    (``samples`` strata per axis, default the spec's). A parameter node at
    infinity (a roughness axis's last) holds E = 0."""
    samples = samples or spec.samples
    nodes = [a.nodes() for a in spec.axes]
    grid = np.stack(np.meshgrid(*nodes, indexing="ij"), axis=-1).reshape(-1, len(nodes))
    d = spec.directions
    infinite = np.isinf(grid).any(axis=1)
    grid = grid[~infinite]
    mu = np.maximum(grid[:, 0], MU_MIN)
    wi_np = hemisphere_direction(mu, grid[:, 1] if d == 2 else None)
    params_np = grid[:, d:]
    # Jittered strata (a fixed seed): the midpoints alone alias with samplers
    # that split the square (GGX's visible normals: 0.998 instead of 0.976).
    rng = np.random.default_rng(SEED)
    i, j = (a.ravel() for a in np.meshgrid(np.arange(samples), np.arange(samples), indexing="ij"))
    ux = (i + rng.random(i.size)) / samples
    uy = (j + rng.random(j.size)) / samples
    per = samples * samples
    out = np.empty(len(grid))
    step = max(1, batch // per)
    for start in range(0, len(grid), step):
        sl = slice(start, min(start + step, len(grid)))
        n = sl.stop - sl.start
        node = from_numpy(mi.UInt32, np.repeat(np.arange(n, dtype=np.uint32), per))
        take = lambda a: dr.gather(mi.Float, from_numpy(mi.Float, a[sl]), node)
        wi = mi.Vector3f(take(wi_np[:, 0]), take(wi_np[:, 1]), take(wi_np[:, 2]))
        params = [take(params_np[:, k]) for k in range(params_np.shape[1])]
        sample2 = from_numpy(mi.Point2f, (np.tile(ux, n), np.tile(uy, n)))
        wo = spec.sample(wi, sample2, *params)
        pdf = spec.pdf(wi, wo, *params)
        ok = (pdf > 0) & (mi.Frame3f.cos_theta(wo) > 0)
        value = dr.select(ok, spec.f(wi, wo, *params) / dr.select(ok, pdf, 1.0), 0.0)
        total = dr.block_sum(mi.Float64(value), per)
        out[sl] = np.asarray(total) / per
    values = np.zeros(len(infinite))
    values[~infinite] = np.clip(out, 0.0, 1.0)
    values = values.reshape(tuple(a.n for a in spec.axes))
    if spec.valid_up_to is not None:
        k = spec.directions
        x = spec.axes[k].nodes()
        last = int(np.searchsorted(x, spec.valid_up_to, side="right")) - 1   # last valid node
        v = np.moveaxis(values, k, 0)
        d1 = 1.5 * v[last] - 2.0 * v[last - 1] + 0.5 * v[last - 2]     # one-sided slope
        d2 = v[last] - 2.0 * v[last - 1] + v[last - 2]                 # and curvature
        for j in range(last + 1, len(x)):
            v[j] = v[last] + (j - last) * d1 + 0.5 * (j - last) ** 2 * d2
        values = np.clip(np.moveaxis(v, 0, k), 0.0, 1.0)
    return values


def specs() -> list:
    """Every table of every model, AlbedoSpecs and WalkSpecs (imported here:
    the models import this module)."""
    from . import PLUGINS
    found = []
    for cls in PLUGINS:
        for spec in getattr(cls, "albedo_specs", lambda: [])():
            if spec.name not in {s.name for s in found}:
                found.append(spec)
    return found
