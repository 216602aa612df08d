"""The ``mi-brdfs`` command (also ``python -m mi_brdfs``), with the flags of
Mitsuba's own ``mitsuba`` command.

    mi-brdfs render SCENE [-D key=value ...] [-o OUT.exr|.png|.jpg ...] [--spp N]
                    [--passes P] [--seed S] [--tonemap NAME] [--exposure EV]
                    [-m VARIANT] [-t THREADS] [-q] [-v ...] [--traceback]
    mi-brdfs scenes
    mi-brdfs compare REFERENCE TEST [TEST ...] -o REPORT_DIR [--flip ldr|hdr] ...
                    (see mi_brdfs/tools/compare.py; exit 0 pass, 3 a threshold failed)
    mi-brdfs validate -o REPORT_DIR [--quick]   (exit 1 when a check fails)
    mi-brdfs bench -o OUT_DIR [--quick] [--only GROUP]
    mi-brdfs fit TARGET [TARGET ...] -o REPORT_DIR [--models NAME ...] [--quick]
                 [--metric cosine|ngan] [-j N] [--scheduler ADDRESS]
                    (see mi_brdfs/tools/fit; exit 1 when a fit fails)
    mi-brdfs --version

``render`` takes a scene file or the name of a bundled scene (``mi-brdfs
scenes`` lists them), loads it with its ``-D`` defaults (as ``mitsuba -D``),
renders the spp in passes with different seeds (Mitsuba's JIT variants report
no progress of their own) and averages them, with a progress bar on a
terminal and plain lines in a pipe. Each ``-o`` is written by its extension
(:mod:`mi_brdfs.render.imagefile`): ``.exr`` keeps every film channel and the
render's metadata, ``.png``/``.jpg`` are tone-mapped 8-bit sRGB. Without
``-o`` the output is ``SCENE.exr`` beside the scene file, as ``mitsuba``
writes it (a bundled scene's: in the current folder).

``-m/--variant`` picks the Mitsuba variant, ``-t/--threads`` Dr.Jit's thread
count, ``-v`` (repeatable) raises Mitsuba's log level (Info, Debug, Trace).

Every number and path is checked before work starts. Errors print one line,
``mi-brdfs COMMAND: error: ...``, and exit with status 1 (never a signal);
``--traceback`` shows the traceback instead.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from importlib import metadata
from typing import NoReturn

from .. import _interrupt as interrupt
from ..render import imagefile, tonemap
from . import destinations
from .arguments import info_logger, integer, real, set_threads, set_variant, set_verbosity
from .errors import CLIError, one_line
from .progress import Progress

DESCRIPTION = ("The course lecture's BRDF models as Mitsuba 3 plugins: render scenes, compare "
               "renders, validate the plugins, benchmark them and fit them to materials. "
               "Each command's flags: mi-brdfs COMMAND --help.")
UINT32_MAX = 2**32 - 1
REPORT_MODULES = ("matplotlib", "scipy", "flip_evaluator")
KNOWN_DEFINES = {"spp": 1, "res": 1}      # the bundled scenes' numeric defaults -> minimum





def parse_defines(pairs: list[str]) -> dict[str, str]:
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



# ----------------------------------------------------------------------------
#  render and scenes
# ----------------------------------------------------------------------------

def resolve_scene(arg: str) -> tuple[str, bool]:
    """(scene file, bundled?) for a path or a bundled scene's name."""
    from .. import scenes

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


def check_render_numbers(scene, args: argparse.Namespace, defines: dict[str, str]) -> int:
    """The spp to render; errors for a scene whose numbers cannot render."""
    spp = args.spp if args.spp is not None else scene_spp(scene)
    if spp < 1:
        where = f"-D spp={defines['spp']}" if "spp" in defines else "its sampler"
        raise CLIError(f"the scene's sample count is {spp} (from {where}); valid: an integer "
                       ">= 1 (or give --spp N)")
    width, height = scene.sensors()[0].film().crop_size()
    if width < 1 or height < 1:
        raise CLIError(f"the scene's film is {width}x{height} pixels; valid: at least 1x1")
    chunks = max(1, min(args.passes, spp))
    max_seed = (UINT32_MAX - (chunks - 1)) // chunks
    if args.seed > max_seed:
        raise CLIError(f"--seed {args.seed} is invalid with {chunks} passes; valid: an integer "
                       f"from 0 to {max_seed}")
    return spp


def check_bundled_defines(name: str, defines: dict[str, str]) -> None:
    """The bundled scenes use ``mode`` as the plugins' mode and as the
    integrator's type: any other value is one line naming the two."""
    from ..bsdfs.base import MODES
    mode = defines.get("mode")
    if mode is not None and mode not in MODES:
        raise CLIError(f"-D mode={mode} is invalid for the bundled scene {name}; valid: "
                       f"{', '.join(MODES)}")


