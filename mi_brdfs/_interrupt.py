"""Ctrl-C ends a command within about a second, wherever it is, and leaves no
temporary file behind.

Python raises KeyboardInterrupt only between bytecodes of the main thread:
while the main thread waits for a render pass (a Dr.Jit kernel that can run
for minutes), or while Mitsuba's C++ calls a plugin's Python code (which may
swallow the exception), nothing may happen for minutes. So while a command
runs (:func:`watching`) two things act on Ctrl-C:

- **the main thread**, as usual: it raises KeyboardInterrupt as soon as it
  runs Python and unwinds, each block cleaning up after itself, and
  :func:`end` prints "PROG: interrupted" and ends the process with status
  130 at once (a normal exit would wait for Dr.Jit's kernels still in flight,
  minutes of a render pass);
- **the watcher**, a thread woken at once through Python's wake-up fd (written
  by the C-level handler from whichever thread the signal reaches). If the
  command has not ended within :data:`GRACE` seconds of the signal, the
  watcher ends the process: it removes the temporary paths still registered,
  prints the same line and exits with status 130.

**One owner per temporary path at every moment.** A temporary file or folder
is made and registered, and later removed and deregistered, by
:func:`temporary` while holding one lock, the lock the watcher takes before it
removes anything and keeps until the process is gone; and a KeyboardInterrupt
that comes while the main thread holds that lock is raised when it lets go
(:func:`critical` blocks, such as a report moved into place, are never cut
halfway either). So a path is either registered, and the watcher would remove
it, or already removed (or moved into place) by its block: whichever of the
two ends the process, and however slowly the main thread unwinds, nothing is
left. The line is printed once, by whichever ends the command.

(The watcher needs Python's lock: a Dr.Jit read-back that keeps it while it
waits for a kernel, such as ``float(x[0])``, delays the exit until the kernel
ends; the render passes read with NumPy, which lets it go, measured.)
"""
from __future__ import annotations

import contextlib
import os
import shutil
import signal
import sys
import threading
import time
from typing import Callable, Iterator

GRACE = 0.5        # seconds after Ctrl-C before the watcher ends the command

_temporary: set[str] = set()     # the temporary paths the watcher would remove
_lock = threading.RLock()        # held to make, remove or move them; the watcher keeps it
_deferred = False                # a Ctrl-C that came while the main thread held the lock
_announced = False               # "PROG: interrupted" is written


@contextlib.contextmanager
def _owned() -> Iterator[None]:
    """A block holding the lock: the watcher waits for it, and a Ctrl-C that
    comes meanwhile raises KeyboardInterrupt when it ends (never inside)."""
    global _deferred
    with _lock:
        yield
    if _deferred and not _lock._is_owned():
        _deferred = False
        raise KeyboardInterrupt


def _remove(path: str) -> None:
    with contextlib.suppress(OSError):
        if os.path.isdir(path) and not os.path.islink(path):
            shutil.rmtree(path)
        else:
            os.unlink(path)


@contextlib.contextmanager
def temporary(make: Callable[[], str]) -> Iterator[str]:
    """Own a temporary file or folder while the block runs: ``make()`` creates
    it and returns its path. When the block ends, whichever way, the path is
    removed if it is still there (a block that succeeds has moved it into
    place); if the watcher ends the process first, the watcher removes it."""
    path = None
    try:
        with _owned():
            path = make()
            _temporary.add(path)
        yield path
    finally:
        if path is not None:
            with _owned():
                _remove(path)
                _temporary.discard(path)


@contextlib.contextmanager
def critical() -> Iterator[None]:
    """A block that a hard exit waits for and that Ctrl-C does not cut (e.g. a
    report moved into place: the user's previous report is set aside for the
    few milliseconds it takes)."""
    with _owned():
        yield


def _announce(prog: str, start: str = "") -> None:
    global _announced
    if not _announced:
        _announced = True
        with contextlib.suppress(OSError, ValueError):
            sys.stderr.write(f"{start}{prog}: interrupted\n")
            sys.stderr.flush()


def end(prog: str) -> None:
    """The command has unwound after a Ctrl-C: remove what a clean-up that the
    interrupt cut short left registered, print "PROG: interrupted" unless the
    watcher has, and end the process with status 130 (the output flushed)."""
    with _owned():
        for path in list(_temporary):
            _remove(path)
        _temporary.clear()
        _announce(prog)
        with contextlib.suppress(OSError, ValueError):
            sys.stdout.flush()
        os._exit(130)


def _hard_exit(prog: str) -> None:
    _lock.acquire()                      # kept: nothing is made, removed or moved after this
    for path in list(_temporary):
        _remove(path)
    _announce(prog, start="\n")         # (after a progress bar's line)
    os._exit(130)


def _on_interrupt(signum, frame) -> None:
    """The main thread's SIGINT handler while a command is watched."""
    global _deferred
    if _lock._is_owned():                # inside a block that must not be cut: at its end
        _deferred = True
        return
    raise KeyboardInterrupt


@contextlib.contextmanager
def watching(prog: str, grace: float = GRACE) -> Iterator[bool]:
    """Run the block with Ctrl-C watched as the module says; yields False (and
    watches nothing) outside the main thread, where SIGINT is ignored, or where
    someone else's wake-up fd is set. An interrupted block ends the process
    (:func:`end`) when its KeyboardInterrupt reaches this block."""
    global _deferred, _announced
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is signal.SIG_IGN):
        yield False
        return
    read, write = os.pipe()
    os.set_blocking(write, False)
    previous_fd = signal.set_wakeup_fd(write, warn_on_full_buffer=False)
    if previous_fd != -1:                              # someone else's: leave it
        signal.set_wakeup_fd(previous_fd)
        os.close(read)
        os.close(write)
        yield False
        return
    _deferred = _announced = False

    def wait() -> None:
        while True:
            try:
                byte = os.read(read, 1)
            except OSError:
                return
            if not byte:                               # the block ended: pipe closed
                return
            if byte[0] == signal.SIGINT:
                time.sleep(grace)                      # the main thread may end it first
                _hard_exit(prog)

    previous_handler = signal.signal(signal.SIGINT, _on_interrupt)
    watcher = threading.Thread(target=wait, name="mi-brdfs-interrupt", daemon=True)
    watcher.start()
    try:
        yield True
    except KeyboardInterrupt:
        end(prog)
    finally:
        signal.signal(signal.SIGINT, previous_handler)
        signal.set_wakeup_fd(-1)
        os.close(write)
        watcher.join(timeout=1.0)
        os.close(read)
