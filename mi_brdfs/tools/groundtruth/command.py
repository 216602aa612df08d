"""``python -m mi_brdfs.tools.groundtruth``: the walk's reference albedos and
what the compensated plugins differ from it by."""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

from ..destinations import OutputError, check_output_file
from .microsurface import DISTRIBUTIONS, Alpha
from .pairs import DIRECTIONAL_PATHS, directional_reference, print_directional_residuals
from .report import (compensated_albedo, fresnel_reference, grazing_difference, reference,
                     reference_agreement, residuals_fresnel,
                     reference_anisotropic, residuals, residuals_anisotropic, slice_difference)
from .walk import albedo

PROG = "python -m mi_brdfs.tools.groundtruth"
ANISOTROPIC = ((0.05, 0.3), (0.3, 0.05), (0.1, 1.0))      # (α_x, α_y) printed by --anisotropic


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog=PROG, description=main.__doc__)
    parser.add_argument("-o", "--output", help="write the reference albedos (JSON) here")
    parser.add_argument("--roughness", choices=("isotropic", "anisotropic"), default="isotropic",
                        help="which reference albedos -o writes: over (theta, alpha, F0), or "
                             "over (theta, phi, alpha_u, alpha_v, F0) (default isotropic)")
    parser.add_argument("--fresnel-forms", action="store_true",
                        help="-o writes instead the walk's albedos with cook_torrance's other "
                             "Fresnel forms at every bounce (Au, Cu, Al, F82, a dielectric, "
                             "white) over (theta, alpha, channel)")
    parser.add_argument("--directional", action="store_true",
                        help="-o writes instead the walk's BRDF at pairs of directions "
                             "(closed-form first bounce, bounces k >= 2 and their standard "
                             "error) and the hemisphere's L1 of cook_torrance's directional "
                             "and separable lobes against the walk (the reference of "
                             "tests/bsdfs/test_directional.py)")
    parser.add_argument("--reference", help="read them from here (instead of walking); "
                                            "either kind")
    parser.add_argument("--paths", type=int, default=None,
                        help="paths per point (default 100,000; 400,000 for --directional)")
    parser.add_argument("--residuals", action="store_true",
                        help="print the compensated models' residuals against the walk")
    parser.add_argument("--agreement", action="store_true",
                        help="walk the reference points again (another seed) and print how "
                             "far the --reference values are, in standard errors")
    parser.add_argument("--slices", action="store_true",
                        help="print how far BRDF slices are from the walk's (relative L1)")
    parser.add_argument("--decomposition", action="store_true",
                        help="print what single scattering misses: the separable E_ss, the "
                             "height-correlated first bounce E_1 and the bounces k >= 2")
    parser.add_argument("--grazing", action="store_true",
                        help="print what the separable compensation lobe adds at grazing pairs "
                             "(retro-reflection, side-on, mirror) against the walk's multiple "
                             "scattering there (Beckmann x Smith, alpha 0.3, F0 1 and 0.7)")
    parser.add_argument("--anisotropic", action="store_true",
                        help="print the walk's albedo for anisotropic roughness "
                             f"(alpha_x, alpha_y) in {list(ANISOTROPIC)}, F0 1 and 0.5, "
                             "along (phi 0) and across (phi 90) the tangent")
    return parser


def print_decomposition(paths: int) -> None:
    print("distribution, alpha, theta_i, F0: E_ss (separable, the plugin) | E_1 "
          "(height-correlated, the walk's first bounce) | k >= 2 | W (the walk)")
    thetas = (0, 60, 85)
    mus = np.cos(np.radians(thetas))
    for distribution in DISTRIBUTIONS:
        for alpha in (0.3, 0.6, 1.0):
            w = albedo(distribution, mus, alpha, (1.0, 0.5), paths, seed=11)
            e1 = albedo(distribution, mus, alpha, (1.0, 0.5), paths, seed=11, orders=(1, 1))
            for j, f0 in enumerate((1.0, 0.5)):
                ess = compensated_albedo({"type": "cook_torrance", "distribution": distribution,
                                          "geometry": "smith", "alpha": alpha, "k": 0.0,
                                          "f0": f0, "specular_reflectance": 1.0}, thetas)
                for k, theta in enumerate(thetas):
                    print(f"{distribution}, {alpha}, {theta}, {f0}: {ess[k]:.3f} | "
                          f"{e1[k, j]:.3f} | {w[k, j] - e1[k, j]:.3f} | {w[k, j]:.3f}")


