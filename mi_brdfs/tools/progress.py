"""Progress of a render in passes (or of tasks: ``unit``): a tqdm bar on a
terminal, plain lines in a pipe or a log file (never a carriage return
there), nothing with ``--quiet``.

The ETA comes from the passes after the first one: the first pass also
compiles the kernels (seconds, for a pass that then takes milliseconds), so
counting it would make every early estimate far too long. After the first
pass alone there is no estimate yet.
"""
from __future__ import annotations

import sys
from typing import TextIO

from tqdm import tqdm


def eta(history: list[tuple[int, float]], total: int) -> float | None:
    """Seconds left, from ``history`` = [(done_spp, elapsed_s) after each pass]:
    the rate of the passes after the first; None before the second pass."""
    if len(history) < 2:
        return None
    (first_spp, first_s), (done, elapsed) = history[0], history[-1]
    spp, seconds = done - first_spp, elapsed - first_s
    if spp <= 0:
        return None
    return max(seconds, 0.0) / spp * (total - done)


def _seconds(s: float | None) -> str:
    if s is None:
        return "?"
    return f"{s:.1f} s" if s < 60 else f"{int(s // 60)} min {s % 60:02.0f} s"


class Progress:
    """``show(done_spp, total_spp, elapsed_s)`` callback for ``render_passes``:
    at the start (done 0), then after each pass."""

    def __init__(self, label: str, stream: TextIO | None = None, enabled: bool = True,
                 unit: str = "spp"):
        self.label, self.enabled, self.unit = label, enabled, unit
        self.stream = stream if stream is not None else sys.stderr
        self.history: list[tuple[int, float]] = []
        self.bar = None
        self.terminal = enabled and hasattr(self.stream, "isatty") and self.stream.isatty()

    def __call__(self, done: int, total: int, elapsed: float) -> None:
        if not self.enabled:
            return
        if done == 0:                       # the start: the first pass also compiles
            if self.terminal:
                self._bar(0, total, None)
            else:
                self.stream.write(f"{self.label}: 0/{total} {self.unit}, first pass "
                                  "(it also traces and compiles the kernels)\n")
                self.stream.flush()
            return
        self.history.append((done, elapsed))
        left = eta(self.history, total)
        if self.terminal:
            self._bar(done, total, left)
        else:
            self.stream.write(f"{self.label}: {done}/{total} {self.unit}, {_seconds(elapsed)}, "
                              f"ETA {_seconds(left)}\n")
            self.stream.flush()

    def _bar(self, done: int, total: int, left: float | None) -> None:
        if self.bar is None:
            self.bar = tqdm(total=total, desc=self.label, unit=self.unit, file=self.stream,
                            dynamic_ncols=True, leave=True,
                            bar_format="{desc}: {percentage:3.0f}%|{bar}| {n}/{total} "
                                       + self.unit + " [{elapsed}, {postfix}]")
        self.bar.set_postfix_str(f"ETA {_seconds(left)}", refresh=False)
        self.bar.update(done - self.bar.n)
        if done >= total:
            self.close()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None
