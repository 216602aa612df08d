r"""The random walk on the Smith microsurface, in the renderer: the full BRDF
of a microfacet conductor, evaluated and sampled stochastically.

Heitz, Hanika, d'Eon & Dachsbacher 2016, "Multiple-Scattering Microfacet
BSDFs with the Smith Model" (ACM TOG 35(4)): the Smith microsurface is a
volume of facets; light that enters it is reflected from facet to facet
until it leaves through the top. What we take from the paper: the model (a
volume whose extinction along w is the projected area of the facets facing
w, free flights in height, the visible normals as the phase function), its
stochastic **sampling** (walk until the path leaves: the exit direction is
the sample, the product of the Fresnel factors its weight) and its
stochastic **evaluation** (next-event estimation toward the light at every
facet met). This is what Blender Cycles ships as "Multiscatter GGX". The
coordinates, the loop and the symmetric estimator below are our own; the
model is exactly the project's NumPy walk (:mod:`mi_brdfs.tools.groundtruth.walk`,
whose docstring derives it), which the tests hold this module to.

**Depth.** τ = -ln C1(h) (0 at the top). Along a direction w the
microsurface is a homogeneous medium in τ of extinction |Λ(w)| per unit of τ,
Λ(w) = A(-w)/w_z with A the projected area (:func:`projected_area`), so a
free flight of E ~ Exp(1) moves a path to τ' = τ - E w_z / A(-w); going up,
τ' <= 0 means it has left. The masking of w at depth τ is G1(w, τ) = exp(-τ Λ(w)).

**Phase function.** At a facet the path arriving along w sees it from
wb = -w: a normal m is drawn from the normals visible from wb (any wb, above
or below the horizon: :func:`sample_visible`), the path is mirrored about it
and its weight multiplied by F(wb·m), the plugin's Fresnel form at every
bounce (Schlick's with ``f0``, as the NumPy walk; the exact forms alike).

**Evaluation** (``eval``, f·cos θ_o). The first bounce in closed form, the
height-correlated single scattering (Heitz 2014, eq. 99),

.. math::

    f_1 \cos\theta_o = \frac{F(\omega_i\cdot h)\,D(h)\,\cos\theta_o}
        {4\,(\cos\theta_o\,A(-\omega_i) + \cos\theta_i\,A(\omega_o))},

then the bounces k >= 2 by next-event estimation: at each facet met from wb
at depth τ, F(wb·h) D(h) / (4 A(wb)) G1(wo, τ) with h = (wb + wo)/|wb + wo|
(the phase function toward wo times the chance of leaving along it). Its
expectation X(wi → wo) is f_ms·cos θ_o. **Reciprocity**: a walk from one
end is reciprocal in expectation only (its random numbers follow that end);
we walk from both, X from wi toward wo and Y from wo toward wi (whose
expectation is f_ms·cos θ_i, the walk's BRDF being reciprocal), and take

.. math::

    \hat f_{ms} = \frac{X + Y}{\cos\theta_i + \cos\theta_o},

the weights cos θ_o/(cos θ_i + cos θ_o) on X/cos θ_o and cos θ_i/(...) on
Y/cos θ_i: unbiased, no division by the cosine of a grazing end (which
estimating f from Y alone would need), and, since the
random numbers of the walk from a toward b are a hash of (a, b, si.uv),
**reciprocal per evaluation** to float precision, not only in expectation.
Two walks per call: twice the cost of one.

**Random numbers.** Mitsuba's ``eval`` takes none: a PCG32 stream per lane
is seeded by a hash (TEA) of the bits of the directions and of ``si.uv``,
which a renderer changes at every call (tests average over random uv);
``sample`` seeds it from ``sample1`` and ``sample2``.

**Sampling** (``sample``): the walk from wi until the path leaves; wo its
exit direction, the weight the product of the Fresnel factors (1 for F = 1:
the white furnace holds sample by sample). A path still inside after
:data:`MAX_BOUNCES` facets is dropped (weight 0): none up to α = 10 in the
tests; the bounces grow with α, and from α ~ 20 (GGX seen from the normal)
light is lost, most of it by α ~ 100.

**The pdf.** The walk's exit density is f·cos θ_o / (albedo), which has no
closed form. ``pdf`` returns a deterministic stand-in that MIS weights use,

.. math::

    \tilde p(\omega_o) = (1 - q)\,\frac{D(h)\,G_1(\omega_i)}{4\cos\theta_i}
        + q\,\frac{\cos\theta_o}{\pi}, \qquad q = \max(1 - G_1(\omega_i), q_{min}),

the visible-normal density of single scattering and a cosine lobe for the
bounces after it. A sample's weight is not f/p̃ but the
walk's own (an unbiased f·cos/p of the true density), so a path tracer's
MIS stays unbiased: its weights need only sum to 1 over the strategies, and
``pdf``, ``eval_pdf`` and ``BSDFSample3f.pdf`` give the same p̃. A χ² test of
the sampler against p̃ must fail; the tests compare the sampler with ``eval``
instead (and both with the NumPy walk).

**Derivatives**: the single scattering and p̃ are differentiated; the walks
run under ``dr.suspend_grad`` (their part of eval and the sample weights are
constants to an optimiser).

Traced code: Dr.Jit only (one symbolic loop per walk with a bounce cap,
masks and ``dr.select``), every function of local directions; ``kind`` is
"ggx" or "beckmann", ``ax``/``ay`` the roughness along s and t.
"""
from __future__ import annotations

