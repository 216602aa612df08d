"""Tabulated functions: values on a regular grid, looked up with multilinear
interpolation in Dr.Jit, in every variant.

A :class:`Grid` holds the values of a function at the nodes of its axes (an
``n_1 × … × n_d`` NumPy array) and interpolates them linearly along each axis,
so lookups are differentiable in every coordinate (piecewise linearly) and
work per lane, with textured parameters. An :class:`Axis` places its ``n``
nodes uniformly in a warped coordinate (``linear``: x itself; ``sqrt``:
sqrt(x), denser near ``lo``; ``log1p``: log(1 + x), for exponents spanning
decades); values beyond the ends are clamped to them.

JIT variants gather from a Dr.Jit array; scalar variants index the NumPy array
(they have no gathers and no derivatives). Used by :mod:`.energy` (albedo
tables), :mod:`.microfacet` (the Smith G1 of the Blinn distribution) and
:mod:`.oren_nayar` (the lecture's table of sin α tan β).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np


@dataclass(frozen=True)
class Axis:
    """``n`` nodes from ``lo`` to ``hi``, uniform in the ``warp`` of x."""
    name: str
    lo: float
    hi: float
    n: int
    warp: str = "linear"

    def _forward_np(self, x):
        return {"linear": lambda v: v, "sqrt": np.sqrt, "log1p": np.log1p}[self.warp](x)

    def _forward_dr(self, x):
        if self.warp == "sqrt":
            return dr.sqrt(dr.fmax(x, 0.0))
        if self.warp == "log1p":
            return dr.log(1.0 + dr.fmax(x, 0.0))
        return x

    def nodes(self) -> np.ndarray:
        """The node positions in x (float64)."""
        u = np.linspace(self._forward_np(self.lo), self._forward_np(self.hi), self.n)
        return {"linear": lambda v: v, "sqrt": np.square, "log1p": np.expm1}[self.warp](u)

    def coordinate(self, x):
        """x as a continuous node index in [0, n - 1] (Dr.Jit; clamped at the ends)."""
        a, b = self._forward_np(self.lo), self._forward_np(self.hi)
        u = (self._forward_dr(x) - a) * ((self.n - 1) / (b - a))
        return dr.fmin(dr.fmax(u, 0.0), self.n - 1)

    def coordinate_np(self, x) -> np.ndarray:
        a, b = self._forward_np(self.lo), self._forward_np(self.hi)
        u = (self._forward_np(np.maximum(x, self.lo)) - a) * ((self.n - 1) / (b - a))
        return np.clip(u, 0.0, self.n - 1)

    def quadrature(self, x, w) -> np.ndarray:
        """Node weights W such that sum_k W_k g_k = sum_j w_j g~(x_j) for the
        interpolant g~ of any node values g: a quadrature rule (x, w) in x
        carried over to the nodes (NumPy)."""
        return self.hats(x).T @ np.asarray(w, dtype=np.float64)

    def hats(self, x) -> np.ndarray:
        """(len(x), n) interpolation weights of the nodes at the points x (NumPy)."""
        u = self.coordinate_np(np.asarray(x, dtype=np.float64))
        i = np.minimum(np.floor(u).astype(int), self.n - 2)
        f = u - i
        w = np.zeros((len(u), self.n))
        w[np.arange(len(u)), i] = 1.0 - f
        w[np.arange(len(u)), i + 1] += f
        return w


class Grid:
    """Values on the nodes of ``axes``, looked up by multilinear interpolation."""

    def __init__(self, axes: tuple[Axis, ...], values: np.ndarray):
        values = np.asarray(values, dtype=np.float64)
        if values.shape != tuple(a.n for a in axes):
            raise ValueError(f"grid values of shape {values.shape} for axes "
                             f"{[a.n for a in axes]}")
        self.axes = tuple(axes)
        self.values = values
        self.strides = [int(np.prod([a.n for a in axes[k + 1:]])) for k in range(len(axes))]
        flat = values.astype(np.float32).ravel()
        self._flat_np = flat
        self._flat = mi.Float(flat) if dr.is_jit_v(mi.Float) else None

    def _gather(self, index):
        if self._flat is not None:
            return dr.gather(mi.Float, self._flat, index)
        return float(self._flat_np[int(index)])

    def __call__(self, *xs):
        """The interpolated value at the point (x_1, …, x_d) (Dr.Jit, per lane)."""
        cells = []
        for axis, x in zip(self.axes, xs):
            u = axis.coordinate(x)
            i = dr.minimum(mi.UInt32(u), axis.n - 2)          # the cell's lower node
            cells.append((i, u - mi.Float(i)))
        result = mi.Float(0.0)
        for corner in itertools.product((0, 1), repeat=len(cells)):
            index = mi.UInt32(0)
            weight = mi.Float(1.0)
            for (i, f), c, stride in zip(cells, corner, self.strides):
                index += (i + c) * stride
                weight *= f if c else 1.0 - f
            result += weight * self._gather(index)
        return result

    def integrate(self, weights: list[np.ndarray]) -> np.ndarray:
        """Sum the values against node weights along the first ``len(weights)``
        axes (e.g. :meth:`Axis.quadrature` of a density): the integral of the
        interpolant, as an array over the remaining axes."""
        result = self.values
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

