"""Ctrl-C ends a command within about a second, wherever it is: during the
imports (one line, status 130, no traceback), and during a render pass that
runs for minutes (the previous output kept, no temporary file left); and in
each order in which the main thread and the watcher can end it, no temporary
path is left and the line is printed once. Each command runs in its own
process with SIGINT's default disposition (a test run in the background would
otherwise hand it on ignored)."""
import os
import pty
import signal
import subprocess
import sys
import time

import pytest

LAUNCH = "import sys, mi_brdfs_command; sys.exit(mi_brdfs_command.main())"

# A render pass that runs for minutes, watched, with a temporary file
# registered and another file not: the watcher removes the first only.
KERNEL = r"""
import sys
import numpy as np
import drjit as dr, mitsuba as mi
import mi_brdfs
from mi_brdfs import _interrupt as interrupt
scene = mi.load_file(mi_brdfs.scenes.path("course"), mode="hdr", res=128)
dr.set_log_level(dr.LogLevel.Info)            # says when the kernel starts to run
with interrupt.watching("kernel") as watched, interrupt.temporary(lambda: sys.argv[1]):
    assert watched
    np.array(mi.render(scene, spp=1 << 17))   # (as the passes read it: waits for the kernel)
"""
# Dr.Jit's line (on stdout, its log at level Info) as a kernel starts to run:
# the signal then reaches the process while the main thread waits for that
# kernel, not while Python traces it (where a KeyboardInterrupt would do).
LAUNCHING = "-> launching"


