"""NumPy arrays into Dr.Jit (mi_brdfs._jit.from_numpy): values kept, and no read
past the end of NumPy's buffer — checked with a buffer that ends at a page
the process may not read, in a subprocess (a read past it kills that process)."""
import subprocess
import sys

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_brdfs._jit import from_numpy

GUARDED = r"""
import ctypes, mmap, sys
import numpy as np
import mi_brdfs, drjit as dr, mitsuba as mi
from mi_brdfs._jit import from_numpy

how, name, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
cls = getattr(mi, name)
dtype = {"Float": np.float32, "Float64": np.float64, "UInt32": np.uint32}[name]
libc = ctypes.CDLL(None)
libc.mprotect.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int]
page = mmap.PAGESIZE
size = n * np.dtype(dtype).itemsize
pages = -(-size // page) + 1
buf = mmap.mmap(-1, pages * page)
base = ctypes.addressof(ctypes.c_char.from_buffer(buf))
assert libc.mprotect(base + (pages - 1) * page, page, 0) == 0     # the last page: no access
a = np.frombuffer(buf, dtype=dtype, count=n, offset=(pages - 1) * page - size)
a[:] = np.arange(n) % 7
x = cls(a) if how == "plain" else from_numpy(cls, a)
y = x * 2 + 1                      # a kernel that reads x lane by lane
dr.eval(y)
print(float(dr.sum(mi.Float64(y))[0]))
"""


def guarded(how, name, n):
    return subprocess.run([sys.executable, "-c", GUARDED, how, name, str(n)],
                          capture_output=True, text=True)


@pytest.mark.parametrize("name", ["Float", "Float64", "UInt32"])
@pytest.mark.parametrize("n", [1, 5, 20100, 1_000_003])
def test_from_numpy_reads_nothing_past_the_buffer(name, n):
    run = guarded("helper", name, n)
    assert run.returncode == 0, run.stderr
    assert float(run.stdout) == pytest.approx(float(np.sum(2 * (np.arange(n) % 7) + 1)))


def test_the_guard_catches_dr_jits_own_read_past_the_end():
    """The control: Dr.Jit maps a NumPy array of its own dtype, and a kernel reads
    past its end (Dr.Jit 1.5.0). If this stops happening, from_numpy is no
    longer needed."""
    run = guarded("plain", "Float", 20100)
    if run.returncode == 0:
        pytest.skip("this Dr.Jit no longer reads past a mapped NumPy buffer")
    assert run.returncode < 0                       # killed by a signal


@pytest.mark.parametrize("cls, dtype", [(mi.Float, np.float32), (mi.Float64, np.float64),
                                        (mi.UInt32, np.uint32), (mi.Int32, np.int32)])
def test_from_numpy_copies_the_values(cls, dtype):
    a = np.arange(37, dtype=dtype) * 3
    x = from_numpy(cls, a)
    assert type(x) is cls and dr.width(x) == a.size
    a_before = np.array(a, dtype=dtype)
    a[:] = 0                                          # a copy: later changes don't show
    assert np.array_equal(np.array(x), a_before)


def test_from_numpy_converts_lists_and_other_dtypes():
    x = from_numpy(mi.Float, [0.5, 1.5, 2.5])
    assert np.array_equal(np.array(x), np.array([0.5, 1.5, 2.5], np.float32))
    assert dr.width(from_numpy(mi.Float, np.zeros(0))) == 0
    with pytest.raises(TypeError, match="Matrix3f is neither a flat array type"):
        from_numpy(mi.Matrix3f, np.zeros((3, 3, 2)))


def test_from_numpy_builds_vectors_from_components():
    wo = np.arange(12, dtype=np.float64).reshape(4, 3)
    v = from_numpy(mi.Vector3f, wo.T)
    assert type(v) is mi.Vector3f
    assert np.array_equal(np.array(v), wo.T)
