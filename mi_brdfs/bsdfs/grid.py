"""Tabulated functions: values on a regular grid, interpolated in Dr.Jit, in every variant.

A :class:`Grid` holds the values of a function at the nodes of its axes (an
``n_1 × … × n_d`` NumPy array) and interpolates them per lane, so lookups work
with textured parameters and are differentiable in every coordinate. An
:class:`Axis` places its ``n`` nodes uniformly in a warped coordinate u
(``linear``: x itself; ``sqrt``: sqrt(x), denser near ``lo``; ``log1p``:
log(1 + x), for exponents spanning decades; ``log``: log(x), ``lo`` > 0, for a
roughness whose features scale with it (below ``lo`` the value at ``lo``);
``sine``: (2/π) asin(sqrt(x)) on [0, 1], x = sin²(πu/2), denser near both ends;
``ratio``: sqrt(x / (1 + x)) and ``root``: sqrt(x) / (1 + sqrt(x)), which map
[0, ∞] onto [0, 1] — sqrt near 0,
the last node is x = ∞, and 1 - u falls as 1/(2x) or 1/sqrt(x) towards it);
values beyond the ends are clamped to them.

Along each axis the interpolation is either linear (the default: two nodes
per axis, a derivative that jumps at every node) or, for an axis with
``smooth=True``, the interpolating uniform cubic B-spline in u (four
coefficients per axis; Unser, Aldroubi & Eden 1991, "Fast B-spline transforms
for continuous image representation and interpolation"): it passes through
the nodes, its first and second derivatives are continuous, so gradients with
respect to that coordinate have no steps, and its error is O(h⁴) in the value
and O(h³) in the derivative (h the node spacing in u). The coefficients c
solve (c_{k-1} + 4 c_k + c_{k+1}) / 6 = v_k, with a vanishing third
difference at each end (a ghost coefficient beyond each end). The B-spline
weights are non-negative and sum to 1, so an interpolant whose coefficients
lie in [lo, hi] stays in [lo, hi]: ``Grid(..., bounds=(0, None))`` clips the
coefficients so (exact at the nodes unless a clip was needed, i.e. where the
data bends too sharply for the spline next to the bound), and the interpolant
needs no clamp — which keeps integrals of it exact (:mod:`.energy`).

JIT variants gather from a Dr.Jit array, :attr:`Grid.data`; a lookup may be
given that array explicitly (``grid(x, data=...)``), so that a plugin holding
it as a member makes it part of what Dr.Jit traverses (a frozen function then
sees it as an input). Scalar variants index the NumPy array (they have no
gathers and no derivatives). Used by :mod:`.energy` (albedo tables),
:mod:`.microfacet` (the Smith G1 of the Blinn distribution) and
:mod:`.oren_nayar` (the lecture's table of sin α tan β).
"""
from __future__ import annotations

from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from .._jit import from_numpy


def bspline(t):
    """The cubic B-spline weights of coefficients k-1, k, k+1, k+2 at t in
    [0, 1] of cell [k, k+1]: non-negative, summing to 1 (Dr.Jit or NumPy)."""
    s = 1.0 - t
    t2 = t * t
    return (s * s * s / 6.0, (3.0 * t2 * t - 6.0 * t2 + 4.0) / 6.0,
            (-3.0 * t2 * t + 3.0 * t2 + 3.0 * t + 1.0) / 6.0, t2 * t / 6.0)


def bspline_derivative(t):
    """d/dt of :func:`bspline`'s weights."""
    s = 1.0 - t
    return (-0.5 * s * s, 0.5 * (3.0 * t * t - 4.0 * t), 0.5 * (-3.0 * t * t + 2.0 * t + 1.0),
            0.5 * t * t)


def prefilter(values: np.ndarray, axis: int) -> np.ndarray:
    """The B-spline coefficients (n + 2 along ``axis``: a ghost at each end)
    that interpolate ``values`` along that axis."""
    n = values.shape[axis]
    a = np.zeros((n + 2, n + 2))
    a[0, :4] = [1.0, -3.0, 3.0, -1.0]              # third difference 0 at each end
    a[-1, -4:] = [-1.0, 3.0, -3.0, 1.0]
    for k in range(n):
        a[k + 1, k:k + 3] = [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0]
    v = np.moveaxis(values, axis, 0)
    rhs = np.concatenate([np.zeros((1,) + v.shape[1:]), v, np.zeros((1,) + v.shape[1:])])
    c = np.linalg.solve(a, rhs.reshape(n + 2, -1)).reshape(rhs.shape)
    return np.moveaxis(c, 0, axis)


