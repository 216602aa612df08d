"""What the commands' shared arguments mean: checked numbers (argparse types
whose bad value is one line, exit 1) and Mitsuba's settings (variant,
threads, log level). Used by the CLI, by the render command and by the tools
that parse arguments of their own (the explorer's backend)."""
from __future__ import annotations

import argparse
import math
import sys
from typing import Callable

import drjit as dr
import mitsuba as mi

import mi_brdfs

from .errors import CLIError, one_line


def integer(low: int, high: int | None = None) -> Callable[[str], int]:
    """An argparse type: an integer in [low, high]."""
    valid = f"an integer >= {low}" if high is None else f"an integer from {low} to {high}"

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"invalid value {text!r}; valid: {valid}") from None
        if value < low or (high is not None and value > high):
            raise argparse.ArgumentTypeError(f"invalid value {text}; valid: {valid}")
        return value
    return parse


def real(low: float, high: float) -> Callable[[str], float]:
    """An argparse type: a finite number in [low, high]."""
    valid = f"a number from {low:g} to {high:g}"

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"invalid value {text!r}; valid: {valid}") from None
        if not math.isfinite(value) or not low <= value <= high:
            raise argparse.ArgumentTypeError(f"invalid value {text}; valid: {valid}")
        return value
    return parse


def set_variant(name: str | None) -> str:
    if name:
        if name not in mi.variants():
            raise CLIError(f"-m {name} is not a Mitsuba variant here; valid: "
                           f"{', '.join(mi.variants())}")
        try:
            mi.set_variant(name)
        except Exception as error:
            raise CLIError(f"-m {name} cannot be used here: {one_line(error)}") from None
    return mi_brdfs.register()


def set_threads(count: int | None) -> None:
    if count is not None:
        dr.set_thread_count(count)


def set_verbosity(level: int) -> None:
    """0: warnings only; 1: Mitsuba's Info; 2: Debug (and Dr.Jit's Info); 3: Trace."""
    mi.set_log_level([mi.LogLevel.Warn, mi.LogLevel.Info, mi.LogLevel.Debug,
                      mi.LogLevel.Trace][min(level, 3)])
    if level >= 2:
        dr.set_log_level(dr.LogLevel.Info if level == 2 else dr.LogLevel.Debug)


def info_logger(prog: str, level: int) -> Callable[[str], None]:
    if level < 1:
        return lambda msg: None
    return lambda msg: print(f"{prog}: {msg}", file=sys.stderr)