def start(args):
    """The process, its stdout a terminal (Dr.Jit and Mitsuba log there through
    C's stdio, which a pipe would hold back in its buffer) read as
    ``process.lines``, its stderr a pipe."""
    leader, follower = pty.openpty()
    process = subprocess.Popen([sys.executable, *args], stdout=follower,
                               stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    os.close(follower)
    process.lines = terminal_lines(leader)
    return process


def terminal_lines(fd):
    """The lines written to a terminal's other end, until it closes."""
    with os.fdopen(fd, "r", errors="replace") as f:
        try:
            yield from f
        except OSError:                    # EIO: the process closed its end
            return


def interrupt_after(process, line_in, delay: float = 0.0):
    """Send SIGINT once ``line_in`` shows on the process's stdout (at once if
    None), ``delay`` s later; the seconds the process took to end, and its stderr."""
    if line_in is not None:
        for line in process.lines:
            if line_in in line:
                break
        else:
            pytest.fail(f"{line_in!r} never showed: {process.communicate()}")
    time.sleep(delay)
    sent = time.monotonic()
    process.send_signal(signal.SIGINT)
    try:
        _, err = process.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        process.kill()
        pytest.fail("the process did not end within 60 s of Ctrl-C")
    for _ in process.lines:                # (drains the terminal; closes it)
        pass
    return time.monotonic() - sent, err


# The entry point, with the import of Mitsuba held up: the Ctrl-C lands while
# the command's imports run, however fast the machine is.
SLOW_IMPORTS = r"""
import sys, time
import mi_brdfs_command

class Slow:
    def find_spec(self, name, path=None, target=None):
        if name == "mitsuba":
            print("importing mitsuba", flush=True)
            time.sleep(60)
        return None

sys.meta_path.insert(0, Slow())
sys.exit(mi_brdfs_command.main())
"""


def test_during_the_imports():
    """mi-brdfs's entry point, interrupted while it imports Mitsuba."""
    process = start(["-c", SLOW_IMPORTS, "scenes"])
    seconds, err = interrupt_after(process, "importing mitsuba")
    assert process.returncode == 130, err
    assert err == "mi-brdfs: interrupted\n"
    assert seconds < 5, seconds                    # (the import would take a minute)


def test_inside_a_kernel_the_watcher_ends_it(tmp_path):
    """Python cannot raise KeyboardInterrupt while the main thread waits for a
    render's kernel: the watcher ends the process, removing only the files
    registered."""
    registered, kept = tmp_path / ".tmp-partial.exr", tmp_path / "mine.exr"
    registered.write_text("half a file")
    kept.write_text("a user's file")
    process = start(["-c", KERNEL, str(registered)])
    seconds, err = interrupt_after(process, LAUNCHING, delay=0.5)
    assert process.returncode == 130, err
    assert err.strip().splitlines()[-1] == "kernel: interrupted", err
    assert seconds < 5, seconds               # the kernel alone runs for minutes
    assert not registered.exists() and kept.read_text() == "a user's file"


def test_during_a_render_pass(tmp_path):
    """Ctrl-C in the middle of a long first pass: out within a few seconds, the
    previous render kept, nothing else left in the folder."""
    out = tmp_path / "course.exr"
    out.write_bytes(b"the previous good render")
    process = start(["-c", LAUNCH, "render", "course", "-D", "mode=hdr", "-D", "res=256",
                     "--spp", "65536", "--passes", "2", "-vv", "-o", str(out)])
    seconds, err = interrupt_after(process, LAUNCHING, delay=0.5)
    assert process.returncode == 130, err
    assert err.strip().splitlines()[-1] == "mi-brdfs render: interrupted", err[-2000:]
    assert "Traceback" not in err
    assert seconds < 5, seconds
    assert out.read_bytes() == b"the previous good render"
    assert [p.name for p in tmp_path.iterdir()] == ["course.exr"]


# --- every order in which the two can end it, forced -----------------------------
# mi_brdfs/_interrupt.py alone (no Mitsuba), with a short grace.
# The main thread is put in position, says "ready", and the test sends SIGINT.
ORDERS = r"""
import importlib.util, os, signal, sys, time
spec = importlib.util.spec_from_file_location("interrupt", sys.argv[1])
interrupt = importlib.util.module_from_spec(spec)
spec.loader.exec_module(interrupt)
folder, order = sys.argv[2], sys.argv[3]
GRACE = 0.2

def partial():                        # a temporary file the command makes
    path = os.path.join(folder, ".tmp-partial")
    open(path, "w").close()
    return path

def ready():
    print("ready", flush=True)

def python_runs():                    # the KeyboardInterrupt is raised here
    ready()
    while True:
        time.sleep(0.01)

def in_a_kernel():                    # no Python runs (SIGINT reaches another thread)
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    ready()
    time.sleep(60)

def in_a_critical_block():            # the Ctrl-C comes while a report is moved into place
    with interrupt.critical():
        ready()
        time.sleep(0.5)
        open(os.path.join(folder, "moved"), "w").close()
    time.sleep(60)

# seconds the rest of the unwinding takes, after the temporary's own block
REST = {"slow unwinding": 3 * GRACE}
try:
    with interrupt.watching("prog", grace=GRACE):
        try:
            with interrupt.temporary(partial):
                {"watcher first": in_a_kernel, "critical": in_a_critical_block}.get(
                    order, python_runs)()
        finally:
            time.sleep(REST.get(order, 0.0))
except KeyboardInterrupt:
    sys.exit(3)                       # not reached: the watched block ends the process
"""


@pytest.mark.parametrize("order", ["watcher first", "main thread first", "slow unwinding",
                                   "critical"])
def test_every_order_leaves_nothing_and_says_it_once(tmp_path, order):
    """watcher first: the main thread waits in C (as for a kernel); main thread
    first: it unwinds by itself, within the grace or slower (the watcher then
    ends the process halfway through the unwinding, after the temporary's block
    removed its file: what failed under load); critical: the Ctrl-C comes
    inside a block that must not be cut, which ends before either acts."""
    import mi_brdfs
    module = os.path.join(os.path.dirname(mi_brdfs.__file__), "_interrupt.py")
    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "mine.exr").write_text("a user's file")
    process = start(["-c", ORDERS, module, str(folder), order])
    seconds, err = interrupt_after(process, "ready")
    assert process.returncode == 130, err
    assert [line for line in err.splitlines() if line.strip()] == ["prog: interrupted"], err
    assert sorted(p.name for p in folder.iterdir()) == \
        (["mine.exr", "moved"] if order == "critical" else ["mine.exr"])
    assert seconds < 3, seconds