def cmd_render(args: argparse.Namespace) -> int:
    scene_path, bundled = resolve_scene(args.scene)
    defines = parse_defines(args.defines)
    if bundled:
        check_bundled_defines(args.scene, defines)
    targets = args.output or [default_output(scene_path, bundled)]
    for path in targets:
        imagefile.check_extension(path)
        destinations.check_output_file(path)
    if args.tonemap not in tonemap.OPERATORS:
        raise CLIError(f"--tonemap {args.tonemap} is unknown; valid: {', '.join(tonemap.OPERATORS)}")

    variant = set_variant(args.variant)
    set_threads(args.threads)
    set_verbosity(args.verbose)
    import drjit as dr
    import mitsuba as mi

    from ..render import memory
    from ..render.passes import render_passes, split_passes

    # parallel=False: serial loading is cheap. (Parallel loading failed now and then
    # while the plugins' constructors called the loader: see _binding.create.)
    scene = mi.load_file(scene_path, parallel=False, **defines)
    spp = check_render_numbers(scene, args, defines)

    log = info_logger(args.prog, args.verbose)
    chunks = split_passes(spp, args.passes)        # the passes that run (none empty)
    problem = memory.refusal(memory.need(scene))
    if problem:
        raise CLIError(problem)
    width, height = scene.sensors()[0].film().crop_size()
    log(f"{scene_path}: {width}x{height}, {spp} spp in {len(chunks)} passes, "
        f"seed {args.seed}, "
        f"variant {variant}, {dr.thread_count()} threads")
    progress = Progress(args.prog, enabled=not args.quiet)
    start = time.perf_counter()
    try:
        image = render_passes(scene, spp, args.passes, args.seed, show=progress, log=log)
    finally:
        progress.close()
    seconds = time.perf_counter() - start
    try:
        names = imagefile.channel_names(film_channel_names(scene), image.shape[2])
    except Exception:                       # a film without a bitmap: generic names
        names = imagefile.channel_names([], image.shape[2])
    info = {"scene": os.path.abspath(scene_path), "spp": sum(chunks), "seed": args.seed,
            "passes": len(chunks), "pass_spp": ",".join(map(str, chunks)), "variant": variant,
            "defines": " ".join(f"{k}={v}" for k, v in defines.items()),
            **versions()}
    for path in targets:
        imagefile.write(path, image, names, info, args.tonemap, args.exposure)
    print(f"{args.scene}: {image.shape[1]}x{image.shape[0]}, {spp} spp in {seconds:.1f} s -> "
          f"{', '.join(targets)}")
    return 0


def cmd_scenes(args: argparse.Namespace) -> int:
    from .. import scenes
    for name in scenes.names():
        print(f"{name:15} {scenes.path(name)}")
    return 0


# ----------------------------------------------------------------------------
#  Reports
# ----------------------------------------------------------------------------

def cmd_compare(args: argparse.Namespace) -> int:
    from . import compare

    thresholds = {k: getattr(args, k) for k in compare.THRESHOLDS}
    results = compare.compare(args.reference, args.tests, args.output, thresholds,
                              compare.parse_region(args.crop), args.tonemap,
                              flip_mode=args.flip, mask_nonfinite=args.mask_nonfinite,
                              layer=args.layer)
    for c in results:
        m = c.metrics
        print(f"{c.test_path}: rmse {m['rmse']:.4g}, relmse {m['relmse']:.4g}, "
              f"flip ({m['flip_mode']}) {m['flip']:.4g}, psnr {m['psnr']:.4g} dB -> "
              + c.verdict + (": " + "; ".join(c.failures) if c.failures else ""))
    print(f"report: {os.path.join(args.output, 'index.html')}")
    return 3 if any(c.verdict == "FAIL" for c in results) else 0


def cmd_validate(args: argparse.Namespace) -> int:
    from . import validate

    set_threads(args.threads)
    set_verbosity(args.verbose)
    log = (lambda *a: None) if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    results = validate.validate(args.output, quick=args.quick, log=log)
    s = results["summary"]
    for check in results["checks"]:
        if check["status"] == "fail":
            print(f"FAIL {check['id']}: {check['measured']}")
    print(f"report: {os.path.join(args.output, 'index.html')} ({results['seconds']:.0f} s); "
          f"{s['pass']} checks pass, {s['documented']} documented behaviour, "
          f"{s['known']} documented known limitations, {s['fail']} fail")
    return 1 if s["fail"] else 0