def print_slices() -> None:
    for geometry in ("smith", "cook_torrance"):
        for distribution in ("ggx", "beckmann", "blinn"):
            for alpha in (0.3, 0.6, 1.0):
                for theta in (30, 60):
                    comp, single = slice_difference(distribution, geometry, alpha, theta, 0.6)
                    print(f"{distribution}/{geometry}, alpha {alpha}, F0 0.6, theta_i {theta} "
                          f"deg: plane-of-incidence slice vs the walk, relative L1: "
                          f"compensated {100 * comp:.1f} %, single scattering {100 * single:.1f} %")


def print_grazing(paths: int) -> None:
    print("cook_torrance beckmann/smith, alpha 0.3: f (1/sr) that the separable compensation "
          "lobe adds, against the walk's multiple scattering (bounces >= 2, +- standard error, "
          f"{paths} paths)")
    for f0 in (1.0, 0.7):
        for r in grazing_difference("beckmann", 0.3, f0, paths):
            where = f"{r['pair']} {r['theta_i']}/{r['theta_o']} deg" + (
                f", azimuths {r['dphi']} deg apart" if r["pair"] == "side-on" else "")
            print(f"F0 {f0}, {where}: compensation adds {r['added']:.4f}, the walk's "
                  f"{r['walk']:.3g} +- {r['walk_error']:.1g}")


def print_anisotropic(paths: int) -> None:
    thetas, phis, f0s = (0, 45, 85), (0, 90), (1.0, 0.5)
    print(f"walk albedo W (+- standard error), {paths} paths per point; phi from the "
          "tangent s (alpha_x along s)")
    for distribution in DISTRIBUTIONS:
        for ax, ay in ANISOTROPIC:
            t, p = (a.ravel() for a in np.meshgrid(thetas, phis, indexing="ij"))
            w, err = albedo(distribution, np.cos(np.radians(t)), Alpha(ax, ay), f0s, paths,
                            seed=28, phi=np.radians(p), error=True)
            for k in range(len(t)):
                print(f"{distribution}, alpha ({ax}, {ay}), theta {t[k]}, phi {p[k]}: "
                      f"F0 1: {w[k, 0]:.6f}, F0 0.5: {w[k, 1]:.4f} +- {err[k, 1]:.4f}")


def print_residuals(ref: dict) -> None:
    if "pairs" in ref:                               # the walk at pairs of directions
        print_directional_residuals(ref)
        return
    if "forms" in ref:                               # the other Fresnel forms
        print("compensated cook_torrance (Smith G, k 0, m_S 1) against the walk with the same "
              f"Fresnel at every bounce, alpha in {ref['alpha']}, theta in {ref['theta']} deg, "
              "per channel:")
        for r in residuals_fresnel(ref):
            alpha, theta, e, w = r["at"]
            print(f"{r['form']}, {r['distribution']}: largest relative difference "
                  f"{100 * r['relative']:.2f} % (at alpha {alpha}, {theta} deg: {e} vs {w})")
        return
    if "phi" in ref:                                 # an anisotropic reference
        for distribution in DISTRIBUTIONS:
            for geometry in ("smith", "cook_torrance"):
                r = residuals_anisotropic(ref, distribution, geometry)
                au, av, f0, theta, phi, e, w = r["at"]
                print(f"{distribution}/{geometry} anisotropic: alpha_u, alpha_v in "
                      f"{ref['alpha']}, F0 in [0, 1], 0-85 deg, phi {ref['phi']}: largest "
                      f"relative difference {100 * r['relative']:.1f} % (walk >= 0.01; at "
                      f"({au}, {av}), F0 {f0}, {theta} deg, phi {phi}: {e:.4f} vs {w:.4f}), "
                      f"largest absolute {r['absolute']:.4f}; where the walk reflects >= 3 %: "
                      f"{100 * r['relative_3']:.1f} %; by phi: "
                      + ", ".join(f"{p} deg {100 * x:.1f} %" for p, x in r["by_phi"].items())
                      + f"; single scattering alone {100 * r['single']:.1f} %")
        return
    for distribution in ("ggx", "beckmann", "blinn"):
        for geometry in ("smith", "cook_torrance"):
            r = residuals(ref, distribution, geometry)
            alpha, f0, theta, e, w = r["at"]
            print(f"{distribution}/{geometry}: alpha <= 1, F0 in [0, 1], 0-85 deg: largest "
                  f"relative difference {100 * r['relative']:.1f} % (walk >= 0.01; at alpha "
                  f"{alpha}, F0 {f0}, {theta} deg: {e:.4f} vs {w:.4f}), largest absolute "
                  f"{r['absolute']:.4f}")