import math
import struct
from typing import Callable, NamedTuple

import drjit as dr
import mitsuba as mi

from .microfacet import Microfacet, dot, half_vector

MAX_BOUNCES = 64          # facets a path meets at most (a longer one is dropped)
Q_MIN = 0.1               # the least weight of the pdf's cosine lobe
NEWTON_STEPS = 20         # safeguarded Newton steps of the Beckmann visible slope
SLOPE_TAIL = 6.0          # the slope bracket reaches this far into the Gaussian tail
AREA_MIN = 1e-30          # a projected area's floor where it divides
DEN_MIN = 1e-18           # a denominator's floor whose square (its derivative) is normal
A_MAX = 9.0               # Beckmann: |cot θ / α| beyond which A(w) is max(z, 0) in float32
INV_SQRT_PI = 1.0 / math.sqrt(math.pi)


class Surface(NamedTuple):
    """The microsurface at a lane: its distribution and roughness."""
    kind: str             # "ggx" or "beckmann"
    ax: object            # α along s (local x)
    ay: object            # α along t (local y)
    microfacet: Microfacet   # the same, as the plugin's D and G1 (visible normals)


def surface(microfacet: Microfacet) -> Surface:
    """The walk's surface of a plugin's :class:`.Microfacet` (Beckmann or GGX)."""
    ay = microfacet.alpha if microfacet.isotropic else microfacet.alpha_v
    visible = Microfacet(microfacet.kind, microfacet.alpha, microfacet.alpha_v, True)
    return Surface(microfacet.kind, microfacet.alpha, ay, visible)


# ----------------------------------------------------------------------------
#  The microsurface: projected area, masking at a depth, visible normals
# ----------------------------------------------------------------------------

def erfcx(x):
    """exp(x²) erfc(x) for x >= 0 (Numerical Recipes' erfcc, Press et al. 1992,
    §6.2: fractional error below 1.2e-7 everywhere), without the exp(-x²)
    that underflows."""
    t = 1.0 / (1.0 + 0.5 * x)
    poly = -1.26551223 + t * (1.00002368 + t * (0.37409196 + t * (0.09678418 + t * (
        -0.18628806 + t * (0.27886807 + t * (-1.13520398 + t * (1.48851587 + t * (
            -0.82215223 + t * 0.17087277))))))))
    return t * dr.exp(poly)


