"""import mi_brdfs finds a working LLVM, and refuses a bad one with a clear error."""
import glob
import os
import subprocess
import sys

import pytest

import drjit as dr

BAD = sorted(glob.glob("/usr/lib/x86_64-linux-gnu/libLLVM-15.so*"))


def run(code, **env_changes):
    env = {k: v for k, v in os.environ.items() if k != "DRJIT_LIBLLVM_PATH"}
    env.update(env_changes)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)


def test_working_llvm_in_this_process():
    assert dr.detail.llvm_version()[0] >= 16


def test_import_finds_a_working_llvm_by_itself():
    out = run("import mi_brdfs, drjit as dr, mitsuba as mi; "
              "x = dr.minimum(mi.Float([1, 3]), 2.0); print(dr.detail.llvm_version()[0], x)")
    assert out.returncode == 0, out.stderr
    major, rest = out.stdout.split(" ", 1)
    assert int(major) >= 16 and "[1, 2]" in rest


@pytest.mark.skipif(not BAD, reason="no LLVM 15 on this machine")
def test_bad_llvm_is_refused_with_a_clear_error():
    out = run("import mi_brdfs", DRJIT_LIBLLVM_PATH=BAD[0])
    assert out.returncode == 1
    last = out.stderr.strip().splitlines()[-1]
    assert "LLVMError" in last and "LLVM 15" in last and "libLLVM-15" in last
    assert "karellen-llvm-core" in last and "libllvm19" in last


@pytest.mark.skipif(not BAD, reason="no LLVM 15 on this machine")
def test_importing_drjit_first_is_explained():
    out = run("import mitsuba, mi_brdfs")
    if out.returncode == 0:          # drjit found a working system LLVM by itself
        pytest.skip("drjit's own search finds a working LLVM here")
    last = out.stderr.strip().splitlines()[-1]
    assert "imported before mi_brdfs" in last and "DRJIT_LIBLLVM_PATH" in last
