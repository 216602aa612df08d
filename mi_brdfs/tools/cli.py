"""The ``mi-brdfs`` command (also ``python -m mi_brdfs``), with the flags of
Mitsuba's own ``mitsuba`` command.

    mi-brdfs render SCENE [-D key=value ...] [-o OUT.exr|.png|.jpg ...] [--spp N]
                    [--passes P] [--seed S] [--tonemap NAME] [--exposure EV]
                    [-m VARIANT] [-t THREADS] [-q] [-v ...] [--traceback]
    mi-brdfs scenes
    mi-brdfs compare REFERENCE TEST [TEST ...] -o REPORT_DIR [--flip ldr|hdr] ...
                    (see mi_brdfs/tools/compare.py; exit 0 pass, 3 a threshold failed)
    mi-brdfs validate -o REPORT_DIR [--quick]   (exit 1 when a check fails)
    mi-brdfs bench -o OUT_DIR [--quick] [--only GROUP] [--merge REPORT]
    mi-brdfs fit TARGET [TARGET ...] -o REPORT_DIR [--models NAME ...] [--quick]
                 [--metric cosine|ngan] [-j N] [--scheduler ADDRESS]
                    (see mi_brdfs/tools/fit; exit 1 when a fit fails)
    mi-brdfs fit --scene SCENE -o REPORT_DIR [-D key=value ...] [--models NAME ...]
                 [--quick] [-j N]   (see mi_brdfs/tools/fit/scenefit.py)
    mi-brdfs explore [--port PORT] [--host HOST] [--no-browser]
                    (see mi_brdfs/tools/explore)
    mi-brdfs --version

The parsers and the dispatch only: each command is a module or package of
its own, usable from Python (``render``: :mod:`.render`; ``compare``:
:mod:`.compare`; ``validate``, ``bench``, ``fit``, ``explore``: the packages
of those names).

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
from typing import NoReturn

from .. import _interrupt as interrupt, scenes
from ..render import tonemap
from . import render
from .explore import add_parser as add_explore
from .arguments import integer, real, set_threads, set_verbosity
from .errors import CLIError, one_line

DESCRIPTION = ("The course lecture's BRDF models as Mitsuba 3 plugins: render scenes, compare "
               "renders, validate the plugins, benchmark them and fit them to materials. "
               "Each command's flags: mi-brdfs COMMAND --help.")
REPORT_MODULES = ("matplotlib", "scipy", "flip_evaluator")


# ----------------------------------------------------------------------------
#  render and scenes
# ----------------------------------------------------------------------------

def cmd_render(args: argparse.Namespace) -> int:
    done = render.render(args.scene, args.output, args.defines, spp=args.spp,
                         passes=args.passes, seed=args.seed, tonemap_name=args.tonemap,
                         exposure=args.exposure, variant=args.variant, threads=args.threads,
                         verbose=args.verbose, quiet=args.quiet, prog=args.prog)
    print(f"{args.scene}: {done.width}x{done.height}, {done.spp} spp in {done.seconds:.1f} s -> "
          f"{', '.join(done.outputs)}")
    return 0


def cmd_scenes(args: argparse.Namespace) -> int:
    for name in scenes.names():
        print(f"{name:15} {scenes.path(name)}")
    return 0


# ----------------------------------------------------------------------------
#  Reports
# ----------------------------------------------------------------------------

def cmd_compare(args: argparse.Namespace) -> int:
    from . import compare           # here: start-up of every other command (measured)

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
    from . import validate          # here: it needs the reports extra (SciPy)
    from .validate.page import plural

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
          f"{plural(s['known'], 'documented known limitation')}, {s['fail']} fail")
    return 1 if s["fail"] else 0


def cmd_bench(args: argparse.Namespace) -> int:
    from . import bench             # here: it needs the reports extra (SciPy)

    set_threads(args.threads)
    set_verbosity(args.verbose)
    log = (lambda *a: None) if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    only = [g.strip() for g in args.only.split(",")] if args.only else None
    results = bench.run(args.output, quick=args.quick, only=only, cache_dir=args.cache, log=log,
                        merge=args.merge)
    run = results["runs"][-1]["group_seconds"]
    kept = len(results["groups"]) - len(run)
    groups = lambda n: f"{n} group{'s' * (n != 1)}"
    print(f"bench: {groups(len(run))} "
          + (f"taken from {args.merge}" if args.merge else
             f"in {sum(t or 0 for t in run.values()):.0f} s")
          + (f", {groups(kept)} kept from the previous report" if kept else "")
          + f" -> {os.path.join(args.output, 'README.md')}"
          + (" (--quick: a smoke test; its numbers are not measurements)"
             if args.quick and not args.merge else ""))
    return 0


def cmd_fit(args: argparse.Namespace) -> int:
    from . import fit               # here: start-up of every other command (measured)
    from .fit import sweep

    set_verbosity(args.verbose)
    if args.scene is not None:
        return cmd_fit_scene(args)
    if not args.targets:
        raise CLIError("give a TARGET (an XML file holding a <bsdf>, or PLUGIN:key=value,...) "
                       "or --scene SCENE.xml")
    if args.defines:
        raise CLIError("-D is for --scene; a TARGET takes its values in PLUGIN:key=value,...")
    show = sweep.progress_printer(args.prog, enabled=not args.quiet, verbose=args.verbose > 0)
    try:
        records = fit.fit(args.targets, args.output, args.models, quick=args.quick,
                          metric_name=args.metric, scheduler=args.scheduler,
                          jobs=args.jobs,
                          show=show, command=" ".join(["mi-brdfs", *sys.argv[1:]]))
    finally:
        show.close()
    failed = [r for r in records if "error" in r]
    for r in failed:
        print(f"FAILED {r['target']} × {r['model']}: {r['error']}")
    print(f"report: {fit.report_path(args.output)}; {len(records) - len(failed)} fits, "
          f"{len(failed)} failed")
    return 1 if failed else 0


def cmd_fit_scene(args: argparse.Namespace) -> int:
    from .fit import scenefit, sweep

    if args.targets:
        raise CLIError(f"give TARGETs or --scene, not both (got {args.targets[0]} and "
                       f"--scene {args.scene})")
    path, bundled = render.resolve_scene(args.scene)
    defines = render.parse_defines(args.defines)
    if bundled:
        render.check_bundled_defines(args.scene, defines)
    show = sweep.progress_printer(args.prog, enabled=not args.quiet, verbose=args.verbose > 0)
    res, spp = (scenefit.QUICK_RES, scenefit.QUICK_SPP) if args.quick else \
        (scenefit.RES, scenefit.SPP)
    try:
        result = scenefit.fit_scene(path, args.output, defines, args.models, res=res, spp=spp,
                                    jobs=args.jobs, show=show,
                                    command=" ".join(["mi-brdfs", *sys.argv[1:]]),
                                    log=None if args.quiet else
                                    (lambda line: print(f"{args.prog}: {line}", file=sys.stderr)))
    finally:
        show.close()
    print(f"report: {os.path.join(args.output, 'index.html')}; {scenefit.summary(result)}")
    return 0


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


# the compare command's thresholds: the metric each bounds (mi_brdfs.tools.compare)
COMPARE_LIMITS = {
    "max_rmse": "root-mean-square difference, sqrt(mean((t - r)²)),",
    "max_relmse": "relative MSE, mean((t - r)² / (r + 0.01)²),",
    "max_mae": "mean absolute difference, mean(|t - r|),",
    "max_abs": "largest absolute difference of a pixel channel, max(|t - r|),",
    "max_flip": "mean FLIP error",
}
# bench's groups in their order (bench.groups.GROUPS, which needs the reports
# extra to import: the parser of every command must not)
BENCH_GROUPS = ("builtin", "models", "oren_nayar", "sampling", "integrators", "convergence",
                "scaling", "lobes", "energy", "ladder", "walk", "materials", "frozen", "kernels",
                "tracing", "explore", "trade", "fit")


def parser() -> Parser:
    v = render.versions()
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
    r.add_argument("--spp", type=integer(1, render.UINT32_MAX), default=None,
                   help="samples per pixel (default: the scene's)")
    r.add_argument("--passes", type=integer(1, 4096), default=8,
                   help="render in this many passes (default 8)")
    r.add_argument("--seed", type=integer(0, render.UINT32_MAX), default=0,
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
    for name, what in COMPARE_LIMITS.items():
        c.add_argument("--" + name.replace("_", "-"), dest=name, type=real(0, 1e30), default=None,
                       metavar="X", help=f"FAIL a test image whose {what} exceeds X")
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
                   help="report folder: new, empty, or a previous report (a previous bench "
                        "report keeps the groups this run does not bring)")
    b.add_argument("--quick", action="store_true",
                   help="a smoke test that every group runs: tiny scene, few repeats, no "
                        "findings (CI); its numbers are not measurements")
    b.add_argument("--only", default=None, metavar="GROUP[,GROUP...]",
                   help="run these groups only (default: all of them): "
                        + ", ".join(BENCH_GROUPS))
    b.add_argument("--merge", default=None, metavar="REPORT",
                   help="run nothing: take the groups (--only's, or all) of another bench "
                        "report folder, as they were measured, into the report -o")
    b.add_argument("--cache", default=None, help="reference cache (default ~/.cache/mi_brdfs)")
    b.set_defaults(run=cmd_bench)

    f = sub.add_parser("fit", parents=[common(threads=False)],
                       help="fit every course model to BSDFs: error, images, cost; HTML report")
    f.add_argument("targets", nargs="*", metavar="TARGET",
                   help="an XML file holding a <bsdf>, or PLUGIN:key=value,... "
                        "(e.g. roughconductor:material=Au,alpha=0.3)")
    f.add_argument("--scene", default=None, metavar="SCENE",
                   help="instead of TARGETs: a scene file (or a bundled scene's name); every "
                        "BSDF of it is replaced by the cheapest course model that looks the "
                        "same in its renders, or kept with the reason; the simplified scene "
                        "and its report are written to -o")
    f.add_argument("-D", dest="defines", action="append", default=[], metavar="key=value",
                   help="a parameter of the --scene file, as mitsuba -D (e.g. -D mode=hdr)")
    f.add_argument("-o", "--output", required=True,
                   help="report folder: new, empty, or a previous report")
    f.add_argument("--models", nargs="+", default=None, metavar="NAME",
                   help="models to fit: names (e.g. cook_torrance/ggx/smith, phong+ec) or plugin "
                        "names (default: every model)")
    f.add_argument("--quick", action="store_true", help="fewer directions, steps and pixels (CI)")
    f.add_argument("--metric", default="cosine", choices=("cosine", "ngan"),
                   help="the BRDF-space metric (default cosine; ngan: Ngan et al. 2005)")
    f.add_argument("-j", "--jobs", type=integer(1, 1024), default=None,
                   help="local worker processes for the fits (default: the cores, at most 2; "
                        "the render costs are timed afterwards, one at a time)")
    f.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on this Dask distributed scheduler (e.g. tcp://host:8786) "
                        "instead of local processes")
    f.set_defaults(run=cmd_fit)
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
