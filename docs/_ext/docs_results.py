"""The committed results on the site: every figure a page gives of them is read
from them at build time, never typed.

- the role ``{result}`NAME``` (MyST; ``:result:`NAME``` in reST): one figure or
  phrase of :data:`RESULTS`, e.g. ``{result}`validation.checks``` -> ``348``;
- the directive ``trade-table``: the fit guide's table "which model for which
  material", from the committed trade sweep (``fits.json``);
- the results pages (``results/benchmarks``, ``results/validation``,
  ``results/fit``), which link to the committed reports, copied into the site
  as ``reports/validation/`` and ``reports/trade/``.
"""
from __future__ import annotations

import collections
import json
from functools import lru_cache
from pathlib import Path

from docutils import nodes
from sphinx.util.docutils import SphinxDirective

DOCS = Path(__file__).resolve().parent.parent
VALIDATION = DOCS / "validation" / "results.json"
BENCH = DOCS / "benchmarks" / "results.json"
FITS = DOCS / "benchmarks" / "trade" / "fits.json"
STATUS = {"pass": "pass", "documented": "documented behaviour",
          "known": "known limitation", "fail": "FAIL"}


@lru_cache(maxsize=None)
def _json(path: Path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def validation() -> dict:
    return _json(VALIDATION)


def bench() -> dict:
    return _json(BENCH)


def fits() -> list[dict]:
    return _json(FITS)


# ----------------------------------------------------------------------------
#  Figures, by name
# ----------------------------------------------------------------------------

def _chi2_phrase() -> str:
    tests = validation()["sampling"]
    passed = sum(t["passed"] for t in tests)
    if passed == len(tests):
        return f"every one of the {len(tests)} χ² tests passes"
    return f"{passed} of the {len(tests)} χ² tests pass"


def _negative_phrase() -> str:
    controls = validation()["negative"]
    rejected = sum(c["rejected"] for c in controls)
    if rejected == len(controls):
        return f"every one of the {len(controls)} negative controls is rejected"
    return f"{rejected} of the {len(controls)} negative controls are rejected"


def _ires_phrase() -> str:
    """How fine the converged χ² integration had to go, in the committed report."""
    tests = validation()["sampling"]
    counts = collections.Counter(t["ires"] for t in tests)
    coarsest = min(counts)
    grazing = [t for t in tests if t["theta"] == max(t["theta"] for t in tests)]
    fine = sum(t["ires"] >= 257 for t in grazing)
    finest = max(tests, key=lambda t: t["ires"])
    return (f"{coarsest} points for {counts[coarsest]} of the {len(tests)} tests, 257 or more "
            f"for {fine} of the {len(grazing)} tests at {grazing[0]['theta']}° (lobes that meet "
            f"the horizon), and {finest['ires']} for {finest['model']} "
            f"({finest['config']}) at {finest['theta']}°")


def _trade_targets() -> int:
    return len(dict.fromkeys(r["target"] for r in fits()))


def _trade_best(prefix: str) -> dict[str, dict]:
    """The best fit (lowest BRDF error) of each target whose spec starts with
    ``prefix``."""
    best = {}
    for r in fits():
        if r["target"].startswith(prefix) and ("error" not in r) and (
                r["target"] not in best or r["brdf_error"] < best[r["target"]]["brdf_error"]):
            best[r["target"]] = r
    if not best:
        raise ValueError(f"no committed fit of a target {prefix!r}")
    return best


def _trade_range(*prefixes: str) -> str:
    """The lowest BRDF errors of these targets, from the smallest to the largest."""
    errors = sorted(r["brdf_error"] for p in prefixes for r in _trade_best(p).values())
    return f"{errors[0]:.2g}–{errors[-1]:.2g}"


def _trade_fit(target: str, model: str | None = None) -> dict:
    """One target's best fit, or its fit by ``model``."""
    if model is None:
        return _trade_best(target)[target]
    return next(r for r in fits() if r["target"] == target and r["model"] == model)


PLASTIC = "roughplastic:alpha=0.1,diffuse_reflectance=[0.6,0.2,0.1]"


def _fit_models() -> int:
    from mi_brdfs.tools.fit.models import all_models
    return len(all_models())


RESULTS = {
    "validation.checks": lambda: str(len(validation()["checks"])),
    "validation.pass": lambda: str(validation()["summary"]["pass"]),
    "validation.documented": lambda: str(validation()["summary"]["documented"]),
    "validation.known": lambda: str(validation()["summary"]["known"]),
    "validation.fail": lambda: str(validation()["summary"]["fail"]),
    "validation.seconds": lambda: f"{validation()['seconds']:.0f} s",
    "validation.chi2": _chi2_phrase,
    "validation.negative": _negative_phrase,
    "validation.ires": _ires_phrase,
    "trade.fits": lambda: str(len(fits())),
    "trade.targets": lambda: str(_trade_targets()),
    "trade.models": lambda: str(_fit_models()),
    "trade.gold_copper": lambda: _trade_range("roughconductor:material=Au",
                                              "roughconductor:material=Cu"),
    "trade.aluminium": lambda: _trade_range("roughconductor:material=Al"),
    "trade.plastic.model": lambda: _trade_fit(PLASTIC)["model"],
    "trade.plastic.error": lambda: f"{_trade_fit(PLASTIC)['brdf_error']:.2g}",
    "trade.plastic.flip": lambda: f"{_trade_fit(PLASTIC)['image_flip']:.2f}",
    "trade.plastic.lambert_flip": lambda: f"{_trade_fit(PLASTIC, 'lambert')['image_flip']:.2f}",
    "bench.machine": lambda: ", ".join(f"{k} {v}" for k, v in bench()["machine"].items()),
}


def result_role(name, rawtext, text, lineno, inliner, options=None, content=None):
    key = text.strip()
    if key not in RESULTS:
        msg = inliner.reporter.error(f"unknown result {key!r}; known: {', '.join(RESULTS)}",
                                     line=lineno)
        return [inliner.problematic(rawtext, rawtext, msg)], [msg]
    return [nodes.Text(RESULTS[key]())], []


# ----------------------------------------------------------------------------
#  The trade table
# ----------------------------------------------------------------------------

def trade_table() -> str:
    """The Markdown table of the committed trade sweep (the sweep's own writer)."""
    from mi_brdfs.tools.fit import trade
    labels = {spec: label for label, spec in trade.TARGETS}
    return trade.table(fits(), labels)


class TradeTable(SphinxDirective):
    """``trade-table``: the table "which model for which material" (Markdown
    pages only: the table is parsed as Markdown)."""

    def run(self):
        self.env.note_dependency(str(FITS))
        container = nodes.container(classes=["wide-table"])
        self.state.nested_parse(trade_table().splitlines(), self.content_offset, container)
        return [container]


# ----------------------------------------------------------------------------
#  The results pages
# ----------------------------------------------------------------------------

def benchmarks_page() -> str:
    from mi_brdfs.tools.bench import report
    from mi_brdfs.tools.bench.groups import GROUPS
    about = {name: g.about for name, g in GROUPS.items()}
    text = report.markdown(bench(), about, images="../benchmarks/")   # from results/
    return text.replace("# mi-brdfs bench results", "# Benchmark results", 1)


def validation_page() -> str:
    r = validation()
    by_section = collections.defaultdict(collections.Counter)
    for c in r["checks"]:
        by_section[c["section"]][c["status"]] += 1
    lines = ["# Validation report", "",
             f"The committed report of `mi-brdfs validate` ({r['size']} run, Mitsuba "
             f"{r['mitsuba']}, `{r['variant']}`, {r['seconds']:.0f} s): "
             f"{len(r['checks'])} checks. What the checks are and how to read them: "
             "{doc}`/guide/validation`.", "",
             "<a class=\"report-link\" href=\"../reports/validation/index.html\">"
             "The full report</a> (every check with its measurement, the renders, the "
             "white-furnace curves, the χ² tables and the lobe plots).", "",
             "| section | " + " | ".join(STATUS.values()) + " |",
             "|---|" + "---|" * len(STATUS)]
    for section, counts in by_section.items():
        lines.append(f"| {section} | " + " | ".join(str(counts[s]) for s in STATUS) + " |")
    lines.append("| **all** | " + " | ".join(str(r["summary"][s]) for s in STATUS) + " |")
    others = [c for c in r["checks"] if c["status"] != "pass"]
    if others:
        lines += ["", "## The checks that do not pass, and why", "",
                  "| check | status | measured | reason |", "|---|---|---|---|"]
        for c in others:
            cells = [c["what"], STATUS[c["status"]], c["measured"], c["reason"]]
            lines.append("| " + " | ".join(x.replace("|", "\\|") for x in cells) + " |")
    return "\n".join(lines) + "\n"


def fit_page() -> str:
    records = fits()
    failed = sum("error" in r for r in records)
    lines = ["# Fit report: which model for which material", "",
             f"The committed trade sweep (`mi-brdfs bench`, its `trade` group): every course "
             f"model fitted to {_trade_targets()} materials, {len(records)} fits"
             + (f", {failed} failed" if failed else "") + ". How the fits are made and how to "
             "read the table: {doc}`/guide/fit`.", "",
             "<a class=\"report-link\" href=\"../reports/trade/index.html\">The full "
             "report</a> (per material: the Pareto plot of error against cost, the BRDF "
             "slices, every fit's render, parameters and XML).", "",
             "Each cell: the model's BRDF error and, after the dot, the FLIP of its image; "
             "the lowest BRDF error per material in bold; cost × is the median render time "
             "over the material's own.", "",
             "```{trade-table}", "```", ""]
    return "\n".join(lines)


def pages(docs: Path) -> dict[str, tuple[str, str]]:
    return {"results/benchmarks": (".md", benchmarks_page()),
            "results/validation": (".md", validation_page()),
            "results/fit": (".md", fit_page())}


def setup(app) -> None:
    app.add_role("result", result_role)
    app.add_directive("trade-table", TradeTable)