def projected_area(s: Surface, w):
    """A(w) = ∫ max(0, w·m) D(m) dm, for any unit w (0 straight down), with
    r = α(φ) sin θ and z = cos θ (Heitz 2014): GGX (z + sqrt(z² + r²))/2,
    Beckmann z erfc(-z/r)/2 + r exp(-z²/r²)/(2 sqrt π); below the horizon in
    forms that keep their relative precision (no cancellation of two terms)."""
    z = w.z
    # (safe_sqrt: a finite derivative at r = 0, along the normal)
    r = dr.safe_sqrt(dr.square(s.ax * w.x) + dr.square(s.ay * w.y))
    if s.kind == "ggx":
        h = dr.sqrt(dr.fma(z, z, r * r))
        below = r * r / (2.0 * dr.select(z < 0.0, h - z, 1.0))   # (h - z >= 2|z| there)
        return dr.select(z >= 0.0, 0.5 * (z + h), below)
    # |a| <= A_MAX: beyond, erfc(|a|) and e^(-a²) are 0 in float32 (and a² would
    # overflow, its derivative with it); r held >= |z|/A_MAX so that the
    # division's derivative stays finite
    a = z / dr.fmax(r, dr.fmax(dr.abs(z) * (1.0 / A_MAX), AREA_MIN))
    gauss = dr.exp(-a * a)
    # z >= 0: z (1 - erfc(a)/2) + r e^(-a²)/(2 sqrt π); z < 0: e^(-a²) (r/(2 sqrt π) + z erfcx(-a)/2)
    x = dr.abs(a)
    ex = erfcx(x)
    up = z * (1.0 - 0.5 * ex * gauss) + r * gauss * (0.5 * INV_SQRT_PI)
    down = gauss * (r * (0.5 * INV_SQRT_PI) + 0.5 * z * ex)
    return dr.fmax(dr.select(z >= 0.0, up, down), 0.0)


def masking(s: Surface, w, tau):
    """G1(w, τ) = exp(-τ Λ(w)) of a direction w above the horizon at depth τ
    (1 at the top, 0 for w on or below the horizon under it)."""
    lam = projected_area(s, -w) / dr.fmax(w.z, 0.0)        # Λ(w); inf at the horizon
    return dr.select(w.z > 0.0, dr.exp(-dr.select(tau > 0.0, tau * lam, 0.0)), 0.0)


def _beckmann_slope(cos_t, sin_t, u):
    """The x-slope s (along the direction's azimuth, α = 1) of a Beckmann
    normal visible from a direction at cos θ, sin θ >= 0, any cos θ: the
    slopes s <= cot θ with density ∝ (cos θ - s sin θ) e^(-s²), whose integral
    up to s is P(s) = cos θ erfc(-s)/2 + sin θ e^(-s²)/(2 sqrt π). Solves
    P(s) = u P(cot θ) by Newton steps kept in a shrinking bracket (bisection
    where a step leaves it), with P scaled by e^(min(cot θ, 0)²) so that the
    tail below the horizon does not underflow."""
    cot = cos_t / dr.fmax(sin_t, AREA_MIN)
    m2 = dr.square(dr.fmin(cot, 0.0))                       # the scale's exponent

    def scaled(x):
        gauss = dr.exp(m2 - x * x)
        ex = erfcx(dr.abs(x))
        neg = gauss * (0.5 * cos_t * ex + (0.5 * INV_SQRT_PI) * sin_t)
        pos = cos_t * (1.0 - 0.5 * ex * gauss) + (0.5 * INV_SQRT_PI) * sin_t * gauss
        return dr.select(x < 0.0, neg, pos), (cos_t - x * sin_t) * gauss * INV_SQRT_PI

    hi = dr.fmin(cot, SLOPE_TAIL)
    lo = dr.fmin(cot, 0.0) - SLOPE_TAIL
    target = u * scaled(hi)[0]
    x = dr.clip(dr.erfinv(dr.clip(2.0 * u - 1.0, -0.999999, 0.999999)), lo, hi)
    for _ in range(NEWTON_STEPS):
        value, slope = scaled(x)
        excess = value - target
        hi = dr.select(excess > 0.0, x, hi)
        lo = dr.select(excess > 0.0, lo, x)
        step = x - excess / dr.select(slope > 0.0, slope, 1.0)
        inside = (slope > 0.0) & (step > lo) & (step < hi)
        x = dr.select(inside, step, 0.5 * (lo + hi))
    return x