@dataclass(frozen=True)
class Axis:
    """``n`` nodes from ``lo`` to ``hi``, uniform in the ``warp`` of x;
    interpolated linearly, or by a C1 cubic if ``smooth``."""
    name: str
    lo: float
    hi: float
    n: int
    warp: str = "linear"
    smooth: bool = False

    def _forward_np(self, x):
        x = np.asarray(x, dtype=np.float64)
        if self.warp in ("ratio", "root"):
            x = np.maximum(x, 0.0)
            with np.errstate(invalid="ignore"):
                u = np.sqrt(x / (1.0 + x)) if self.warp == "ratio" else np.sqrt(x) / (1.0 + np.sqrt(x))
            return np.where(np.isinf(x), 1.0, u)
        if self.warp == "log":
            return np.log(np.maximum(x, self.lo))
        if self.warp == "sine":
            return (2.0 / np.pi) * np.arcsin(np.sqrt(np.clip(x, 0.0, 1.0)))
        return {"linear": lambda v: v, "sqrt": np.sqrt, "log1p": np.log1p}[self.warp](x)

    def _inverse_np(self, u):
        if self.warp in ("ratio", "root"):
            with np.errstate(divide="ignore"):
                if self.warp == "ratio":
                    return np.where(u >= 1.0, np.inf, u * u / (1.0 - u * u))
                return np.where(u >= 1.0, np.inf, (u / (1.0 - u)) ** 2)
        return {"linear": lambda v: v, "sqrt": np.square, "log1p": np.expm1,
                "log": np.exp, "sine": lambda v: np.sin(0.5 * np.pi * v) ** 2}[self.warp](u)

    def _forward_dr(self, x):
        if self.warp == "sqrt":
            return dr.sqrt(dr.fmax(x, 0.0))
        if self.warp == "log1p":
            return dr.log(1.0 + dr.fmax(x, 0.0))
        if self.warp == "log":
            return dr.log(dr.fmax(x, self.lo))
        if self.warp == "sine":
            return (2.0 / dr.pi) * dr.asin(dr.sqrt(dr.clip(x, 0.0, 1.0)))
        if self.warp == "ratio":
            x = dr.fmax(x, 0.0)
            return dr.sqrt(x / (1.0 + x))
        if self.warp == "root":
            r = dr.sqrt(dr.fmax(x, 0.0))
            return r / (1.0 + r)
        return x

    def _ends(self) -> tuple[float, float]:
        return float(self._forward_np(self.lo)), float(self._forward_np(self.hi))

    def nodes(self) -> np.ndarray:
        """The node positions in x (float64; inf for the ``ratio`` warp's last)."""
        a, b = self._ends()
        return self._inverse_np(np.linspace(a, b, self.n))

    def coordinate(self, x):
        """x as a continuous node index in [0, n - 1] (Dr.Jit; clamped at the ends)."""
        a, b = self._ends()
        u = (self._forward_dr(x) - a) * ((self.n - 1) / (b - a))
        return dr.fmin(dr.fmax(u, 0.0), self.n - 1)

    def coordinate_np(self, x) -> np.ndarray:
        a, b = self._ends()
        u = (self._forward_np(np.maximum(x, self.lo)) - a) * ((self.n - 1) / (b - a))
        return np.clip(u, 0.0, self.n - 1)

    def stencil(self, x: float) -> tuple[int, np.ndarray, np.ndarray]:
        """At one value x (NumPy): the first stored index of what interpolates
        there, its weights, and their derivatives with respect to x (0 where
        the coordinate is clamped at an end)."""
        a, b = self._ends()
        scale = (self.n - 1) / (b - a)
        raw = (float(self._forward_np(max(float(x), self.lo))) - a) * scale
        u = min(max(raw, 0.0), self.n - 1.0)
        i = min(int(u), self.n - 2)
        t = u - i
        x = max(float(x), self.lo)
        if not 0.0 <= raw <= self.n - 1:          # beyond the ends: the value is held
            du = 0.0
        elif self.warp == "sqrt":
            du = scale * 0.5 / np.sqrt(x)
        elif self.warp == "log1p":
            du = scale / (1.0 + x)
        elif self.warp == "log":
            du = scale / x
        elif self.warp == "sine":
            du = scale / (np.pi * np.sqrt(x * (1.0 - x)))
        elif self.warp == "ratio":
            du = scale * 0.5 / (np.sqrt(x / (1.0 + x)) * (1.0 + x) ** 2)
        elif self.warp == "root":
            du = scale * 0.5 / (np.sqrt(x) * (1.0 + np.sqrt(x)) ** 2)
        else:
            du = scale
        if not self.smooth:
            return i, np.array([1.0 - t, t]), np.array([-du, du])
        return i, np.array(bspline(t)), du * np.array(bspline_derivative(t))

    def terms(self, x):
        """[(stored index, weight)] of what interpolates at x (Dr.Jit, per
        lane): two node values for a linear axis, four B-spline coefficients
        for a smooth one (stored with a ghost at each end: index k + 1 is the
        coefficient of node k)."""
        u = self.coordinate(x)
        i = dr.minimum(mi.UInt32(u), self.n - 2)              # the cell's lower node
        t = u - mi.Float(i)
        if not self.smooth:
            return [(i, 1.0 - t), (i + 1, t)]
        return [(i + k, w) for k, w in enumerate(bspline(t))]

    def quadrature(self, x, w) -> np.ndarray:
        """Node weights W such that sum_k W_k g_k = sum_j w_j g~(x_j) for the
        linear interpolant g~ of any node values g: a quadrature rule (x, w)
        in x carried over to the nodes (NumPy; linear axes)."""
        return self.hats(x).T @ np.asarray(w, dtype=np.float64)

    def hats(self, x) -> np.ndarray:
        """(len(x), n) linear interpolation weights of the nodes at the points x (NumPy)."""
        if self.smooth:
            raise ValueError(f"axis {self.name!r}: hats of a smooth axis (B-spline) are "
                             "not the node values'")
        u = self.coordinate_np(np.asarray(x, dtype=np.float64))
        i = np.minimum(np.floor(u).astype(int), self.n - 2)
        t = u - i
        w = np.zeros((len(u), self.n))
        rows = np.arange(len(u))
        w[rows, i] = 1.0 - t
        np.add.at(w, (rows, i + 1), t)
        return w


