"""Mitsuba's χ² sampling test with the density integrated until it converges.

``mi.chi2.ChiSquareTest`` compares a histogram of ``sample()`` with the
density ``pdf()`` integrated over each histogram cell by the trapezoid rule
on a fixed ``ires`` × ``ires`` grid of points per cell. A lobe narrower than
the spacing of that grid is integrated wrongly: the cell's expected count is
off by far more than the histogram's noise, and a correct sampler is rejected
(at ``ires`` 16: phong γ = 1000 at normal incidence, sharp Blinn and Ward
lobes at 85°, the toon model's narrow band at threshold 0.97).

:class:`ConvergedChiSquareTest` integrates every cell at ``ires`` first
(9 × 9 points), placed and weighted as Mitsuba does, then halves the
spacing of the points (n → 2n − 1 per axis, the old points kept) for the
cells whose integral is still changing, until the change of every cell is
small against that cell's Poisson noise::

    |I_fine − I_coarse| ≤ TOLERANCE · sqrt(max(I_fine, 1))     (expected sample counts)

so that no cell's integration error adds more than TOLERANCE² to the χ²
statistic (the change bounds the error of I_fine: the trapezoid rule's
error falls by 4 per halving where the density is smooth, by 2 across a
step). The grids are nested so that the change cannot vanish by accident:
across a step the error is the step's offset from the middle of the
interval holding it, and halving the interval moves that middle by a
quarter of its length. (Doubling the points instead can put a symmetric
pair around the same middle at both levels: a toon band's edge then reads
as converged at 8 and 16 points, wrong by 1.5 % of a row of cells.)
Smooth cells stop after one doubling; the cells of a sharp lobe or at a
discontinuity (the toon model's bands) are refined up to ``max_ires``. A
cell that has not converged there is counted in :attr:`unconverged`, and
the test fails: the report says so instead of a p-value it cannot trust.

The test keeps its power: a density that is wrong by a few per cent (the
models' negative controls) is still rejected, since finer integration
only removes the integration error, never the sampler's.
"""
from __future__ import annotations

import time

import drjit as dr
import mitsuba as mi
import numpy as np

from .._jit import from_numpy

TOLERANCE = 0.25         # allowed integration error, in units of a cell's Poisson noise
START_IRES = 9           # points per cell and axis of the first table (8 intervals)
MAX_IRES = 1025          # points per cell and axis, at most (1024 intervals)
MAX_LANES = 1 << 24      # density evaluations per kernel launch


class ConvergedChiSquareTest(mi.chi2.ChiSquareTest):
    """``mi.chi2.ChiSquareTest`` (same arguments) whose density table is
    refined per cell until it converges (see the module's docstring).

    ``ires`` is where the refinement starts (default :data:`START_IRES`).
    After :meth:`tabulate_pdf`: :attr:`ires_reached` (the finest points per
    axis any cell needed) and :attr:`unconverged` (cells still changing at
    ``max_ires``: the test then fails)."""

    def __init__(self, *args, ires: int = None, max_ires: int = MAX_IRES,
                 tolerance: float = TOLERANCE, **kwargs):
        super().__init__(*args, ires=ires or START_IRES, **kwargs)
        self.max_ires = max(max_ires, self.ires)
        self.tolerance = tolerance
        self.ires_reached = self.ires
        self.unconverged = 0

    def tabulate_pdf(self):
        self.histogram_start = time.time()
        cells = np.arange(self.res.x * self.res.y, dtype=np.uint32)
        table = self._integrate(cells, self.ires)
        active, n = cells, self.ires
        while active.size and 2 * n - 1 <= self.max_ires:
            n = 2 * n - 1                  # the intervals halved: the old points kept
            finer = self._integrate(active, n)
            change = np.abs(finer - table[active])
            table[active] = finer
            self.ires_reached = n
            active = active[change > self.tolerance * np.sqrt(np.maximum(finer, 1.0))]
        self.unconverged = int(active.size)
        if self.unconverged:
            self._log(f"Failure: the density's integral did not converge in {self.unconverged} "
                      f"cells at {n} x {n} points per cell")
            self.fail = True
        self.pdf = from_numpy(mi.Float, table)
        self.pdf_sum = dr.sum(self.pdf) / self.sample_count
        lowest = float(np.min(table))
        if not lowest >= 0:                                      # (NaN included)
            self._log(f"Failure: the density integrates to {lowest:.4g} over a cell: it is "
                      "negative (or NaN) somewhere")
            self.fail = True
        if self.pdf_sum[0] > 1.1:
            self._log(f"Failure: the density integrates to {self.pdf_sum[0]:.4f} over the "
                      "domain, more than 1 (+ 10 % for the integration error)")
            self.fail = True
        self.histogram_end = time.time()       # (Mitsuba's name for the pdf's timing)

    def _integrate(self, cells: np.ndarray, n: int) -> np.ndarray:
        """Expected sample counts of ``cells`` (flat indices), by the
        trapezoid rule on n × n points per cell placed as Mitsuba places them."""
        per_launch = max(1, MAX_LANES // (n * n))
        return np.concatenate([self._integrate_chunk(cells[i:i + per_launch], n)
                               for i in range(0, cells.size, per_launch)])

    def _integrate_chunk(self, cells: np.ndarray, n: int) -> np.ndarray:
        points = n * n
        index = dr.arange(mi.UInt32, cells.size * points)
        cell = dr.gather(mi.UInt32, from_numpy(mi.UInt32, cells), index // points)
        k = index % points
        cell_2d = mi.Vector2u(cell % self.res.x, cell // self.res.x)
        k_2d = mi.Vector2u(k % n, k // n)
        cell_size = self.bounds.extents() / self.res
        spacing = cell_size / (n - 1)
        p = self.bounds.min + mi.Vector2f(cell_2d) * cell_size
        p += (mi.Vector2f(k_2d) + 1e-4) * (1 - 2e-4) * spacing
        weight = dr.prod(dr.select((k_2d == 0) | (k_2d == n - 1), 0.5, 1.0))
        weight *= dr.prod(spacing) * self.sample_count
        pdf = self.pdf_func(self.domain.map_forward(p))
        return np.array(dr.block_sum(mi.Float64(pdf * weight), points), dtype=np.float64)
