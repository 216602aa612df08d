"""The ``mi-brdfs`` command (also ``python -m mi_brdfs``).

    mi-brdfs render SCENE.xml [-D key=value ...] [--spp N] [-o out.exr]
                    [--png out.png] [--variant NAME] [--verbose]

Registers the plugins, loads the scene with its ``-D`` defaults, renders, and
writes a linear EXR and, if asked, an 8-bit sRGB PNG (clamped to [0, 1], the
scan-line behaviour). Both files are written atomically: a temporary file
beside the target, renamed over it only once complete.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time


def parse_defines(pairs: list[str]) -> dict[str, str]:
    defines = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise ValueError(f"-D expects key=value, got {pair!r}")
        defines[key] = value
    return defines


def write_atomically(bitmap, path: str) -> None:
    """Write a mi.Bitmap to path via a temporary file renamed over it."""
    directory = os.path.dirname(os.path.abspath(path))
    suffix = os.path.splitext(path)[1]
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=suffix, dir=directory)
    os.close(fd)
    try:
        bitmap.write(tmp)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def render(scene_path: str, defines: dict[str, str] | None = None, spp: int | None = None,
           exr: str | None = None, png: str | None = None, seed: int = 0):
    """Load and render a scene; write EXR/PNG if paths are given; return the mi.Bitmap."""
    import mitsuba as mi

    scene = mi.load_file(scene_path, **(defines or {}))
    image = mi.render(scene, spp=spp or 0, seed=seed)
    bitmap = mi.Bitmap(image)
    if exr:
        write_atomically(bitmap, exr)
    if png:
        ldr = bitmap.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True)
        write_atomically(ldr, png)
    return bitmap


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="mi-brdfs", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render", help="render a scene to EXR (and PNG)")
    r.add_argument("scene")
    r.add_argument("-D", dest="defines", action="append", default=[], metavar="key=value")
    r.add_argument("--spp", type=int, default=None, help="samples per pixel (default: the scene's)")
    r.add_argument("-o", "--output", default=None, help="EXR path (default: SCENE.exr)")
    r.add_argument("--png", default=None, help="also write an 8-bit sRGB PNG here")
    r.add_argument("--variant", default=None, help="Mitsuba variant (default llvm_ad_rgb)")
    r.add_argument("--verbose", action="store_true", help="show tracebacks")
    args = parser.parse_args(argv)

    try:
        if not os.path.exists(args.scene):
            raise FileNotFoundError(f"scene not found: {args.scene}")
        defines = parse_defines(args.defines)
        import mi_brdfs
        import mitsuba as mi
        if args.variant:
            mi.set_variant(args.variant)
            mi_brdfs.register()
        exr = args.output or os.path.splitext(os.path.basename(args.scene))[0] + ".exr"
        start = time.perf_counter()
        bitmap = render(args.scene, defines, args.spp, exr, args.png)
        elapsed = time.perf_counter() - start
        print(f"{args.scene}: {bitmap.width()}x{bitmap.height()} in {elapsed:.1f} s -> {exr}"
              + (f", {args.png}" if args.png else ""))
        return 0
    except Exception as error:       # one clear line, unless --verbose
        if args.verbose:
            raise
        message = str(error).strip().splitlines()[-1] if str(error).strip() else repr(error)
        print(f"mi-brdfs: error: {message}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
