"""What a render needs in memory, and what the machine has: checked before a
render starts, so that a resolution too large for the machine is one line
instead of a crash (or the kernel's out-of-memory killer) minutes later.

Mitsuba's JIT variants trace a pass's samples in one kernel that streams them
into the film: memory grows with the pixels, not with the samples per pixel.
Measured on the bundled scenes (``lambert``, ``course`` in both modes; peak
RSS of ``mi-brdfs render`` at 256² to 4096², 1 to 16 spp, 1 to 4 passes):
109 to 128 bytes per pixel above the process's start-up size, for an RGB film.
Per channel that is the film's own storage (its channels, alpha and the filter
weight, float32), the image ``mi.render`` returns, and the passes' float64
accumulation: :data:`BYTES_PER_CHANNEL` for each film channel plus two.
``tests/render/test_memory.py`` holds the estimate against a measured render.

Dr.Jit also limits an array to 2^32 - 1 elements: the film's storage must
stay below that. (A pass of more samples than that Mitsuba splits itself.)
"""
from __future__ import annotations

import resource
from dataclasses import dataclass

BYTES_PER_CHANNEL = 26          # per pixel and film channel (+ 2: alpha, filter weight)
ELEMENTS_MAX = 2**32 - 1        # the largest Dr.Jit array


@dataclass(frozen=True)
class Need:
    """What one render asks of the machine."""
    width: int
    height: int
    channels: int                # the film's channels (RGB, Y, AOVs)

    @property
    def pixels(self) -> int:
        return self.width * self.height

    @property
    def bytes(self) -> int:
        return self.pixels * (self.channels + 2) * BYTES_PER_CHANNEL

    @property
    def film_elements(self) -> int:
        return self.pixels * (self.channels + 2)


def need(scene) -> Need:
    """The memory need of rendering ``scene``'s first sensor."""
    film = scene.sensors()[0].film()
    width, height = film.crop_size()
    channels = film.base_channels_count() + len(scene.integrator().aov_names())
    return Need(int(width), int(height), int(channels))


def _read_int(path: str) -> int | None:
    try:
        with open(path) as f:
            text = f.read().strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None


def _meminfo(key: str) -> int | None:
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def _cgroup_room() -> int | None:
    """What the process's cgroup (v2, else v1) still lets it allocate."""
    try:
        with open("/proc/self/cgroup") as f:
            lines = f.read().splitlines()
    except OSError:
        return None
    for line in lines:
        parts = line.split(":", 2)
        if len(parts) != 3:
            continue
        if parts[1] == "":                                  # v2: 0::/path
            base = "/sys/fs/cgroup" + parts[2]
            limit, used = _read_int(base + "/memory.max"), _read_int(base + "/memory.current")
        elif "memory" in parts[1].split(","):                # v1
            base = "/sys/fs/cgroup/memory" + parts[2]
            limit = _read_int(base + "/memory.limit_in_bytes")
            used = _read_int(base + "/memory.usage_in_bytes")
        else:
            continue
        if limit is not None and limit < 2**60:
            return max(0, limit - (used or 0))
    return None


def available() -> tuple[int, str]:
    """(bytes, where the limit comes from): the least of the memory the
    kernel reports as available, the cgroup's remaining limit and the
    process's data-size limit."""
    limits = []
    room = _meminfo("MemAvailable")
    if room is not None:
        limits.append((room, "available memory"))
    room = _cgroup_room()
    if room is not None:
        limits.append((room, "the cgroup's memory limit"))
    for name, what in ((resource.RLIMIT_DATA, "the data-size limit (ulimit -d)"),
                       (resource.RLIMIT_AS, "the address-space limit (ulimit -v)")):
        soft, _ = resource.getrlimit(name)
        if soft != resource.RLIM_INFINITY:
            limits.append((soft, what))
    return min(limits) if limits else (2**63, "no limit found")


def gib(n: float) -> str:
    return f"{n / 2**30:.1f} GiB" if n >= 2**30 else f"{n / 2**20:.0f} MiB"


def refusal(n: Need, room: tuple[int, str] | None = None) -> str | None:
    """Why this render cannot run here, on one line (None: it can): naming the
    estimate, the limit, and what to lower."""
    if n.film_elements > ELEMENTS_MAX:
        return (f"a {n.width}x{n.height} film with {n.channels} channels holds "
                f"{n.film_elements:.3g} values, more than Dr.Jit's largest array "
                f"({ELEMENTS_MAX:.3g}); lower -D res (or the film's size)")
    limit, what = room if room is not None else available()
    if n.bytes > limit:
        return (f"a {n.width}x{n.height} render needs about {gib(n.bytes)} of memory "
                f"({n.channels} film channels), more than {what} ({gib(limit)}); "
                "lower -D res (memory grows with the pixels, not with --spp or --passes)")
    return None
