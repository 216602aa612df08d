"""Where the commands write, checked before any work starts; nothing the user
had is ever deleted.

Output files (``render -o x.exr``): the folder must exist and take a new file.
Writability is tried (a temporary file is created and removed), not asked of
``os.access``, which says yes to root even on a read-only file system. An
existing file is replaced atomically, as ``mitsuba -o`` replaces it.

Report folders (``compare -o DIR``, ``validate -o DIR``) are one of:

- a path that does not exist yet (its parent folder must);
- an empty folder;
- a previous report of ours: a folder holding the marker file ``.mi-brdfs-report``,
  which lists every file that report wrote (paths relative to the folder: a
  report may have subfolders, e.g. the bench's fit sweep), and nothing else.
  A subfolder the report wrote that is a report of ours itself, with its own
  marker, counts with every file that marker lists: the bench's ``trade/``
  is re-run by its own command (``python -m mi_brdfs.tools.fit.trade -o
  docs/benchmarks/trade``), which writes files the bench's marker never
  listed, and the bench must still take its folder.

Anything else (an existing file, a folder holding other files, a folder that
holds one of the command's inputs, a symbolic link) is refused with one line,
before any work, and nothing is touched, however the path is spelled: a
trailing separator (``out/``, ``link/``) names the same folder as without, and
a relative path (``.`` included) is taken from the current folder
(:func:`report_target`). The report is written into a temporary folder beside
the target and moved into place when complete; a previous report is replaced
by deleting only the files its marker lists (and the subfolders that held
them, once empty). File and folder modes follow the
umask (0644 and 0755 under umask 022), as for any file the user creates.
"""
from __future__ import annotations

import contextlib
import json
import os
import tempfile
from typing import Iterable, Iterator

from .. import _interrupt as interrupt
from ..render.exr import dir_mode, file_mode, new_file

MARKER = ".mi-brdfs-report"


class OutputError(ValueError):
    """An output path that cannot be used (reported on one line)."""


def check_writable_dir(directory: str) -> None:
    """Raise OutputError unless a new file can be created in ``directory``."""
    if not os.path.isdir(directory):
        raise OutputError(f"folder {directory} does not exist")
    try:
        with interrupt.temporary(lambda: new_file(directory, ".tmp-probe-")):
            pass                                 # made, then removed
    except OSError as error:
        raise OutputError(f"cannot write in {directory}: {error.strerror}") from None


def check_output_file(path: str, option: str = "-o") -> None:
    """An output file: not a folder, in an existing folder that takes new files."""
    if os.path.isdir(path):
        raise OutputError(f"{option} {path} is a folder; give a file name")
    check_writable_dir(os.path.dirname(os.path.abspath(path)))


def _listing(path: str) -> list[str]:
    """Every file under ``path``, as relative paths ("/"-separated), and every
    folder that holds no file (as "name/"), sorted."""
    found = []
    for folder, dirs, files in os.walk(path):
        rel = os.path.relpath(folder, path)
        prefix = "" if rel == "." else rel.replace(os.sep, "/") + "/"
        found += [prefix + name for name in files]
        if not files and not dirs and prefix:
            found.append(prefix)
    return sorted(found)


def _safe(name) -> bool:
    """A marker entry: a relative path inside the report, no "..", no absolute path."""
    parts = name.split("/") if isinstance(name, str) else [""]
    return all(part not in ("", ".", "..") for part in parts)


