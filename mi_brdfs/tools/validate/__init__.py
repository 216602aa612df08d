"""The project's own validation, as one HTML report.

    mi-brdfs validate -o REPORT_DIR [--quick]

Sections, each a function that returns its rows, a function that turns the
rows into checks and one that writes its part of the page (a new section
adds the three and one line in :func:`validate`):

1. **Built-in equivalence** — the same scene rendered with a course model and
   with the Mitsuba built-in it should match, in ``passes`` independent passes
   each. "Identical up to noise" is judged per pixel by Welch's t-test of the
   two pass means against their variances, with a Bonferroni correction over
   the pixels (as Mitsuba's own render tests judge a render against its
   reference's variance), not by a fixed threshold. Beside the renders,
   **exact Fresnel** (:func:`fresnel_section`): at BSDF level ``cook_torrance``
   (Smith G, no diffuse) with ``fresnel="dielectric"`` equals ``roughplastic``
   (diffuse 0) to float precision, over many directions, and with the
   lecture's Schlick F differs by what Schlick's approximation changes: the
   render difference of the Schlick form against ``roughplastic`` is then
   that approximation's effect, and nothing else; with ``base="plastic"`` the
   whole BSDF equals ``roughplastic`` (a render check above).
2. **White furnace** — each model, both modes, white colours: the directional
   albedo E(theta_i) = integral of eval(wi, wo) dwo, by stratified quadrature
   (independent of the plugin's sampling) and by rendering the BSDF alone (a
   large plane seen by an orthographic camera at theta_i) inside a uniform white
   environment; the two must agree. Albedos above 1 are flagged with by how much
   and where. Models with ``energy_compensation`` get a third curve beside the
   two modes, hdr compensated. Where a model's cases promise albedo 1 (a white
   energy-preserving configuration, :func:`mi_brdfs.bsdfs.cases.promises_one`) the albedo
   must be 1 within 1 % up to 85°; a lobe's colour (m_S) scales its
   compensated albedo linearly, Fresnel is the only per-bounce reflectance.
   The scan-line modes are
   the lecture's clamped formulas: their albedo above 1 is documented
   behaviour, not a failure.
3. **Sampling** — Mitsuba's χ² test (p-value) of every sampler of the
   models' cases (:func:`mi_brdfs.bsdfs.cases.report_chi2`: all of the battery's tests; with
   ``--quick`` the representative ones of each model), with the density
   integrated per cell until it converges (:mod:`mi_brdfs.tools.chi2`: a fixed ``ires``
   rejects correct samplers of sharp lobes), and the variance of the sample
   weights (0 would be perfect importance sampling). The **negative
   controls** (:func:`mi_brdfs.bsdfs.cases.negative_controls`: a sampler against the pdf of a
   slightly different lobe) must be rejected: the test has the power to see
   a wrong pdf.
4. **Lobes** — eval (f·cos theta_o) in the plane of incidence for several
   incident angles, both modes, as polar plots.
5. **Ground truth** — compensated ``cook_torrance`` against the random walk on
   the Smith microsurface (:mod:`mi_brdfs.tools.groundtruth`): albedo against angle and BRDF
   slices, with the largest difference per D x G against its bound.

The report opens with a summary: every check with its status — pass, fail,
documented behaviour (what the scan-line modes and Schlick's approximation do
by design, measured) or a documented known limitation — each with its reason
(the table :data:`DOCUMENTED`; the README lists the limitations with their
measured numbers). ``mi-brdfs validate`` exits with status 1 when a check
fails that is not documented. New rows in the models' cases get their
checks without any change here.

The report folder is new, empty or a previous report (never a folder with
other files, see :mod:`mi_brdfs.tools.destinations`); it is written into a temporary folder and
moved into place when complete. ``--quick`` runs a reduced grid at reduced
sizes (for CI).

The package: :mod:`.sections` (what each section measures), :mod:`.verdicts`
(its checks and the summary), :mod:`.page` (the report's page).
"""
from __future__ import annotations

import json
import os
import time
from typing import Callable

import mitsuba as mi

from ...bsdfs import cases
from .. import compare, destinations, groundtruth
from .page import html_page
from .sections import (ALPHA, FULL, QUICK, Settings, chi2_count, equivalence_section,
                       fresnel_section, furnace_section, lobe_section, negative_section,
                       sampling_section, welch_test)
from .verdicts import DOCUMENTED, Known, checks, documented, summary

__all__ = ["validate", "ALPHA", "FULL", "QUICK", "Settings", "DOCUMENTED", "Known", "checks",
           "documented", "summary", "chi2_count", "equivalence_section", "fresnel_section",
           "furnace_section", "lobe_section", "negative_section", "sampling_section",
           "welch_test"]


def validate(out_dir: str, quick: bool = False, log: Callable[[str], None] = print) -> dict:
    """Run every section and write the report to out_dir (a new or empty
    folder, or a previous report: checked before any work). The results
    include ``checks`` and their ``summary`` (counts per status)."""
    compare.require_reports()
    size = QUICK if quick else FULL
    furnace = {name: cases.report_furnace(name)[:2 if quick else None] for name in cases.ALL}
    chi2 = cases.report_chi2(quick)
    negative = cases.negative_controls()
    count = chi2_count(chi2, negative)
    start = time.perf_counter()
    with destinations.report_dir(out_dir, "validate") as tmp:
        results = {"size": "quick" if quick else "full", "mitsuba": mi.__version__,
                   "variant": mi.variant()}
        log("built-in equivalence ...")
        results["equivalence"] = equivalence_section(size, tmp)
        results["fresnel"] = fresnel_section()
        log("white furnace ...")
        results["furnace"] = furnace_section(size, tmp, furnace)
        log("sampling ...")
        results["sampling"] = sampling_section(size, chi2, count)
        results["negative"] = negative_section(size, negative, count)
        log("lobes ...")
        results["lobes"] = lobe_section(tmp, cases.lobe_configs())
        log("ground truth ...")
        results["groundtruth"] = groundtruth.report_section(tmp, quick)
        results["checks"] = checks(results)
        results["summary"] = summary(results["checks"])
        results["seconds"] = time.perf_counter() - start
        with open(os.path.join(tmp, "results.json"), "w") as f:
            json.dump(results, f, indent=1)
        with open(os.path.join(tmp, "index.html"), "w") as f:
            f.write(html_page(results))
    return results
