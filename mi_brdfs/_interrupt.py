"""Ctrl-C ends a command within about a second, wherever it is.

Python runs its SIGINT handler (the KeyboardInterrupt) only between bytecodes
of the main thread: while the main thread waits for a render pass (a Dr.Jit
kernel that can run for minutes) nothing happens until the pass ends. While a
command runs (:func:`watching`), Python's C-level handler also writes to a
pipe at once (from whichever thread the signal reaches), and a thread waiting
on that pipe ends the process if the command has not ended within
:data:`GRACE` seconds of the signal: it removes the temporary files and
folders registered with :func:`temporary` (the atomic writes' and the
reports' own, nothing else), prints "PROG: interrupted" and exits with status
130. A main thread that reaches Python meanwhile unwinds as usual
(KeyboardInterrupt), cleans up, and says :func:`finished` first. (The
thread needs Python's lock: a Dr.Jit read-back that keeps it while it waits
for a kernel, such as ``float(x[0])``, delays the exit until the kernel ends;
the render passes read with NumPy, which lets it go, measured.)
"""
from __future__ import annotations

import contextlib
import os
import shutil
import signal
import sys
import threading
from typing import Iterator

GRACE = 0.5                      # seconds the main thread has to unwind by itself

_temporary: set[str] = set()     # paths to remove on a hard exit
_lock = threading.RLock()        # held while a hard exit must wait (see critical())
_finished = threading.Event()


@contextlib.contextmanager
def temporary(path: str) -> Iterator[str]:
    """Register ``path`` (a temporary file or folder the caller made) for removal
    should the process be ended by the watcher while the block runs."""
    with _lock:
        _temporary.add(path)
    try:
        yield path
    finally:
        with _lock:
            _temporary.discard(path)


@contextlib.contextmanager
def critical() -> Iterator[None]:
    """A block a hard exit waits for (e.g. a report moved into place: the user's
    previous report is set aside for the few milliseconds it takes)."""
    with _lock:
        yield


def finished() -> None:
    """The command is ending by itself (it caught the interrupt): the watcher
    stands down."""
    _finished.set()


def _hard_exit(prog: str) -> None:
    _lock.acquire()                      # kept: nothing registers or moves after this
    for path in list(_temporary):
        with contextlib.suppress(OSError):
            if os.path.isdir(path) and not os.path.islink(path):
                shutil.rmtree(path)
            else:
                os.unlink(path)
    with contextlib.suppress(OSError, ValueError):
        sys.stderr.write(f"\n{prog}: interrupted\n")
        sys.stderr.flush()
    os._exit(130)


@contextlib.contextmanager
def watching(prog: str, grace: float = GRACE) -> Iterator[bool]:
    """Run the block with Ctrl-C watched as the module says; yields False (and
    watches nothing) outside the main thread, where SIGINT is ignored, or where
    someone else's wake-up fd is set."""
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is signal.SIG_IGN):
        yield False
        return
    read, write = os.pipe()
    os.set_blocking(write, False)
    previous = signal.set_wakeup_fd(write, warn_on_full_buffer=False)
    if previous != -1:                                 # someone else's: leave it
        signal.set_wakeup_fd(previous)
        os.close(read)
        os.close(write)
        yield False
        return
    _finished.clear()

    def wait() -> None:
        while True:
            try:
                byte = os.read(read, 1)
            except OSError:
                return
            if not byte:                               # the block ended: pipe closed
                return
            if byte[0] == signal.SIGINT and not _finished.wait(grace):
                _hard_exit(prog)

    watcher = threading.Thread(target=wait, name="mi-brdfs-interrupt", daemon=True)
    watcher.start()
    try:
        yield True
    finally:
        signal.set_wakeup_fd(-1)
        os.close(write)
        watcher.join(timeout=1.0)
        os.close(read)
