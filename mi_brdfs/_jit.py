"""NumPy arrays into Dr.Jit arrays, in Dr.Jit's own memory.

Measured with Dr.Jit 1.5.0 on the LLVM backend: ``mi.Float(a)`` for a NumPy
array ``a`` whose dtype matches does not copy ``a`` — it maps NumPy's buffer
(``jit_var_mem_map``: a later change of ``a`` shows in the Dr.Jit array; an
array of another dtype is converted first, which we have not taken apart, so
it goes the same way here). Dr.Jit's LLVM kernels read an input array a whole
vector at a time, the last vector included: up to a vector's width of elements
past the array's end. Its own allocations are padded for that; NumPy's are not.
Where NumPy's buffer ends right before an unmapped page, the kernel dies by
SIGSEGV. That is rare and depends on the process's allocation history (CI
saw it once, ``mi-brdfs validate`` in Mitsuba's χ² code over an array made
here); ``tests/test_jit.py`` makes it happen every time with a guard page.
``dr.copy`` does not help: the copy is such a kernel.

:func:`from_numpy` copies the values into a padded, 64-byte aligned NumPy
buffer (so that the same code gives the same kernel from run to run: the
alignment of an input is part of a kernel's hash), maps that, and gathers the
values into an array Dr.Jit allocates. Every NumPy array the package hands to
Dr.Jit goes through it.
"""
from __future__ import annotations

import numpy as np

import drjit as dr

PAD = 64            # elements: beyond any LLVM vector width (16 with AVX-512)
ALIGN = 64          # bytes
DTYPES = {"Float32": np.float32, "Float64": np.float64, "UInt32": np.uint32,
          "Int32": np.int32, "UInt64": np.uint64, "Int64": np.int64, "Bool": np.bool_}


def from_numpy(cls, values):
    """A ``cls`` holding a copy of ``values``, in memory Dr.Jit allocated.

    ``cls`` is a flat Dr.Jit array type (``mi.Float``, ``mi.UInt32``: ``values``
    is anything NumPy makes a 1-D array of) or a vector of them
    (``mi.Vector3f``, ``mi.Point2f``, ``mi.Color3f``: ``values`` holds one such
    array per component, e.g. ``wo.T`` for an (n, 3) array ``wo``). Non-JIT
    types (scalar variants) are built directly."""
    if not dr.is_jit_v(cls):
        return cls(*values) if dr.depth_v(cls) == 2 else cls(values)
    if dr.depth_v(cls) == 2:
        return cls(*(from_numpy(dr.value_t(cls), c) for c in values))
    if dr.depth_v(cls) != 1:
        raise TypeError(f"from_numpy: {cls.__name__} is neither a flat array type "
                        "nor a vector of one")
    dtype = np.dtype(DTYPES[dr.type_v(cls).name])
    a = np.asarray(values, dtype=dtype).ravel()
    n = a.size
    if n == 0:
        return dr.zeros(cls, 0)
    count = -(-n // PAD) * PAD + PAD
    raw = np.zeros(count * dtype.itemsize + ALIGN, dtype=np.uint8)
    skip = (-raw.ctypes.data) % ALIGN
    padded = raw[skip:skip + count * dtype.itemsize].view(dtype)
    padded[:n] = a
    index = dr.arange(dr.uint32_array_t(cls), n)
    out = dr.gather(cls, cls(padded), index)
    dr.eval(out)
    return out
