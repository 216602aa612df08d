"""The ``mi-brdfs`` command (also ``python -m mi_brdfs``).

    mi-brdfs render SCENE.xml [-D key=value ...] [--spp N] [--passes P] [-o out.exr]
                    [--png out.png [--tonemap NAME] [--exposure EV]] [--seed S]
                    [--variant NAME] [--verbose]
    mi-brdfs compare REFERENCE.exr TEST.exr [...] -o REPORT_DIR [--max-rmse X ...]
                    (see mi_brdfs/tools/compare.py; exit 0 pass, 3 a threshold failed)

Registers the plugins, loads the scene with its ``-D`` defaults (as Mitsuba's
own ``mitsuba`` command does), renders the spp in passes with different seeds
(Mitsuba's JIT variants report no progress of their own) and averages them,
showing progress and an ETA after each pass; then writes the linear EXR and,
if asked, a tone-mapped 8-bit sRGB PNG. Outputs are written atomically.
Errors print one line (``mi-brdfs: error: ...``) and exit with status 1; with
``--verbose`` the traceback is shown.
"""
from __future__ import annotations

import argparse
import os
import re
import sys
import time

from ..render import exr, tonemap
from ..render.passes import render_passes


class CLIError(Exception):
    """An error reported as one line, without a traceback."""


def parse_defines(pairs: list[str]) -> dict[str, str]:
    defines = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise CLIError(f"-D expects key=value, got {pair!r}")
        defines[key] = value
    return defines


def check_writable(path: str) -> None:
    directory = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(directory):
        raise CLIError(f"cannot write {path}: directory {directory} does not exist")
    if not os.access(directory, os.W_OK):
        raise CLIError(f"cannot write {path}: directory {directory} is not writable")


def progress(done: int, total: int, elapsed: float, stream=sys.stderr) -> None:
    width = 30
    filled = int(width * done / total)
    eta = elapsed / done * (total - done) if done else float("nan")
    stream.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {done}/{total} spp, "
                 f"{elapsed:.1f} s, ETA {eta:.1f} s ")
    if done == total:
        stream.write("\n")
    stream.flush()


def scene_spp(scene) -> int:
    return scene.sensors()[0].sampler().sample_count()


def cmd_render(args) -> int:
    if not os.path.exists(args.scene):
        raise CLIError(f"scene not found: {args.scene}")
    defines = parse_defines(args.defines)
    out = args.output or os.path.splitext(os.path.basename(args.scene))[0] + ".exr"
    check_writable(out)
    if args.png:
        check_writable(args.png)
    if args.tonemap not in tonemap.OPERATORS:
        raise CLIError(f"unknown --tonemap {args.tonemap!r}; valid: {', '.join(tonemap.OPERATORS)}")

    import mi_brdfs
    import mitsuba as mi
    if args.variant:
        try:
            mi.set_variant(args.variant)
        except Exception as error:
            raise CLIError(f"variant {args.variant!r} is not available: {error}") from None
        mi_brdfs.register()

    # parallel=False: scene loading with Python plugins in worker threads failed
    # intermittently here (bad_alloc, basic_string::_M_create); serial loading is cheap.
    scene = mi.load_file(args.scene, parallel=False, **defines)
    spp = args.spp or scene_spp(scene)
    start = time.perf_counter()
    image = render_passes(scene, spp, args.passes, args.seed,
                          show=None if args.quiet else progress)
    rgb = image[..., :3]
    exr.write_exr(out, rgb)
    written = [out]
    if args.png:
        tonemap.write_png(args.png, rgb, args.tonemap, args.exposure)
        written.append(args.png)
    print(f"{args.scene}: {rgb.shape[1]}x{rgb.shape[0]}, {spp} spp in "
          f"{time.perf_counter() - start:.1f} s -> {', '.join(written)}")
    return 0


def cmd_compare(args) -> int:
    from . import compare

    thresholds = {k: getattr(args, k) for k in compare.THRESHOLDS}
    results = compare.compare(args.reference, args.tests, args.output, thresholds,
                              compare.parse_region(args.crop), args.tonemap)
    for c in results:
        m = c.metrics
        print(f"{c.test_path}: rmse {m['rmse']:.4g}, relmse {m['relmse']:.4g}, "
              f"flip {m['flip']:.4g}, psnr {m['psnr']:.4g} dB -> "
              + ("PASS" if c.passed else "FAIL: " + "; ".join(c.failures)))
    print(f"report: {os.path.join(args.output, 'index.html')}")
    return 0 if all(c.passed for c in results) else 3


