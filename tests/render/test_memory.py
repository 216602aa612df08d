"""What a render needs in memory (mi_brdfs/render/memory.py): the estimate
against a measured render, and a render too large for the machine refused
before any work, on one line naming the estimate, the limit and what to lower."""
import json
import subprocess
import sys

import pytest

from mi_brdfs.render import memory
from mi_brdfs.tools import cli, errors

# The peak RSS of one `mi-brdfs render` in a fresh process, as JSON on stdout:
# the kernel's VmHWM, which starts anew at exec (ru_maxrss would keep the
# size of the test process it was forked from).
MEASURE = r"""
import json, sys
from mi_brdfs.tools import cli
code = cli.main(sys.argv[1:])
with open("/proc/self/status") as f:
    kib = next(int(line.split()[1]) for line in f if line.startswith("VmHWM:"))
print(json.dumps({"code": code, "kib": kib}))
"""


def peak_bytes(res: int, out) -> int:
    done = subprocess.run([sys.executable, "-c", MEASURE, "render", "lambert", "-D",
                           f"res={res}", "--spp", "2", "--passes", "2", "-q", "-o", str(out)],
                          capture_output=True, text=True, timeout=600)
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["code"] == 0, done.stderr
    return result["kib"] * 1024


def test_estimate_holds_a_measured_render(tmp_path):
    """The growth of the peak RSS from a 64² to a 1536² render lies within 30 %
    of the growth of the estimate (a process's start-up size is not part of it)."""
    small, large = (peak_bytes(res, tmp_path / f"{res}.exr") for res in (64, 1536))
    estimate = memory.Need(1536, 1536, 3).bytes - memory.Need(64, 64, 3).bytes
    assert 0.7 < (large - small) / estimate < 1.3, (large - small, estimate)


def test_too_large_for_the_machine_is_refused_first(tmp_path, monkeypatch, capsys):
    out = tmp_path / "big.exr"
    out.write_bytes(b"a previous render")
    monkeypatch.setattr(memory, "available", lambda: (200 * 2**20, "available memory"))
    assert cli.main(["render", "lambert", "-D", "res=2048", "-q", "-o", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert err.startswith("mi-brdfs render: error: a 2048x2048 render needs about 520 MiB "
                          "of memory"), err
    assert "more than available memory (200 MiB); lower -D res" in err, err
    assert out.read_bytes() == b"a previous render"           # nothing touched
    assert [p.name for p in tmp_path.iterdir()] == ["big.exr"]


def test_larger_than_a_dr_jit_array_is_refused(tmp_path, capsys):
    assert cli.main(["render", "lambert", "-D", "res=100000", "-q", "-o",
                     str(tmp_path / "x.exr")]) == 1
    err = capsys.readouterr().err.strip()
    assert "a 100000x100000 film with 3 channels holds 5e+10 values, more than Dr.Jit's " \
           "largest array" in err, err
    assert "(see above)" not in err


def test_available_is_the_least_limit():
    room, what = memory.available()
    assert 0 < room < 2**63 and what


@pytest.mark.parametrize("chain", ["cause", "context"])
def test_an_error_that_says_see_above_shows_its_cause(chain):
    try:
        try:
            raise RuntimeError("Tensor(): invalid size specified (40000000000 vs 1345294336)!")
        except RuntimeError as inner:
            outer = RuntimeError("drjit.custom(<Op>): error while performing a custom "
                                 "differentiable operation. (see above).")
            if chain == "cause":
                raise outer from inner
            raise outer
    except RuntimeError as error:
        assert errors.one_line(error) == ("Tensor(): invalid size specified "
                                       "(40000000000 vs 1345294336)!")
