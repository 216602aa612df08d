"""Power-cosine lobes about an axis, evaluated and sampled accurately in float32.

A power-cosine lobe of exponent e about a unit axis a is cos^e(theta) for the
directions v with cos(theta) = v·a > 0, and 0 elsewhere. The Phong lobe is one
about the mirror direction of the viewer (e = gamma); the Blinn half-vector
density is one about the normal (e = gamma + 1). Used by :mod:`mi_brdfs.phong`
and :mod:`mi_brdfs.blinn`.

Why not simply ``dr.power(dot(v, a), e)`` and ``1 - u^(2/(e+1))``: a lobe of
exponent e is about 1/sqrt(e) radians wide, so at e = 10^6 every direction of
interest has 1 - cos(theta) ~ 10^-6, a few float32 ulps of 1 (2^-24 = 6e-8).
cos(theta) rounded to float32 then holds one or two significant digits of
1 - cos(theta), and cos^e swings by e·6e-8 = 6 % per ulp; worse, the classic
sampler's sin²(theta) = 1 - u^(2/(e+1)) cancels catastrophically and collapses
the lobe onto a handful of rings (onto the axis itself beyond e ~ 10^8). Here:

- the versine 1 - cos(theta) is computed without cancellation: for unit
  directions from the difference v - a (exact in floating point near the axis,
  Sterbenz), as ``(|v - a|² - (|v| - |a|)²) / (2 |v| |a|)``; about the normal from
  ``sin²(theta) = (x² + y²)/|v|²``, as sin²/(1 + cos);
- cos^e(theta) = exp(e · log1p(-(1 - cos theta))) near the axis,
  exp(e log cos theta) away from it (where cos theta itself is accurate);
- the sampler inverts the cdf cos^(e+1)(theta) = u as
  cos(theta) = exp(log(u)/(e+1)), sin²(theta) = -expm1(2 log(u)/(e+1)).

Dr.Jit has neither ``log1p`` nor ``expm1``: :func:`log1p` and :func:`expm1`
below are Goldberg's and Kahan's float-exact tricks (relative error a few ulps
over their whole domain). Every function is NaN- and Inf-free, values and
gradients, for any direction (zero vectors included) and 0 <= e < inf:
unselected ``dr.select`` branches are evaluated on benign stand-ins.

Convention: the lobe is 0 where cos(theta) <= 0, also for e = 0 (0^0 := 0, the
limit e -> 0+), so an e = 0 lobe is the uniform hemisphere about the axis.
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

TINY = 1e-18          # keeps squared norms away from 0 (TINY is still a normal float32)
U_MIN = 1e-30         # smallest u the sampler takes the log of (log(U_MIN) = -69)
NEAR_AXIS = 0.5       # versine below which cos^e uses log1p: cos(theta) > 1/2


# ----------------------------------------------------------------------------
#  log1p and expm1 (absent from Dr.Jit)
# ----------------------------------------------------------------------------

def log1p(x):
    """log(1 + x) to a few ulps for x > -1 (Goldberg 1991, Theorem 4).

    u = 1 + x is rounded, but log(u)·x/(u - 1) divides out the rounding error.
    """
    u = 1.0 + x
    exact = u == 1.0                                  # |x| below half an ulp of 1
    d = dr.select(exact, 1.0, u - 1.0)                # benign stand-ins where exact
    lu = dr.log(dr.select(exact, 1.0, dr.fmax(u, TINY)))
    return dr.select(exact, x, lu * x / d)


def expm1(x):
    """exp(x) - 1 to a few ulps for x <= 88 (Kahan's trick, as log1p above).

    Where exp(x) rounds to 1 the result is x; where exp(x) - 1 rounds to -1
    (x < -17) it is -1 (exact in float32).
    """
    u = dr.exp(x)
    um1 = u - 1.0
    tiny = u == 1.0
    minus_one = um1 == -1.0
    plain = (u != 1.0) & (um1 != -1.0)      # (not ~: scalar variants' masks are bools)
    lu = dr.log(dr.select(plain, u, 2.0))            # benign stand-in: log 2 != 0
    ratio = um1 * dr.select(plain, x, 1.0) / lu
    return dr.select(tiny, x, dr.select(minus_one, -1.0, ratio))


# ----------------------------------------------------------------------------
#  The lobe
# ----------------------------------------------------------------------------

def cos_versin(v, axis):
    """(cos theta, 1 - cos theta) of the angle between v and ``axis``, both
    directions of (about) unit length, e.g. float32 unit vectors (the zero
    vector gives cos theta = 0: outside the lobe)."""
    nv = dr.sqrt(dr.fmax(dr.squared_norm(v), TINY))
    na = dr.sqrt(dr.fmax(dr.squared_norm(axis), TINY))
    cos_t = dr.dot(v, axis) / (nv * na)
    # |v - a|² = (|v| - |a|)² + 2 |v| |a| (1 - cos theta), with v - a exact near the axis
    versin = (dr.squared_norm(v - axis) - dr.square(nv - na)) / (2.0 * nv * na)
    return cos_t, dr.fmin(dr.fmax(versin, 0.0), 2.0)


def cos_versin_z(v):
    """(cos theta, 1 - cos theta) of v (any length, e.g. a half vector d + w_r)
    about +z, from ``sin²(theta) = (x² + y²)/|v|²``; the zero vector gives (0, 1)."""
    norm2 = dr.squared_norm(v)
    zero = norm2 < TINY
    norm2 = dr.select(zero, 1.0, norm2)
    cos_t = dr.select(zero, 0.0, v.z * dr.rsqrt(norm2))
    sin2 = dr.fmin((dr.square(v.x) + dr.square(v.y)) / norm2, 1.0)
    # 1 - cos = sin²/(1 + cos) where cos > 0; no cancellation is possible elsewhere
    up = cos_t > 0.0
    versin = dr.select(up, sin2 / (1.0 + dr.select(up, cos_t, 0.0)), 1.0 - cos_t)
    return cos_t, dr.select(zero, 1.0, versin)


def log_cos(cos_t, versin):
    """log(cos theta) for cos theta > 0, accurate near the axis (a finite stand-in elsewhere)."""
    near = versin < NEAR_AXIS
    near_value = log1p(-dr.select(near, versin, 0.0))
    far_value = dr.log(dr.select(near, 1.0, dr.fmax(cos_t, TINY)))
    return dr.select(near, near_value, far_value)


def pow_cos(cos_t, versin, e):
    """cos^e(theta) where cos theta > 0, else 0 (also for e = 0)."""
    return dr.select(cos_t > 0.0, dr.exp(e * log_cos(cos_t, versin)), 0.0)


def pdf(cos_t, versin, e):
    """Density (per solid angle) of :func:`sample`: (e+1)/(2 pi) · cos^e(theta)."""
    return (e + 1.0) * dr.inv_two_pi * pow_cos(cos_t, versin, e)


def sample(sample2, e):
    """A direction about +z with density (e+1)/(2 pi) cos^e(theta) (cos theta > 0).

    Inverts the cdf of cos(theta), cos^(e+1)(theta) = u with u = 1 - sample2.x
    (so sample2.x = 0 gives the axis), with sin²(theta) accurate for any e.
    """
    y = dr.log(dr.fmax(1.0 - sample2.x, U_MIN)) / (e + 1.0)    # log cos(theta) <= 0
    cos_t = dr.exp(y)
    sin_t = dr.sqrt(dr.fmax(-expm1(2.0 * y), TINY))             # TINY: finite d(sqrt)
    s, c = dr.sincos(dr.two_pi * sample2.y)
    return mi.Vector3f(c * sin_t, s * sin_t, cos_t)