def cmd_validate(args) -> int:
    from . import validate

    log = (lambda *a: None) if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    results = validate.validate(args.output, quick=args.quick, log=log)
    failed_chi2 = [r for r in results["sampling"] if not r["passed"]]
    over = [r for r in results["furnace"] if r["exceeds_1"]]
    print(f"report: {os.path.join(args.output, 'index.html')} ({results['seconds']:.0f} s); "
          f"{len(failed_chi2)} chi-square failures; {len(over)} furnace rows above 1")
    return 0


def cmd_bench(args) -> int:
    from . import bench

    log = (lambda *a: None) if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    only = [g.strip() for g in args.only.split(",")] if args.only else None
    results = bench.run(args.output, quick=args.quick, only=only, cache_dir=args.cache, log=log)
    print(f"bench: {len(results['groups'])} groups in {results['seconds']:.0f} s -> "
          f"{os.path.join(args.output, 'README.md')}")
    return 0


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="mi-brdfs", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render", help="render a scene to EXR (and PNG)")
    r.add_argument("scene")
    r.add_argument("-D", dest="defines", action="append", default=[], metavar="key=value",
                   help="set a scene <default> parameter")
    r.add_argument("--spp", type=int, default=None, help="samples per pixel (default: the scene's)")
    r.add_argument("--passes", type=int, default=8, help="render in this many passes (default 8)")
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("-o", "--output", default=None, help="EXR path (default: SCENE.exr here)")
    r.add_argument("--png", default=None, help="also write an 8-bit sRGB PNG here")
    r.add_argument("--tonemap", default="clamp", help="PNG tone mapping: " + ", ".join(tonemap.OPERATORS))
    r.add_argument("--exposure", type=float, default=0.0, help="PNG exposure in stops (EV)")
    r.add_argument("--variant", default=None, help="Mitsuba variant (default llvm_ad_rgb)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    r.add_argument("-v", "--verbose", action="store_true", help="show tracebacks on errors")
    r.set_defaults(run=cmd_render)

    c = sub.add_parser("compare", help="compare EXR renders against a reference; HTML report")
    c.add_argument("reference")
    c.add_argument("tests", nargs="+")
    c.add_argument("-o", "--output", required=True, help="report directory")
    for name in ("max_rmse", "max_relmse", "max_mae", "max_abs", "max_flip", "min_psnr"):
        c.add_argument("--" + name.replace("_", "-"), dest=name, type=float, default=None)
    c.add_argument("--crop", default=None, metavar="X,Y,W,H", help="compare this region only")
    c.add_argument("--tonemap", default="clamp", help="display tone mapping of the pictures")
    c.add_argument("-v", "--verbose", action="store_true", help="show tracebacks on errors")
    c.set_defaults(run=cmd_compare)

    v = sub.add_parser("validate", help="run the project's validation; HTML report")
    v.add_argument("-o", "--output", required=True, help="report directory")
    v.add_argument("--quick", action="store_true", help="reduced grid and sizes (CI)")
    v.add_argument("-q", "--quiet", action="store_true")
    v.add_argument("-v", "--verbose", action="store_true", help="show tracebacks on errors")
    v.set_defaults(run=cmd_validate)

    b = sub.add_parser("bench", help="measure the speed/accuracy trade-offs")
    b.add_argument("-o", "--output", required=True, help="results directory")
    b.add_argument("--quick", action="store_true", help="tiny scene, few repeats (CI)")
    b.add_argument("--only", default=None, help="comma-separated groups (default: all)")
    b.add_argument("--cache", default=None, help="reference cache (default ~/.cache/mi_brdfs)")
    b.add_argument("-q", "--quiet", action="store_true")
    b.add_argument("-v", "--verbose", action="store_true", help="show tracebacks on errors")
    b.set_defaults(run=cmd_bench)
    return p


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    try:
        return args.run(args)
    except KeyboardInterrupt:
        print("mi-brdfs: interrupted", file=sys.stderr)
        return 130
    except Exception as error:       # one clear line, unless --verbose
        if args.verbose:
            raise
        print(f"mi-brdfs: error: {one_line(error)}", file=sys.stderr)
        return 1


def one_line(error: BaseException) -> str:
    """The gist of an error on one line. Mitsuba wraps a Python plugin's
    exception with its traceback: keep only the exception's own last line."""
    text = str(error).strip()
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    if not lines:
        return type(error).__name__
    if "Traceback (most recent call last)" in text:
        where = re.search(r"At (.+?\(line \d+, col \d+\))", lines[0])
        return (f"{where.group(1)}: " if where else "") + lines[-1]
    return " ".join(lines)


if __name__ == "__main__":
    sys.exit(main())