def cmd_bench(args: argparse.Namespace) -> int:
    from . import bench

    set_threads(args.threads)
    set_verbosity(args.verbose)
    log = (lambda *a: None) if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    only = [g.strip() for g in args.only.split(",")] if args.only else None
    results = bench.run(args.output, quick=args.quick, only=only, cache_dir=args.cache, log=log)
    print(f"bench: {len(results['groups'])} groups in {results['seconds']:.0f} s -> "
          f"{os.path.join(args.output, 'README.md')}"
          + (" (--quick: a smoke test; its numbers are not measurements)" if args.quick else ""))
    return 0


def cmd_fit(args: argparse.Namespace) -> int:
    from . import fit
    from .fit import sweep

    set_verbosity(args.verbose)
    show = sweep.progress_printer(args.prog, enabled=not args.quiet, verbose=args.verbose > 0)
    try:
        records = fit.fit(args.targets, args.output, args.models, quick=args.quick,
                          metric_name=args.metric, jobs=args.jobs, scheduler=args.scheduler,
                          show=show, command=" ".join(["mi-brdfs", *sys.argv[1:]]))
    finally:
        show.close()
    failed = [r for r in records if "error" in r]
    for r in failed:
        print(f"FAILED {r['target']} × {r['model']}: {r['error']}")
    print(f"report: {fit.report_path(args.output)}; {len(records) - len(failed)} fits, "
          f"{len(failed)} failed")
    return 1 if failed else 0


# ----------------------------------------------------------------------------
#  The parser
# ----------------------------------------------------------------------------

class Parser(argparse.ArgumentParser):
    """argparse with the project's error convention: one line, exit status 1."""

    def error(self, message: str) -> NoReturn:
        self.exit(1, f"{self.prog}: error: {message}\n")


def common(threads: bool = True, variant: bool = False) -> Parser:
    p = Parser(add_help=False)
    if variant:
        p.add_argument("-m", "--variant", default=None,
                       help="Mitsuba variant (default llvm_ad_rgb), as mitsuba -m")
    if threads:
        p.add_argument("-t", "--threads", type=integer(1, 1024), default=None,
                       help="Dr.Jit's thread count (default: one per core)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress output")
    p.add_argument("-v", "--verbose", action="count", default=0,
                   help="more log output; repeat for more (Mitsuba's Info, Debug, Trace)")
    p.add_argument("--traceback", action="store_true", help="show the traceback of an error")
    return p