def sample_visible(s: Surface, w, u1, u2):
    """A normal m with the density of the normals visible from w,
    max(0, w·m) D(m) / A(w), for w above or below the horizon (not straight
    down), in the configuration stretched to α = 1 (Heitz & d'Eon 2014): GGX
    by spherical caps (Dupuy & Benyoub 2023), Beckmann by the visible slope
    (:func:`_beckmann_slope`) and a Gaussian one across."""
    vx, vy, vz = s.ax * w.x, s.ay * w.y, w.z
    n = dr.rsqrt(dr.fmax(vx * vx + vy * vy + vz * vz, AREA_MIN))
    vx, vy, vz = vx * n, vy * n, vz * n
    if s.kind == "ggx":
        cz = 1.0 - u1 * (1.0 + vz)                          # a cap of the unit sphere
        sin_c = dr.safe_sqrt(1.0 - cz * cz)
        sn, cs = dr.sincos(dr.two_pi * u2)
        mx, my, mz = vx + sin_c * cs, vy + sin_c * sn, vz + cz
    else:
        sin_t = dr.sqrt(vx * vx + vy * vy)
        along = sin_t > 0.0
        cphi = dr.select(along, vx / dr.select(along, sin_t, 1.0), 1.0)
        sphi = dr.select(along, vy / dr.select(along, sin_t, 1.0), 0.0)
        sx = _beckmann_slope(vz, sin_t, u1)
        sy = dr.erfinv(dr.clip(2.0 * u2 - 1.0, -0.999999, 0.999999))
        mx, my, mz = -(cphi * sx - sphi * sy), -(sphi * sx + cphi * sy), 1.0
    # back from the stretched configuration: a normal's slopes scale by α
    mx, my, mz = s.ax * mx, s.ay * my, dr.fmax(mz, 0.0)
    n = dr.rsqrt(dr.fmax(mx * mx + my * my + mz * mz, AREA_MIN))
    return mi.Vector3f(mx * n, my * n, mz * n)


# ----------------------------------------------------------------------------
#  Random numbers: a PCG32 stream per lane, seeded by a hash of its inputs
# ----------------------------------------------------------------------------

def _bits(x):
    """The bits of a Float as a UInt32 (scalar variants: a Python float)."""
    if dr.is_jit_v(mi.Float):
        return dr.reinterpret_array(mi.UInt32, mi.Float(x))
    return struct.unpack("<I", struct.pack("<f", float(x)))[0]


def stream(*values):
    """A PCG32 generator per lane whose seed is a TEA hash of ``values``'
    bits (Floats), chained two words at a time."""
    words = [_bits(v) for v in values]
    v0, v1 = mi.sample_tea_32(words[0], words[1])
    jit = dr.is_jit_v(mi.Float)
    for i, word in enumerate(words[2:]):
        # (scalar variants: Python ints, wrapped to 32 bits as UInt32 wraps)
        v0, v1 = mi.sample_tea_32(v0 ^ word, (v1 + (i + 1)) if jit else (v1 + i + 1) & 0xFFFFFFFF)
    # The state and increment set directly: PCG32(size, state, seq) would offset
    # each lane's by its index, and a lane's numbers must depend on its inputs only.
    rng = mi.PCG32()
    if jit:
        rng.state = (mi.UInt64(v0) << 32) | mi.UInt64(v1)
        rng.inc = (mi.UInt64(v1 ^ 0x9E3779B9) << 1) | 1
    else:
        rng.state, rng.inc = (v0 << 32) | v1, ((v1 ^ 0x9E3779B9) << 1) | 1
    rng.next_uint32()                       # one step: the state well mixed
    return rng


# ----------------------------------------------------------------------------
#  The walk
# ----------------------------------------------------------------------------

def _unit(fresnel: Callable):
    """The type of a path's weight (a Float, or a colour for a coloured F), 1
    of it, and whether F is the constant 1: then the weight is the Python
    number 1 and no factor is traced (a loop variable that never changes is
    refused when a renderer's own loop records the walk's loop again)."""
    f = fresnel(mi.Float(0.5))
    if type(f) in (float, int) and f == 1.0 and dr.is_jit_v(mi.Float):
        return mi.Float, 1.0, True
    kind = mi.Float if type(f) in (float, int) else type(f)
    return kind, dr.ones(kind) if dr.is_jit_v(mi.Float) else kind(1.0), False


def _free_flight(s: Surface, w, tau, u):
    """τ after a free flight along w (-inf: the path left through the top)."""
    area = projected_area(s, -w)                            # of the facets facing w
    return dr.select(area > 0.0, tau + dr.log(1.0 - u) * w.z / dr.fmax(area, AREA_MIN),
                     -dr.inf)


def _bounce(s: Surface, wb, fresnel, u1, u2):
    """The direction after the facet seen from wb, and its Fresnel factor."""
    m = sample_visible(s, wb, u1, u2)
    c = dot(wb, m)
    return mi.Vector3f(2.0 * c * m - wb), fresnel(c)


