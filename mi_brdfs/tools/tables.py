"""Build and check the shipped albedo tables of :mod:`mi_brdfs.bsdfs.energy`.

    python -m mi_brdfs.tools.tables            # rebuild mi_brdfs/bsdfs/data/albedo.npz
    python -m mi_brdfs.tools.tables --check    # measure the tables' errors

``--check`` measures, for every table, (1) the quadrature error: the largest
difference between the shipped values and a fresh build with half the
samples per axis, and (2) the interpolation error: the largest difference
between E computed at the centres of the cells (every axis refined 2x) and
the table's multilinear interpolation there, over the whole table and over
the incident angles up to 85° (cos θ >= 0.087). The compensated albedo is
1 + (E - E~), so (2) bounds the white furnace's deviation from 1.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import replace

import numpy as np

MU_85 = 0.0871557      # cos 85°


def refined(spec):
    """The spec with every axis refined 2x (its nodes and the cell centres)."""
    axes = tuple(replace(a, n=2 * a.n - 1) for a in spec.axes)
    return replace(spec, axes=axes)


def interpolation_error(spec, table, samples: int) -> tuple[float, float]:
    """(max |E - E~| at cell centres, the same for cos θ >= cos 85°)."""
    import drjit as dr
    import mitsuba as mi

    from ..bsdfs import energy
    fine = refined(spec)
    exact = energy.build(fine, samples)
    centres = tuple(slice(1, None, 2) for _ in fine.axes)
    exact = exact[centres]
    points = [a.nodes()[1::2] for a in fine.axes]
    mesh = [m.ravel() for m in np.meshgrid(*points, indexing="ij")]
    interp = np.asarray(table.grid(*[mi.Float(m) for m in mesh])).reshape(exact.shape)
    dr.eval()
    err = np.abs(exact - np.clip(interp, 0, 1))
    up = points[0] >= MU_85
    return float(err.max()), float(err[up].max())


def main(argv: list[str] | None = None) -> int:
    """Rebuild the albedo tables, or (--check) measure their errors."""
    import mi_brdfs  # noqa: F401  (LLVM set-up, variant)
    import drjit as dr
    import mitsuba as mi

    from ..bsdfs import energy

    parser = argparse.ArgumentParser(prog="python -m mi_brdfs.tools.tables",
                                     description=main.__doc__)
    parser.add_argument("--check", action="store_true", help="measure the shipped tables' errors")
    parser.add_argument("--samples", type=int, default=energy.SAMPLES,
                        help=f"quadrature samples per axis (default {energy.SAMPLES})")
    args = parser.parse_args(argv)
    if not dr.is_jit_v(mi.Float):
        mi.set_variant("llvm_ad_rgb")
    out = {}
    for spec in energy.specs():
        start = time.perf_counter()
        if args.check:
            shipped = energy.table(spec)
            half = energy.build(spec, args.samples // 2)
            quad = float(np.max(np.abs(half - shipped.grid.values)))
            inter, inter85 = interpolation_error(spec, shipped, max(16, args.samples // 4))
            print(f"{spec.name}: axes {'x'.join(str(a.n) for a in spec.axes)}; quadrature "
                  f"error {quad:.1e}; interpolation error {inter:.1e} "
                  f"(up to 85 deg: {inter85:.1e}) [{time.perf_counter() - start:.0f} s]")
            continue
        out[spec.name] = energy.build(spec, args.samples)
        print(f"{spec.name}: {out[spec.name].size} nodes x {args.samples}^2 samples, "
              f"{time.perf_counter() - start:.1f} s", file=sys.stderr)
    if args.check:
        return 0
    os.makedirs(os.path.dirname(energy.DATA), exist_ok=True)
    tmp = energy.DATA + ".tmp.npz"
    np.savez_compressed(tmp, **{k: v.astype(np.float32) for k, v in out.items()})
    os.replace(tmp, energy.DATA)
    print(f"wrote {energy.DATA}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
