"""The one error type of the tools and how any error reads as one line.

Below every command (render, compare, validate, bench, fit, explore) and
the CLI that runs them: a tool raises :class:`CLIError` for bad input it
found itself, and the CLI prints any error through :func:`one_line`.
"""
from __future__ import annotations

import re


class CLIError(Exception):
    """An error reported as one line, without a traceback."""


# Mitsuba's messages start with the source file and line that noticed the
# problem ("[parser.cpp:444] "): a user reads what went wrong, not where.
SOURCE = re.compile(r"^\[[\w.+-]+\.(?:cpp|h|py):\d+\]\s*")


def one_line(error: BaseException) -> str:
    """The gist of an error on one line. Mitsuba wraps a Python plugin's
    exception with its traceback: keep only the exception's own last line.
    Dr.Jit's wrapper of a failed custom operation says only "(see above)":
    its cause's message instead. Mitsuba's source-file prefix is left out."""
    while "(see above)" in str(error) and (error.__cause__ or error.__context__):
        error = error.__cause__ or error.__context__
    text = str(error).strip()
    lines = [SOURCE.sub("", line.strip()) for line in text.splitlines() if line.strip()]
    if not lines:
        return type(error).__name__
    if "Traceback (most recent call last)" in text:
        where = re.search(r"At (.+?\(line \d+, col \d+\))", lines[0])
        return (f"{where.group(1)}: " if where else "") + lines[-1]
    return " ".join(lines)
