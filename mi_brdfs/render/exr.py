"""Linear float images in and out of OpenEXR files (OpenEXR 3.x ``File`` API):
RGB, RGBA, mono (Y) and multi-layer files (AOVs, ``NAME.R``) read alike,
and atomic writes: a file appears at its target path complete or not at all,
with the mode the umask gives a new file (0644 under umask 022), as Mitsuba's
own files have: not the 0600 of a temporary file."""
from __future__ import annotations

import contextlib
import os
import tempfile
from typing import Callable, Iterator, Mapping

import numpy as np
import OpenEXR

from .. import _interrupt as interrupt


def umask() -> int:
    """The process's umask (read by setting it and setting it back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def file_mode() -> int:
    """The mode a new file gets under the current umask (0644 under 022)."""
    return 0o666 & ~umask()


def dir_mode() -> int:
    """The mode a new folder gets under the current umask (0755 under 022)."""
    return 0o777 & ~umask()


def new_file(directory: str, prefix: str, suffix: str = "") -> str:
    """Create an empty file of a new name in ``directory`` (mode 0600); its path."""
    fd, path = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=directory)
    os.close(fd)
    return path


@contextlib.contextmanager
def atomic_path(path: str) -> Iterator[str]:
    """Yield a temporary path beside ``path``; rename it over ``path`` on success,
    delete it on any error (or interruption)."""
    directory = os.path.dirname(os.path.abspath(path))
    suffix = os.path.splitext(path)[1]
    # removed unless moved into place, whatever ends the block (Ctrl-C included)
    with interrupt.temporary(lambda: new_file(directory, ".tmp-", suffix)) as tmp:
        yield tmp
        os.chmod(tmp, file_mode())          # mkstemp made it 0600
        os.replace(tmp, path)


def write_atomically(path: str, write: Callable[[str], None]) -> None:
    """Call ``write(tmp_path)`` and move the result to ``path`` atomically."""
    with atomic_path(path) as tmp:
        write(tmp)


def write_exr(path: str, rgb) -> None:
    """Write an (H, W, 3) linear RGB image as a float32 EXR, atomically."""
    rgb = np.ascontiguousarray(np.asarray(rgb, dtype=np.float32))
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise ValueError(f"write_exr: expected an (H, W, 3) RGB image, got shape {rgb.shape}")
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}

    def write(tmp: str) -> None:
        with OpenEXR.File(header, {"RGB": rgb}) as f:
            f.write(tmp)

    write_atomically(path, write)


def write_channels(path: str, channels: Mapping[str, np.ndarray],
                   metadata: Mapping[str, object] | None = None) -> None:
    """Write named (H, W) float channels as one float32 EXR, with ``metadata``
    as string attributes of its header, atomically. (Not through mi.Bitmap:
    Mitsuba 3.9's EXR writer deadlocks when Dr.Jit runs one thread, ``-t 1``.)"""
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    header.update({key: str(value) for key, value in (metadata or {}).items()})
    data = {name: np.ascontiguousarray(np.asarray(plane, dtype=np.float32))
            for name, plane in channels.items()}
    shapes = {plane.shape for plane in data.values()}
    if len(shapes) != 1 or len(next(iter(shapes))) != 2:
        raise ValueError(f"write_channels: expected (H, W) channels of one size, got {shapes}")

    def write(tmp: str) -> None:
        with OpenEXR.File(header, data) as f:
            f.write(tmp)

    write_atomically(path, write)


# The channels that make a layer's colour, in the order they are returned:
# R, G, B (a colour render), Y (a mono variant's luminance, repeated in the
# three channels), X, Y, Z (a vector AOV such as normals), or a single channel
# of any name (a depth AOV's T, repeated).
COLOUR_SETS = (("R", "G", "B"), ("X", "Y", "Z"), ("Y",))


def read_channels(path: str) -> dict[str, np.ndarray]:
    """Every channel of an EXR file as {name: (H, W) float32 array}."""
    if not os.path.exists(path):
        raise FileNotFoundError(f"no such file: {path}")
    try:
        with OpenEXR.File(path, separate_channels=True) as f:
            return {name: np.asarray(c.pixels, dtype=np.float32)
                    for name, c in f.channels().items()}
    except (RuntimeError, OSError) as error:
        raise ValueError(f"{path}: not a readable EXR file ({error})") from None


def layers(channels) -> dict[str, list[str]]:
    """{layer: its channels' short names} of an EXR's channel names: ``nn.X``
    is channel X of layer ``nn``, ``dd.y.T`` channel T of ``dd.y``, and
    ``R`` a channel of the unnamed base layer ``""``."""
    out: dict[str, list[str]] = {}
    for name in channels:
        layer, _, short = name.rpartition(".")
        out.setdefault(layer, []).append(short)
    return out


def layer_names(channels) -> str:
    """The layers of an EXR for an error message: ``(base), albedo, nn``."""
    return ", ".join(name or "(base)" for name in sorted(layers(channels)))


def read_exr(path: str, layer: str | None = None) -> np.ndarray:
    """An EXR's image as (H, W, 3) float32: the colour of ``layer`` (None or
    "": the base layer, the render itself), as :data:`COLOUR_SETS` says.
    Reads what ``mi-brdfs render`` writes in every variant (R, G, B; R, G,
    B, A; Y) and its AOV layers. ValueError names the layers there are."""
    channels = read_channels(path)
    name = layer or ""
    found = layers(channels)
    shown = f"layer {layer!r}" if layer else "the base layer"
    if name not in found:
        raise ValueError(f"{path}: no {shown}; its layers: {layer_names(channels)}")
    present = found[name]
    full = (lambda c: f"{name}.{c}") if name else (lambda c: c)
    for colour in COLOUR_SETS:
        if all(c in present for c in colour):
            planes = [channels[full(c)] for c in colour]
            break
    else:
        plain = [c for c in present if c != "A"]
        if len(plain) != 1:
            raise ValueError(f"{path}: {shown} has channels {', '.join(sorted(present))}, "
                             "none of R, G, B / X, Y, Z / Y / a single channel")
        planes = [channels[full(plain[0])]]
    if len(planes) == 1:
        planes = planes * 3
    return np.stack(planes, axis=-1).astype(np.float32)
