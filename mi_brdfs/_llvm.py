"""Find an LLVM that Dr.Jit's LLVM backend can use, before Dr.Jit loads one.

Measured on Debian 12 (the project's machines): drjit 1.5.0 aborts the whole
interpreter (``LLVM ERROR: Cannot select: ... fminimum``) with LLVM 15, the
system default, and refuses LLVM 14; it works with Debian's ``libllvm19`` and
with the LLVM 23 shared library of the PyPI wheel ``karellen-llvm-core``, which
is a dependency of this package.

Dr.Jit loads its LLVM once, when ``drjit`` is first imported: it takes
``$DRJIT_LIBLLVM_PATH`` if set, else the first ``libLLVM`` it finds on the
system. So ``configure()`` must run before ``import drjit``; ``check()`` runs
after it and raises :class:`LLVMError` (which says what was found and how to fix
it) instead of letting a bad LLVM abort the interpreter later.
"""
from __future__ import annotations

import os
import sys
from importlib import metadata

ENV = "DRJIT_LIBLLVM_PATH"
MIN_WORKING = 16     # 15 aborts on llvm.minimum/maximum (measured); 14 is refused by drjit
WHEEL = "karellen-llvm-core"

FIX = (
    "Fix it with one of: `pip install karellen-llvm-core` (then import mi_brdfs "
    "before mitsuba/drjit, or export DRJIT_LIBLLVM_PATH=<its libLLVM.so>); "
    "`apt-get install libllvm19`; or export DRJIT_LIBLLVM_PATH=<path of an "
    f"LLVM >= {MIN_WORKING} libLLVM.so>."
)


class LLVMError(ImportError):
    """No LLVM that drjit can use was found (or drjit already loaded a bad one)."""


def wheel_library() -> str | None:
    """Path of the libLLVM shared library shipped by ``karellen-llvm-core``, if installed."""
    try:
        files = metadata.distribution(WHEEL).files or []
    except metadata.PackageNotFoundError:
        return None
    libs = [f for f in files if f.name.startswith("libLLVM.so.")]
    for f in libs:
        path = os.path.realpath(f.locate())
        if os.path.exists(path):
            return path
    return None


def configure() -> None:
    """Point drjit at the wheel's LLVM unless the user chose one or drjit is loaded."""
    if ENV in os.environ or "drjit" in sys.modules:
        return
    path = wheel_library()
    if path is not None:
        os.environ[ENV] = path


def loaded_library() -> str:
    """The libLLVM file mapped into this process (Linux), or a description."""
    try:
        with open("/proc/self/maps") as maps:
            for line in maps:
                if "libLLVM" in line:
                    return line.split()[-1]
    except OSError:
        pass
    return os.environ.get(ENV, "<unknown path>")


def check() -> None:
    """Raise LLVMError if drjit's LLVM backend is one known to abort or to be refused."""
    import drjit as dr          # here: configure() must run before drjit is first imported

    if not dr.has_backend(dr.JitBackend.LLVM):
        raise LLVMError(
            "mi_brdfs: drjit found no usable LLVM shared library "
            f"({ENV}={os.environ.get(ENV, '<unset>')}). " + FIX)
    version = tuple(dr.detail.llvm_version())
    if version[0] < MIN_WORKING:
        wheel = wheel_library()
        late = (f"drjit was imported before mi_brdfs, so mi_brdfs could not point it at "
                f"the working LLVM it found ({wheel}): import mi_brdfs first, or export "
                f"{ENV}={wheel}. " if ENV not in os.environ and wheel else "")
        raise LLVMError(
            f"mi_brdfs: drjit loaded LLVM {'.'.join(map(str, version))} from "
            f"{loaded_library()}; drjit 1.5 aborts the interpreter with LLVM < "
            f"{MIN_WORKING} (LLVM ERROR: Cannot select ... fminimum). {late}" + FIX)
