"""Render a scene to EXR, PNG or JPEG: ``mi-brdfs render``.

    mi-brdfs render SCENE [-D key=value ...] [-o OUT.exr|.png|.jpg ...] [--spp N]
                    [--passes P] [--seed S] [--tonemap NAME] [--exposure EV]
                    [-m VARIANT] [-t THREADS] [-q] [-v ...]

``SCENE`` is a scene file or the name of a bundled scene (``mi-brdfs scenes``
lists them), loaded with its ``-D`` defaults (as ``mitsuba -D``). The spp are
rendered in passes with different seeds (Mitsuba's JIT variants report no
progress of their own) and averaged, with a progress bar on a terminal and
plain lines in a pipe. Each output is written by its extension
(:mod:`mi_brdfs.render.imagefile`): ``.exr`` keeps every film channel and the
render's metadata, ``.png``/``.jpg`` are tone-mapped 8-bit sRGB. Without an
output the render is ``SCENE.exr`` beside the scene file, as ``mitsuba``
writes it (a bundled scene's: in the current folder).

Every number and path is checked before the render starts; a bad one raises
:class:`~mi_brdfs.tools.errors.CLIError` naming the flag.
"""
from __future__ import annotations

import os
import time
from importlib import metadata
from typing import NamedTuple, Sequence

import drjit as dr
import mitsuba as mi

from .. import scenes
from ..bsdfs.base import MODES
from ..render import imagefile, memory, tonemap
from ..render.passes import render_passes, split_passes
from . import destinations
from .arguments import info_logger, set_threads, set_variant, set_verbosity
from .errors import CLIError
from .progress import Progress

UINT32_MAX = 2**32 - 1
KNOWN_DEFINES = {"spp": 1, "res": 1}      # the bundled scenes' numeric defaults -> minimum


class Rendered(NamedTuple):
    """What :func:`render` wrote."""
    outputs: list[str]
    width: int
    height: int
    spp: int
    seconds: float


def parse_defines(pairs: Sequence[str]) -> dict[str, str]:
    defines = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise CLIError(f"-D expects key=value, got {pair!r}")
        if key in KNOWN_DEFINES:
            try:
                number = int(value)
            except ValueError:
                number = None
            if number is None or number < KNOWN_DEFINES[key]:
                raise CLIError(f"-D {key}={value} is invalid; valid: an integer >= "
                               f"{KNOWN_DEFINES[key]}")
        defines[key] = value
    return defines


def resolve_scene(arg: str) -> tuple[str, bool]:
    """(scene file, bundled?) for a path or a bundled scene's name."""
    if os.path.isdir(arg):
        raise CLIError(f"scene {arg} is a folder; give an XML file or a bundled scene's name")
    if os.path.exists(arg):
        return arg, False
    if os.sep not in arg:
        try:
            return scenes.path(arg), True
        except ValueError:
            pass
    raise CLIError(f"scene not found: {arg} (not a file; bundled scenes: "
                   f"{', '.join(scenes.names())})")


def default_output(scene: str, bundled: bool) -> str:
    """SCENE.exr beside the scene file (as ``mitsuba``); a bundled scene's in
    the current folder (never inside the installed package)."""
    stem = os.path.splitext(scene)[0]
    return os.path.basename(stem) + ".exr" if bundled else stem + ".exr"


def scene_spp(scene) -> int:
    return scene.sensors()[0].sampler().sample_count()


def film_channel_names(scene) -> list[str]:
    bitmap = scene.sensors()[0].film().bitmap()
    return [bitmap.struct_()[i].name for i in range(bitmap.channel_count())]


def versions() -> dict[str, str]:
    def version(dist: str) -> str:
        try:
            return metadata.version(dist)
        except metadata.PackageNotFoundError:
            return "unknown"
    return {"mi_brdfs": version("mi_brdfs"), "mitsuba": version("mitsuba"),
            "drjit": version("drjit")}