def scattered(s: Surface, wi, wo, fresnel: Callable, rng):
    """X: the bounces k >= 2 of the walk from wi, by next-event estimation
    toward wo; its expectation is the multiple scattering's f·cos θ_o."""
    kind, one, constant = _unit(fresnel)
    up = wo.z > 0.0

    def body(w, tau, weight, total, rng, k, inside):
        u = rng.next_float32(), rng.next_float32(), rng.next_float32()
        tau = _free_flight(s, w, tau, u[0])
        inside = inside & ((w.z <= 0.0) | (tau > 0.0))      # (no ~: scalar masks are bools)
        wb = -w
        h = half_vector(wb, wo)
        phase = s.microfacet.D(h) / (4.0 * dr.fmax(projected_area(s, wb), AREA_MIN))
        seen = inside & up & (k >= 1)
        total += dr.select(seen, weight * (fresnel(dot(wb, h)) * phase * masking(s, wo, tau)), 0.0)
        w, f = _bounce(s, wb, fresnel, u[1], u[2])
        if not constant:
            weight = weight * f
        return w, tau, weight, total, rng, k + 1, inside

    state = (-wi, dr.zeros(mi.Float), one, dr.zeros(kind), rng, mi.UInt32(0), mi.Bool(True))
    state = dr.while_loop(state, lambda *a: a[6] & (a[5] < MAX_BOUNCES), body,
                          label="walk_eval")
    return state[3]


def single(s: Surface, wi, wo, fresnel: Callable):
    """f_1·cos θ_o, the height-correlated single scattering (see the module doc)."""
    h = half_vector(wi, wo)
    den = wo.z * projected_area(s, -wi) + wi.z * projected_area(s, wo)
    ok = den > DEN_MIN               # (0 only with both directions on the horizon)
    value = s.microfacet.D(h) * wo.z / (4.0 * dr.select(ok, den, 1.0))
    return fresnel(dot(wi, h)) * dr.select(ok, value, 0.0)


def evaluate(s: Surface, wi, wo, fresnel: Callable, uv):
    """f·cos θ_o, the walk's full BRDF, one stochastic estimate (unbiased;
    reciprocal per call: see the module doc). 0 for wo below the horizon.
    Only the single scattering is differentiated: the walks run under
    ``dr.suspend_grad`` (a symbolic loop records no derivatives)."""
    with dr.suspend_grad():
        x = scattered(s, wi, wo, fresnel, stream(wi.x, wi.y, wi.z, wo.x, wo.y, wo.z, uv.x, uv.y))
        y = scattered(s, wo, wi, fresnel, stream(wo.x, wo.y, wo.z, wi.x, wi.y, wi.z, uv.x, uv.y))
    both = wo.z / dr.fmax(wi.z + wo.z, AREA_MIN)
    return dr.select(wo.z > 0.0, single(s, wi, wo, fresnel) + (x + y) * both, 0.0)


def sample(s: Surface, wi, fresnel: Callable, rng):
    """(wo, weight, bounces): the direction in which the walk from wi leaves,
    the product of its Fresnel factors (0 if still inside after MAX_BOUNCES)
    and the number of facets it met."""
    kind, one, constant = _unit(fresnel)

    def body(w, tau, weight, rng, k, inside):
        u = rng.next_float32(), rng.next_float32(), rng.next_float32()
        tau = _free_flight(s, w, tau, u[0])
        inside = inside & ((w.z <= 0.0) | (tau > 0.0))
        wn, f = _bounce(s, -w, fresnel, u[1], u[2])
        w = dr.select(inside, wn, w)
        if not constant:
            weight = dr.select(inside, weight * f, weight)
        return w, tau, weight, rng, dr.select(inside, k + 1, k), inside

    state = (-wi, dr.zeros(mi.Float), one, rng, mi.UInt32(0), mi.Bool(True))
    w, tau, weight, _, k, _ = dr.while_loop(
        state, lambda *a: a[5] & (a[4] <= MAX_BOUNCES), body, label="walk_sample")
    left = (w.z > 0.0) & (tau <= 0.0)          # (else still inside after MAX_BOUNCES)
    return w, dr.select(left, weight, 0.0), k


