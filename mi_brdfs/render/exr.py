"""Linear float RGB images in and out of OpenEXR files (OpenEXR 3.x ``File`` API),
and atomic writes: a file appears at its target path complete or not at all."""
from __future__ import annotations

import contextlib
import os
import tempfile
from typing import Callable, Iterator

import numpy as np
import OpenEXR


@contextlib.contextmanager
def atomic_path(path: str) -> Iterator[str]:
    """Yield a temporary path beside ``path``; rename it over ``path`` on success,
    delete it on any error (or interruption)."""
    directory = os.path.dirname(os.path.abspath(path))
    suffix = os.path.splitext(path)[1]
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=suffix, dir=directory)
    os.close(fd)
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


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


def read_exr(path: str) -> np.ndarray:
    """Read an EXR's RGB channels as an (H, W, 3) float32 array."""
    if not os.path.exists(path):
        raise FileNotFoundError(f"no such file: {path}")
    try:
        with OpenEXR.File(path) as f:
            channels = f.channels()
            if "RGB" in channels:
                return np.asarray(channels["RGB"].pixels, dtype=np.float32)
            if all(c in channels for c in "RGB"):
                return np.stack([channels[c].pixels for c in "RGB"], axis=-1).astype(np.float32)
            if "RGBA" in channels:
                return np.asarray(channels["RGBA"].pixels[..., :3], dtype=np.float32)
            raise ValueError(f"{path}: no R, G, B channels (has {', '.join(channels)})")
    except (RuntimeError, OSError) as error:
        raise ValueError(f"{path}: not a readable EXR file ({error})") from None
