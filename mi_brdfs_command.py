"""The entry point of the ``mi-brdfs`` command, outside the package.

Importing :mod:`mi_brdfs` loads LLVM, Dr.Jit and Mitsuba and registers the
plugins: a second or more. A Ctrl-C in that time must end the command as one
anywhere else does (one line, status 130). A KeyboardInterrupt raised inside
an extension's initialisation leaves it half-made (measured: an ImportError
from nanobind, then a NameError, or an abort when Python finalises), so while
the package loads, Ctrl-C ends the process at once instead: nothing has been
written yet. A handler inside the package would run only once it is imported;
so the command starts here.
"""
from __future__ import annotations

import os
import signal
import sys


def _interrupted(signum, frame) -> None:
    sys.stderr.write("mi-brdfs: interrupted\n")
    sys.stderr.flush()
    os._exit(130)


def main() -> int:
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})   # whatever it inherited
    previous = signal.getsignal(signal.SIGINT)
    if previous is not signal.SIG_IGN:             # (a background job ignores it)
        signal.signal(signal.SIGINT, _interrupted)
    try:
        from mi_brdfs.tools.cli import main as command
    finally:
        signal.signal(signal.SIGINT, previous)
    return command()


if __name__ == "__main__":
    sys.exit(main())