def pdf(s: Surface, wi, wo):
    """p̃(wo): the deterministic stand-in for the walk's exit density that MIS
    weights read (see the module doc); 0 below the horizon."""
    h = half_vector(wi, wo)
    q = dr.fmax(1.0 - s.microfacet.G1(wi), Q_MIN)
    p = (1.0 - q) * s.microfacet.reflection_pdf(wi, wo, h) + q * dr.inv_pi * wo.z
    return dr.select(wo.z > 0.0, p, 0.0)


# ----------------------------------------------------------------------------
#  The plugin's lobe (cook_torrance with multiple_scattering="walk")
# ----------------------------------------------------------------------------

def lobe(plugin, inp, si, wo):
    """The specular lobe of ``plugin`` (a :class:`.cook_torrance.CookTorrance`)
    as the walk's full BRDF: m_S times :func:`evaluate`, with the plugin's
    Fresnel form at every bounce."""
    from .mixture import Scaled
    value = evaluate(surface(inp.microfacet), si.wi, wo, lambda c: plugin.fresnel(inp, c), si.uv)
    return Scaled(inp.colour_s, value) if type(value) is mi.Float else inp.colour_s * value


def lobe_pdf(inp, si, wo):
    """:func:`pdf` of the plugin's roughness."""
    return pdf(surface(inp.microfacet), si.wi, wo)


def sample_bsdf(plugin, ctx, si, sample1, sample2, active=True):
    """``sample`` of a plugin whose specular lobe is the walk: the lobe picked
    as the mixture picks it (:meth:`.mixture.Mixture.probabilities`); the
    walk's exit direction with the weight m_S (1 - k) times its Fresnel
    product over the probability of the pick, or the diffuse lobe's sample
    with its value over its density and pick. ``pdf`` is the mixture's, p̃
    for the walk (:func:`pdf`): what ``eval_pdf`` gives at the same wo."""
    from .mixture import (DIFFUSE, GLOSSY, HORIZON, as_type, facing, product, spectrum,
                          weighted)
    sample1, sample2 = as_type(sample1, mi.Float), as_type(sample2, mi.Point2f)
    use = plugin.enabled(ctx)
    active = facing(si, active)
    inp, _ = plugin.inputs(si, active)
    probs = plugin.probabilities(inp, None, si, use)
    w_d, w_s = plugin.lobe_weights(inp)
    with dr.suspend_grad():
        wo, throughput, _ = sample(surface(inp.microfacet), si.wi,
                                   lambda c: plugin.fresnel(inp, c),
                                   stream(sample1, sample2.x, sample2.y, si.wi.x, si.wi.y))
    weight = inp.colour_s * (throughput * w_s)
    specular = True
    if probs is not None:
        p_d, p_s, _ = probs
        specular = mi.Bool(sample1 >= p_d)
        wo_d = mi.warp.square_to_cosine_hemisphere(sample2)
        p_cos = mi.warp.square_to_cosine_hemisphere_pdf(wo_d)
        diffuse = product(weighted(plugin.eval_diffuse(inp, si, wo_d), w_d, False))
        ok_d = p_cos * p_d > 0.0
        diffuse = dr.select(ok_d, diffuse / dr.select(ok_d, p_cos * p_d, 1.0), 0.0)
        weight = dr.select(specular, weight / dr.select(p_s > 0.0, p_s, 1.0), diffuse)
        wo = dr.select(specular, wo, wo_d)
    pdf_ = plugin.lobes(use, probs, inp, None, si, wo, active, value=False)[1]
    ok = active & (wo.z > HORIZON) & (pdf_ > 0.0)
    bs = mi.BSDFSample3f(dr.select(ok, wo, 0.0))
    bs.pdf = dr.select(ok, pdf_, 0.0)
    bs.eta = 1.0
    index = plugin.state.index
    if type(specular) is bool:
        bs.sampled_type = mi.UInt32(GLOSSY)
        bs.sampled_component = mi.UInt32(index["specular"])
    else:
        bs.sampled_type = dr.select(specular, mi.UInt32(GLOSSY), mi.UInt32(DIFFUSE))
        bs.sampled_component = dr.select(specular, mi.UInt32(index["specular"]),
                                         mi.UInt32(index["diffuse"]))
    weight = dr.select(ok, weight, 0.0)
    if type(weight) is not mi.UnpolarizedSpectrum:
        weight = mi.UnpolarizedSpectrum(weight)
    return bs, spectrum(weight)