class Grid:
    """Values on the nodes of ``axes``, interpolated per axis (linear or smooth).

    ``values``: the node values (n_1 x ... x n_d), or with ``coefficients=True``
    what is stored already (smooth axes: n + 2 B-spline coefficients). ``bounds``:
    clip the stored coefficients to (lo, hi), so that the interpolant stays in
    that range.
    """

    def __init__(self, axes: tuple[Axis, ...], values: np.ndarray, bounds=None,
                 coefficients: bool = False):
        self.axes = tuple(axes)
        values = np.asarray(values, dtype=np.float64)
        stored_shape = tuple(a.n + (2 if a.smooth and coefficients else 0) for a in axes)
        if values.shape != stored_shape:
            raise ValueError(f"grid values of shape {values.shape} for axes "
                             f"{[a.n for a in axes]}")
        stored = values
        if not coefficients:
            for k, axis in enumerate(self.axes):
                if axis.smooth:
                    stored = prefilter(stored, k)
        if bounds is not None:
            stored = np.clip(stored, *bounds)
        self.values = None if coefficients else values    # the node values
        self.stored = stored              # node values (linear axes), coefficients (smooth)
        self.strides = [int(np.prod(stored.shape[k + 1:])) for k in range(len(axes))]
        self.data_np = stored.astype(np.float32).ravel()
        self.data = from_numpy(mi.Float, self.data_np) if dr.is_jit_v(mi.Float) else None

    def __call__(self, *xs, data=None):
        """The interpolated value at the point (x_1, …, x_d) (Dr.Jit, per lane),
        gathered from ``data`` (default :attr:`data`; NumPy in scalar variants)."""
        terms = [axis.terms(x) for axis, x in zip(self.axes, xs)]
        if self.data is None:                                  # scalar variants
            source = self.data_np
            gather = lambda index: float(source[int(index)])
        else:
            source = self.data if data is None else data
            gather = lambda index: dr.gather(mi.Float, source, index)

        def along(k, offset):
            """Interpolate along axes k.. at the flat offset of axes ..k-1."""
            if k == len(terms):                       # (a grid of no axes: one value)
                return gather(offset)
            result = 0.0
            for i, w in terms[k]:
                index = offset + i * self.strides[k]
                part = gather(index) if k + 1 == len(terms) else along(k + 1, index)
                result = result + w * part
            return result

        return mi.Float(along(0, mi.UInt32(0)))

    def integrate(self, weights: list[np.ndarray]) -> np.ndarray:
        """Sum the stored values against node weights along the first
        ``len(weights)`` (linear) axes (e.g. :meth:`Axis.quadrature` of a
        density): the integral of the interpolant, as what a Grid over the
        remaining axes stores (``coefficients=True``)."""
        result = self.stored
        for w in weights:
            result = np.tensordot(w, result, axes=(0, 0))
        return result


def midpoints(n: int) -> np.ndarray:
    """n midpoints of [0, 1] (stratified quadrature nodes)."""
    return (np.arange(n) + 0.5) / n


def hemisphere_direction(mu, sin2_phi=None):
    """Local directions (N, 3) at cos θ = mu and sin²φ (0: φ = 0), NumPy."""
    mu = np.asarray(mu, dtype=np.float64)
    s = np.sqrt(np.maximum(1.0 - mu * mu, 0.0))
    if sin2_phi is None:
        return np.stack([s, np.zeros_like(mu), mu], axis=-1)
    cp, sp = np.sqrt(1.0 - sin2_phi), np.sqrt(sin2_phi)
    return np.stack([s * cp, s * sp, mu], axis=-1)