def parser() -> Parser:
    v = versions()
    p = Parser(prog="mi-brdfs", description=DESCRIPTION)
    p.add_argument("--version", action="version",
                   version=f"mi-brdfs {v['mi_brdfs']} (Mitsuba {v['mitsuba']}, "
                           f"Dr.Jit {v['drjit']})")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("render", parents=[common(variant=True)],
                       help="render a scene to EXR, PNG or JPEG")
    r.add_argument("scene", help="a scene file, or a bundled scene's name (mi-brdfs scenes)")
    r.add_argument("-D", dest="defines", action="append", default=[], metavar="key=value",
                   help="set a scene <default> parameter, as mitsuba -D")
    r.add_argument("-o", "--output", action="append", default=None, metavar="FILE",
                   help="output file, by extension: .exr (every channel, metadata), .png or "
                        ".jpg (tone-mapped 8-bit sRGB); repeatable "
                        "(default: SCENE.exr beside the scene file)")
    r.add_argument("--spp", type=integer(1, UINT32_MAX), default=None,
                   help="samples per pixel (default: the scene's)")
    r.add_argument("--passes", type=integer(1, 4096), default=8,
                   help="render in this many passes (default 8)")
    r.add_argument("--seed", type=integer(0, UINT32_MAX), default=0,
                   help="seed of the first pass; pass k uses seed + k (default 0)")
    r.add_argument("--tonemap", default="clamp", choices=list(tonemap.OPERATORS),
                   help="tone mapping of .png/.jpg outputs (default clamp)")
    r.add_argument("--exposure", type=real(-100, 100), default=0.0,
                   help="exposure of .png/.jpg outputs in stops (EV)")
    r.set_defaults(run=cmd_render)

    s = sub.add_parser("scenes", help="list the bundled scenes")
    s.set_defaults(run=cmd_scenes, traceback=False)

    c = sub.add_parser("compare", parents=[common(threads=False)],
                       help="compare renders (EXR, PNG, JPEG) against a reference; HTML report")
    c.add_argument("reference", help="the reference image (.exr, .png, .jpg)")
    c.add_argument("tests", nargs="+", help="the images to compare with it")
    c.add_argument("-o", "--output", required=True,
                   help="report folder: new, empty, or a previous report")
    for name in ("max_rmse", "max_relmse", "max_mae", "max_abs", "max_flip"):
        c.add_argument("--" + name.replace("_", "-"), dest=name, type=real(0, 1e30), default=None,
                       metavar="X", help=f"FAIL a test image whose {name[4:]} exceeds X")
    c.add_argument("--min-psnr", dest="min_psnr", type=real(-1e3, 1e3), default=None,
                   metavar="DB", help="FAIL a test image whose PSNR is below DB")
    c.add_argument("--flip", choices=("ldr", "hdr"), default=None,
                   help="FLIP mode (default: hdr if an input is EXR, ldr for PNG/JPEG inputs)")
    c.add_argument("--mask-nonfinite", action="store_true",
                   help="leave out pixels that are NaN or Inf in an input (default: refuse them)")
    c.add_argument("--crop", default=None, metavar="X,Y,W,H", help="compare this region only")
    c.add_argument("--tonemap", default="clamp", choices=list(tonemap.OPERATORS),
                   help="display tone mapping of the pictures")
    c.add_argument("--layer", default=None, metavar="NAME",
                   help="compare this layer of the EXR inputs (an AOV such as albedo or nn; "
                        "default: the render's R, G, B, or Y in mono variants)")
    c.set_defaults(run=cmd_compare)

    v = sub.add_parser("validate", parents=[common()], help="run the project's validation; HTML report")
    v.add_argument("-o", "--output", required=True,
                   help="report folder: new, empty, or a previous report")
    v.add_argument("--quick", action="store_true", help="reduced grid and sizes (CI)")
    v.set_defaults(run=cmd_validate)

    b = sub.add_parser("bench", parents=[common()], help="measure the speed/accuracy trade-offs")
    b.add_argument("-o", "--output", required=True,
                   help="report folder: new, empty, or a previous report")
    b.add_argument("--quick", action="store_true",
                   help="a smoke test that every group runs: tiny scene, few repeats, no "
                        "findings (CI); its numbers are not measurements")
    b.add_argument("--only", default=None, help="comma-separated groups (default: all)")
    b.add_argument("--cache", default=None, help="reference cache (default ~/.cache/mi_brdfs)")
    b.set_defaults(run=cmd_bench)

    f = sub.add_parser("fit", parents=[common(threads=False)],
                       help="fit every course model to BSDFs: error, images, cost; HTML report")
    f.add_argument("targets", nargs="+", metavar="TARGET",
                   help="an XML file holding a <bsdf>, or PLUGIN:key=value,... "
                        "(e.g. roughconductor:material=Au,alpha=0.3)")
    f.add_argument("-o", "--output", required=True,
                   help="report folder: new, empty, or a previous report")
    f.add_argument("--models", nargs="+", default=None, metavar="NAME",
                   help="models to fit: names (e.g. cook_torrance/ggx/smith, phong+ec) or plugin "
                        "names (default: every model)")
    f.add_argument("--quick", action="store_true", help="fewer directions, steps and pixels (CI)")
    f.add_argument("--metric", default="cosine", choices=("cosine", "ngan"),
                   help="the BRDF-space metric (default cosine; ngan: Ngan et al. 2005)")
    f.add_argument("-j", "--jobs", type=integer(1, 1024), default=1,
                   help="local worker processes (default 1: the steadiest cost ratios)")
    f.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on this Dask distributed scheduler (e.g. tcp://host:8786) "
                        "instead of local processes")
    f.set_defaults(run=cmd_fit)
    from .explore import add_parser as add_explore      # mi-brdfs explore (tools/explore)
    add_explore(sub, common)
    for name, command in sub.choices.items():
        command.set_defaults(prog=command.prog)
    return p


def main(argv: list[str] | None = None) -> int:
    prog, args = "mi-brdfs", None
    try:
        args = parser().parse_args(argv)
        prog = args.prog
        with interrupt.watching(prog):          # Ctrl-C within a second, even in a kernel
            return args.run(args)
    except KeyboardInterrupt:                   # (before the watching began: at parsing)
        interrupt.end(prog)                     # "PROG: interrupted", once; status 130
    except Exception as error:       # one clear line, unless --traceback
        if args is None or args.traceback:
            raise
        print(f"{prog}: error: {describe(error, args.command)}", file=sys.stderr)
        return 1


def describe(error: BaseException, command: str) -> str:
    if isinstance(error, ModuleNotFoundError) and error.name in REPORT_MODULES:
        return (f"{error.name} is not installed; {command} needs the report dependencies: "
                "pip install 'mi_brdfs[reports]'")
    return one_line(error)




if __name__ == "__main__":
    sys.exit(main())
