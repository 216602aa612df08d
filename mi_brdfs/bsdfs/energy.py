"""Energy compensation: the multiple-scattering lobe every compensated model shares.

A single-scattering lobe of directional albedo E(ω) < 1 (per unit colour)
loses the light that, in a real rough surface, scatters more than once before
leaving. Kulla & Conty ("Revisiting Physically Based Shading at Imageworks",
SIGGRAPH 2017 course) and Turquin ("Practical multiple scattering compensation
for microfacet models", 2019) add the reciprocal lobe

    f_ms(ω_i, ω_o) = F_ms · (1 - E(ω_i)) (1 - E(ω_o)) / (π (1 - E_avg)),
    E_avg = (1/π) ∫ E(ω) cos θ dω,

whose albedo is F_ms (1 - E(ω_i)): with F_ms = 1 a white surface reflects
E + (1 - E) = 1 at every angle. Its colour is the sum over bounces k >= 2 of a
per-bounce reflectance c (Kulla & Conty's average Fresnel F_avg, here m_S·F_avg
for a coloured microfacet model, m_S for Phong, Blinn and Ward, ρ for
Oren-Nayar), each bounce escaping with probability E_avg:

    F_ms = c² E_avg / (1 - c (1 - E_avg))

so coloured surfaces saturate with each bounce instead of greying. The same
form, with the analytic E of Fujii's Oren-Nayar, is the energy-preserving
Oren-Nayar model (EON, Portsmouth, Kutz & Hill, JCGT 2025).

**Tables.** Where E has no closed form it is tabulated from the model's own
single-scattering formula: E(μ, p) = ∫ f(ω_i, ω_o; p) dω_o (``f`` in eval
convention, colour 1) by a deterministic quadrature over the model's own
sampler (one jittered point u in each of SAMPLES² strata of the unit square,
a fixed seed; E = mean of f / pdf at ω_o = sample(u)). Each :class:`AlbedoSpec` declares the axes: the direction
(cos θ_i, and sin²φ_i for anisotropic lobes), then the model's parameters
(roughness, exponent). E is clamped to [0, 1] (Ward's albedo exceeds 1 within
a fraction of a degree of the horizon; there no light is added). The node
μ = 0 holds E at μ = ``MU_MIN``. E_avg is the exact cosine-weighted integral
of the *interpolated* table, so the compensated albedo is 1 up to the table's
interpolation error alone.

The tables are shipped as data (``data/albedo.npz``), made by

    python -m mi_brdfs.tools.tables          # rebuild every table (~20 s)
    python -m mi_brdfs.tools.tables --check  # their quadrature and interpolation errors

so every variant (scalar ones included) loads them without computing; they
are looked up with multilinear interpolation in Dr.Jit (:mod:`.grid`), so
textured parameters and gradients keep working.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Callable

import drjit as dr
import mitsuba as mi
import numpy as np

from .grid import Axis, Grid, hemisphere_direction, midpoints

DATA = os.path.join(os.path.dirname(__file__), "data", "albedo.npz")
MU_MIN = 1e-4             # the cos θ at which the μ = 0 node is computed
SAMPLES = 128             # quadrature: SAMPLES² jittered strata per node
SEED = 20261130           # of the jitter
ONE_MINUS_MIN = 1e-7      # 1 - E_avg is kept above this (E_avg = 1: nothing to add)


# ----------------------------------------------------------------------------
#  The lobe
# ----------------------------------------------------------------------------

def ms_colour(c, e_avg):
    """F_ms = c² E_avg / (1 - c (1 - E_avg)): the multiply scattered colour for
    a per-bounce reflectance c (per channel, clamped to [0, 1] for the series)."""
    c = dr.fmin(dr.fmax(c, 0.0), 1.0)
    return dr.square(c) * e_avg / dr.fmax(1.0 - c * (1.0 - e_avg), ONE_MINUS_MIN)


def ms_lobe(f_ms, e_i, e_o, e_avg, cos_o):
    """f_ms(ω_i, ω_o) · cos θ_o (eval convention): reciprocal, of albedo f_ms (1 - E(ω_i))."""
    one = lambda e: 1.0 - dr.fmin(dr.fmax(e, 0.0), 1.0)
    shape = one(e_i) * one(e_o) / (dr.pi * dr.fmax(one(e_avg), ONE_MINUS_MIN))
    return f_ms * (shape * dr.fmax(cos_o, 0.0))


# ----------------------------------------------------------------------------
#  Albedo tables
# ----------------------------------------------------------------------------

@dataclass(frozen=True)
class AlbedoSpec:
    """How one model's single-scattering albedo is tabulated.

    ``axes``: the direction axes first — ``mu`` (cos θ, 0..1), and for an
    anisotropic lobe ``sin2phi`` (sin²φ, 0..1) — then the model parameters, in
    the order ``f``, ``sample`` and ``pdf`` take them after the directions:
    ``f(wi, wo, *p)`` the lobe in eval convention per unit colour,
    ``sample(wi, sample2, *p)`` a direction from its sampler,
    ``pdf(wi, wo, *p)`` that sampler's density.
    """
    name: str
    axes: tuple[Axis, ...]
    f: Callable = field(compare=False)
    sample: Callable = field(compare=False)
    pdf: Callable = field(compare=False)

    @property
    def directions(self) -> int:
        return 2 if len(self.axes) > 1 and self.axes[1].name == "sin2phi" else 1


class AlbedoTable:
    """E(ω, p) and E_avg(p) of one :class:`AlbedoSpec`, for the active variant."""

    def __init__(self, spec: AlbedoSpec, values: np.ndarray):
        self.spec = spec
        self.grid = Grid(spec.axes, values)
        weights = []
        for axis in spec.axes[:spec.directions]:
            m = 1 << 16
            if axis.name == "mu":          # (1/π) ∫ E cos θ dω = ∫ 2 μ E dμ (isotropic in φ)
                x = midpoints(m)
                w = 2.0 * x / m
            else:                          # the mean over φ in [0, π/2] (E is even in φ)
                x = np.sin(0.5 * np.pi * midpoints(m)) ** 2
                w = np.full(m, 1.0 / m)
            weights.append(axis.quadrature(x, w))
        self.average_grid = Grid(spec.axes[spec.directions:],
                                 self.grid.integrate(weights))

    def __call__(self, v, *params):
        """E at the local direction v (clamped to [0, 1]) for the parameters."""
        mu = dr.fmin(dr.fmax(mi.Frame3f.cos_theta(v), 0.0), 1.0)
        coords = [mu]
        if self.spec.directions == 2:
            rho2 = dr.square(v.x) + dr.square(v.y)
            ok = rho2 > 0
            coords.append(dr.select(ok, dr.square(v.y) / dr.select(ok, rho2, 1.0), 0.0))
        return dr.fmin(dr.fmax(self.grid(*coords, *params), 0.0), 1.0)

    def average(self, *params):
        """E_avg for the parameters."""
        return dr.fmin(dr.fmax(self.average_grid(*params), 0.0), 1.0)


_tables: dict[tuple[str, str], AlbedoTable] = {}
_data: dict[str, np.ndarray] | None = None


class TableError(RuntimeError):
    """The shipped tables are missing or do not match their specification."""


def table(spec: AlbedoSpec) -> AlbedoTable:
    """The shipped table of ``spec`` for the active variant (loaded once)."""
    global _data
    key = (mi.variant(), spec.name)
    if key not in _tables:
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
        _tables[key] = AlbedoTable(spec, values)
    return _tables[key]


# ----------------------------------------------------------------------------
#  Building the tables (JIT variants)
# ----------------------------------------------------------------------------

def build(spec: AlbedoSpec, samples: int = SAMPLES, batch: int = 1 << 22) -> np.ndarray:
    """E at every node of ``spec``, by quadrature over the model's sampler."""
    nodes = [a.nodes() for a in spec.axes]
    grid = np.stack(np.meshgrid(*nodes, indexing="ij"), axis=-1).reshape(-1, len(nodes))
    d = spec.directions
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
        node = mi.UInt32(np.repeat(np.arange(n, dtype=np.uint32), per))
        take = lambda a: dr.gather(mi.Float, mi.Float(np.ascontiguousarray(a[sl])), node)
        wi = mi.Vector3f(take(wi_np[:, 0]), take(wi_np[:, 1]), take(wi_np[:, 2]))
        params = [take(params_np[:, k]) for k in range(params_np.shape[1])]
        sample2 = mi.Point2f(np.tile(ux, n), np.tile(uy, n))
        wo = spec.sample(wi, sample2, *params)
        pdf = spec.pdf(wi, wo, *params)
        ok = (pdf > 0) & (mi.Frame3f.cos_theta(wo) > 0)
        value = dr.select(ok, spec.f(wi, wo, *params) / dr.select(ok, pdf, 1.0), 0.0)
        total = dr.block_sum(mi.Float64(value), per)
        out[sl] = np.asarray(total) / per
    return np.clip(out, 0.0, 1.0).reshape(tuple(a.n for a in spec.axes))


def specs() -> list[AlbedoSpec]:
    """Every table of every model (imported here: the models import this module)."""
    from . import PLUGINS
    found = []
    for cls in PLUGINS:
        for spec in getattr(cls, "albedo_specs", lambda: [])():
            if spec.name not in {s.name for s in found}:
                found.append(spec)
    return found