def check_render_numbers(scene, spp: int | None, passes: int, seed: int,
                         defines: dict[str, str]) -> int:
    """The spp to render; errors for a scene whose numbers cannot render."""
    spp = spp if spp is not None else scene_spp(scene)
    if spp < 1:
        where = f"-D spp={defines['spp']}" if "spp" in defines else "its sampler"
        raise CLIError(f"the scene's sample count is {spp} (from {where}); valid: an integer "
                       ">= 1 (or give --spp N)")
    width, height = scene.sensors()[0].film().crop_size()
    if width < 1 or height < 1:
        raise CLIError(f"the scene's film is {width}x{height} pixels; valid: at least 1x1")
    chunks = max(1, min(passes, spp))
    max_seed = (UINT32_MAX - (chunks - 1)) // chunks
    if seed > max_seed:
        raise CLIError(f"--seed {seed} is invalid with {chunks} passes; valid: an integer "
                       f"from 0 to {max_seed}")
    return spp


def check_bundled_defines(name: str, defines: dict[str, str]) -> None:
    """The bundled scenes use ``mode`` as the plugins' mode and as the
    integrator's type: any other value is one line naming the two."""
    mode = defines.get("mode")
    if mode is not None and mode not in MODES:
        raise CLIError(f"-D mode={mode} is invalid for the bundled scene {name}; valid: "
                       f"{', '.join(MODES)}")


def render(scene: str, outputs: list[str] | None = None, defines: Sequence[str] = (),
           spp: int | None = None, passes: int = 8, seed: int = 0, tonemap_name: str = "clamp",
           exposure: float = 0.0, variant: str | None = None, threads: int | None = None,
           verbose: int = 0, quiet: bool = False, prog: str = "mi-brdfs render") -> Rendered:
    """Render ``scene`` (a file or a bundled scene's name) with ``defines``
    ("key=value", as ``-D``) to each of ``outputs`` (default: SCENE.exr, see
    the module's docstring), ``spp`` in ``passes`` passes from ``seed``;
    ``.png``/``.jpg`` tone-mapped by ``tonemap_name`` at ``exposure`` stops.
    ``variant``, ``threads`` and ``verbose`` are Mitsuba's settings (as
    ``-m``, ``-t``, ``-v``); ``quiet``: no progress; ``prog`` names the
    progress and log lines."""
    scene_path, bundled = resolve_scene(scene)
    defines = parse_defines(defines)
    if bundled:
        check_bundled_defines(scene, defines)
    targets = outputs or [default_output(scene_path, bundled)]
    for path in targets:
        imagefile.check_extension(path)
        destinations.check_output_file(path)
    if tonemap_name not in tonemap.OPERATORS:
        raise CLIError(f"--tonemap {tonemap_name} is unknown; valid: "
                       f"{', '.join(tonemap.OPERATORS)}")

    variant = set_variant(variant)
    set_threads(threads)
    set_verbosity(verbose)

    # parallel=False: a scene loaded in parallel renders the same (tests/tools/
    # test_fit_speed.py) and loads the course scene in 0.2-0.3 s instead of 0.4 s,
    # but its render no longer ends on Ctrl-C (test_interrupt.py's render pass
    # ran past 60 s) and a profile of it sees no call of the plugins' sample.
    loaded = mi.load_file(scene_path, parallel=False, **defines)
    spp = check_render_numbers(loaded, spp, passes, seed, defines)

    log = info_logger(prog, verbose)
    chunks = split_passes(spp, passes)        # the passes that run (none empty)
    problem = memory.refusal(memory.need(loaded))
    if problem:
        raise CLIError(problem)
    width, height = loaded.sensors()[0].film().crop_size()
    log(f"{scene_path}: {width}x{height}, {spp} spp in {len(chunks)} passes, "
        f"seed {seed}, "
        f"variant {variant}, {dr.thread_count()} threads")
    progress = Progress(prog, enabled=not quiet)
    start = time.perf_counter()
    try:
        image = render_passes(loaded, spp, passes, seed, show=progress, log=log)
    finally:
        progress.close()
    seconds = time.perf_counter() - start
    try:
        names = imagefile.channel_names(film_channel_names(loaded), image.shape[2])
    except Exception:                       # a film without a bitmap: generic names
        names = imagefile.channel_names([], image.shape[2])
    info = {"scene": os.path.abspath(scene_path), "spp": sum(chunks), "seed": seed,
            "passes": len(chunks), "pass_spp": ",".join(map(str, chunks)), "variant": variant,
            "defines": " ".join(f"{k}={v}" for k, v in defines.items()),
            **versions()}
    for path in targets:
        imagefile.write(path, image, names, info, tonemap_name, exposure)
    return Rendered(targets, image.shape[1], image.shape[0], spp, seconds)