def main(argv: list[str] | None = None) -> int:
    """Write the walk's reference albedos (-o), print the residual of every
    compensated cook_torrance D x G against them (--residuals), or what the
    other options name."""
    parser = _parser()
    args = parser.parse_args(argv)
    log = lambda text: print(text, file=sys.stderr)
    if not (args.output or args.residuals or args.agreement or args.slices
            or args.decomposition or args.anisotropic or args.grazing):
        parser.error("nothing to do: give -o FILE, --residuals, --agreement, --slices, "
                     "--grazing, --decomposition or --anisotropic")
    if args.paths is None:
        args.paths = DIRECTIONAL_PATHS if args.directional else 100_000
    if args.paths < 2:
        parser.error(f"--paths {args.paths}: at least 2 paths per point")
    if args.agreement and not args.reference:
        parser.error("--agreement compares with the values of --reference FILE; give it")
    ref = None
    if args.reference:
        try:
            with open(args.reference) as f:
                ref = json.load(f)
        except (OSError, ValueError) as error:
            parser.error(f"--reference {args.reference}: cannot read it "
                         f"({getattr(error, 'strerror', None) or error})")
        if args.agreement and ("phi" in ref or "pairs" in ref):
            kind = "the walk's BRDF at pairs" if "pairs" in ref else "anisotropic reference albedos"
            parser.error(f"--agreement: {args.reference} holds {kind}; "
                         "--agreement compares isotropic ones")
    if args.output:
        try:
            check_output_file(args.output)
        except OutputError as error:
            parser.error(str(error))
    if args.decomposition:
        print_decomposition(args.paths)
    if args.slices:
        print_slices()
    if args.grazing:
        print_grazing(args.paths)
    if args.anisotropic:
        print_anisotropic(args.paths)
    if args.agreement:
        for distribution, a in reference_agreement(ref, args.paths, log=log).items():
            print(f"{distribution}: {a['points']} points, {args.paths} paths (seed "
                  f"{a['seed']}) against {ref['paths']}: largest |difference| "
                  f"{a['largest']:.1e} = {a['largest_z']:.2f} standard errors; "
                  f"largest in standard errors {a['worst_z']:.2f}; rms {a['rms_z']:.2f}")
    if not (args.output or args.residuals):
        return 0
    if ref is None:
        make = directional_reference if args.directional else \
            fresnel_reference if args.fresnel_forms else \
            reference_anisotropic if args.roughness == "anisotropic" else reference
        ref = make(args.paths, log)
    if args.output:
        tmp = args.output + ".tmp"
        with open(tmp, "w") as f:
            json.dump(ref, f, indent=None, separators=(",", ":"))
            f.write("\n")
        os.replace(tmp, args.output)
        log(f"wrote {args.output}")
    if args.residuals:
        print_residuals(ref)
    return 0