def previous_report(path: str) -> list[str] | None:
    """The files a previous report of ours in ``path`` wrote (from its marker),
    or None if ``path`` holds no readable marker."""
    try:
        with open(os.path.join(path, MARKER)) as f:
            files = json.load(f)["files"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if not isinstance(files, list) or not all(_safe(n) for n in files):
        return None
    for sub in dict.fromkeys(n.split("/")[0] for n in files if "/" in n):
        inner = previous_report(os.path.join(path, sub))     # a report of its own in it
        if inner is not None:
            files = files + [f"{sub}/{n}" for n in inner + [MARKER]]
    return list(dict.fromkeys(files))


def _inside(path: str, folder: str) -> bool:
    path, folder = os.path.realpath(path), os.path.realpath(folder)
    return os.path.commonpath([path, folder]) == folder


def report_target(path: str) -> str:
    """``path`` as the folder it names: absolute, with trailing separators,
    ``.`` and ``..`` resolved as written (``out/`` is ``out``, a link
    ``elink/`` is the link ``elink``, ``.`` the current folder)."""
    return os.path.abspath(path)


def check_report_dir(path: str, inputs: Iterable[str] = (), option: str = "-o") -> None:
    """Raise OutputError unless ``path`` may receive a report (see the module doc)."""
    shown = f"{option} {path}"
    path = report_target(path)
    for name in inputs:
        if _inside(name, path):
            raise OutputError(f"{shown} holds the input {name}; give another folder")
    if os.path.islink(path):
        raise OutputError(f"{shown} is a symbolic link; give a new or empty folder")
    if os.path.exists(path):
        if not os.path.isdir(path):
            raise OutputError(f"{shown} is an existing file; give a new or empty folder "
                              "(nothing was written)")
        present = _listing(path)
        if present:
            listed = previous_report(path)
            if listed is None:
                raise OutputError(f"{shown} is a folder holding other files "
                                  f"({_few(present)}), not an mi-brdfs report; "
                                  "give a new or empty folder (nothing was written)")
            foreign = [n for n in present if n != MARKER and n not in set(listed)]
            if foreign:
                raise OutputError(f"{shown} holds a previous report and other files "
                                  f"({_few(foreign)}); give a new or empty folder "
                                  "(nothing was written)")
    check_writable_dir(os.path.dirname(os.path.abspath(path)))


def _few(names: list[str], n: int = 3) -> str:
    return ", ".join(names[:n]) + (f" and {len(names) - n} more" if len(names) > n else "")


@contextlib.contextmanager
def report_dir(path: str, command: str, inputs: Iterable[str] = ()) -> Iterator[str]:
    """Check ``path`` (see :func:`check_report_dir`), yield a temporary folder
    to write the report into, then move it to ``path`` with its marker. On an
    error or an interruption the temporary folder is removed and ``path`` is
    left as it was."""
    inputs = list(inputs)
    check_report_dir(path, inputs)
    path = report_target(path)
    parent = os.path.dirname(os.path.abspath(path))
    # our own temporary folder, removed unless moved into place (Ctrl-C included)
    with interrupt.temporary(lambda: tempfile.mkdtemp(prefix=".tmp-report-", dir=parent)) as tmp:
        yield tmp
        files = [n for n in _listing(tmp) if not n.endswith("/")]
        with open(os.path.join(tmp, MARKER), "w") as f:
            json.dump({"command": command, "files": files}, f, indent=1)
        for name in files + [MARKER]:
            os.chmod(os.path.join(tmp, name), file_mode())
        for folder, _, _ in os.walk(tmp):
            os.chmod(folder, dir_mode())         # mkdtemp made it 0700
        check_report_dir(path, inputs)           # unchanged while we worked
        with interrupt.critical():               # a previous report is set aside meanwhile
            _move_into_place(tmp, path)


def _move_into_place(tmp: str, path: str) -> None:
    if not os.path.exists(path):
        os.rename(tmp, path)
        return
    listed = previous_report(path)
    if listed is None:                           # an empty folder
        os.rmdir(path)
        os.rename(tmp, path)
        return
    # A previous report: set it aside, put the new one in place, then delete
    # the files the old marker lists (and nothing else).
    old = tempfile.mkdtemp(prefix=".tmp-old-report-", dir=os.path.dirname(os.path.abspath(path)))
    os.rename(path, old)                         # onto the empty folder just made
    try:
        os.rename(tmp, path)
    except OSError:
        os.rename(old, path)
        raise
    for name in listed + [MARKER]:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(os.path.join(old, name))
    # the subfolders that held them, deepest first, if nothing else is in them
    folders = {os.path.dirname(n) for n in listed if "/" in n}
    for folder in sorted({"/".join(f.split("/")[:k]) for f in folders
                          for k in range(1, f.count("/") + 2)}, key=len, reverse=True):
        with contextlib.suppress(OSError):
            os.rmdir(os.path.join(old, folder))
    with contextlib.suppress(OSError):
        os.rmdir(old)
