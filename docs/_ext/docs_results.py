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


@lru_cache(maxsize=None)
def _trade_checks() -> list:
    """trade.checks of the committed records, once per build (it loads each
    conductor to read its F0; five roles read it)."""
    from mi_brdfs.tools.fit import trade
    return trade.checks(fits())


def _trade_first(conductors: bool | None = None, plugin: str | None = None) -> list[dict]:
    """The first-ranked fit of each material (of the conductors only, or of a
    target plugin only)."""
    from mi_brdfs.tools.fit import rank
    f0 = {spec: error is not None for spec, _, error in _trade_checks()}
    out = []
    for spec in dict.fromkeys(r["target"] for r in fits()):
        if (conductors is not None and f0[spec] != conductors) or (
                plugin is not None and rank.target_plugin(spec) != plugin):
            continue
        order = rank.ranked([r for r in fits() if r["target"] == spec])
        if order:
            out.append(order[0])
    return out


def _span(values, spec=".2f") -> str:
    return f"{min(values):{spec}}–{max(values):{spec}}"


def _trade_cost_phrase() -> str:
    """How the committed sweep's costs were timed: the load, and how many
    intervals reached the tolerance within the rounds allowed."""
    from mi_brdfs.tools.fit import FULL
    timed = [r for r in fits() if r.get("cost_low")]
    load = [r["cost_load"] for r in timed]
    limit = 1.0 + FULL.cost_tolerance
    tight = sum(r["cost_high"] / r["cost_low"] <= limit for r in timed)
    return (f"load average {min(load):.1f}–{max(load):.1f}; {tight} of the {len(timed)} "
            f"intervals reached high/low ≤ {limit:g} within {FULL.cost_rounds[1]} rounds, "
            f"the others stopped at "
            f"{max(r['cost_high'] / r['cost_low'] for r in timed):.3f} at most")


def _trade_compensation_phrase() -> str:
    from mi_brdfs.tools.fit import trade
    worse, better, pairs = trade.compensation_effect(fits())
    return (f"worse in {worse} of the {pairs} (material, model) pairs fitted both ways, "
            f"better in {better}")


def _trade_noise_phrase() -> str:
    """The seed noise's FLIP over the committed materials."""
    noise = {r["target"]: r["image_noise_flip"] for r in fits() if r.get("image_noise_flip")}
    return f"FLIP {_span(list(noise.values()), '.3f')}"


def _trade_below_noise_phrase() -> str:
    """On how many materials the first-ranked fit reads below the seed noise."""
    first = _trade_first()
    below = sum(r["image_flip"] < r["image_noise_flip"] for r in first)
    return f"{below} of the {len(first)} materials"


def _trade_cheaper_phrase() -> str:
    """Which materials have a cheaper model that looks the same (:mod:`rank`)."""
    from mi_brdfs.tools.fit import rank, trade
    labels = {spec: label for label, spec in trade.TARGETS}
    specs = list(dict.fromkeys(r["target"] for r in fits()))
    named = [labels.get(s, s) for s in specs
             if rank.cheaper_alternative(rank.ranked([r for r in fits() if r["target"] == s]))]
    return f"{len(named)} of the {len(specs)} materials" + (f" ({', '.join(named)})" if named else "")


def _fit_time(settings: str) -> str:
    """How long the bench's fit group measured a fit of one material (its
    median, the fits' and the costs' shares, the load)."""
    r = next(r for r in bench()["groups"]["fit"] if r["fit"] == settings)
    return (f"{r['median_s']:.0f} s for {r['models']} models (median of {r['runs']} runs: "
            f"{r['fits_s']:.0f} s of fits, "
            f"{r['costs_s']:.0f} s of costs; load average {r['load_before']:.1f} before, "
            f"{r['load_after']:.1f} after)")


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
    "trade.costs": _trade_cost_phrase,
    "trade.compensation": _trade_compensation_phrase,
    "trade.noise": _trade_noise_phrase,
    "trade.below_noise": _trade_below_noise_phrase,
    "trade.cheaper": _trade_cheaper_phrase,
    "fit.default": lambda: _fit_time("default"),
    "fit.quick": lambda: _fit_time("quick"),
    "trade.own_cost": lambda: _span([r["cost_ratio"] for r in _trade_first(conductors=True)]),
    "trade.plastics": lambda: _span([r["image_flip"] for r in _trade_first(plugin="roughplastic")]),
    "trade.tie": lambda: f"{max(g for _, g, _ in _trade_checks() if g is not None):.3f}",
    "trade.f0": lambda: f"{max(e for _, _, e in _trade_checks() if e is not None):.3f}",
    "trade.conductors": lambda: str(sum(e is not None for _, _, e in _trade_checks())),
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
    """The Markdown tables of the committed trade sweep, as its ``trade.md``
    (the sweep's own writer), the walk rung's figures included."""
    from mi_brdfs.tools.fit import trade
    labels = {spec: label for label, spec in trade.TARGETS}
    return trade.table(fits(), labels, trade.read_walk(str(FITS.parent)))


class TradeTable(SphinxDirective):
    """``trade-table``: the table "which model for which material" (Markdown
    pages only: the table is parsed as Markdown)."""

    def run(self):
        self.env.note_dependency(str(FITS))
        self.env.note_dependency(str(FITS.parent / "walk.json"))
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
    from mi_brdfs.tools.fit import trade          # the caption comes from the cells' writer
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
             trade.CAPTION, "",
             "```{trade-table}", "```", ""]
    return "\n".join(lines)


def pages(docs: Path) -> dict[str, tuple[str, str]]:
    return {"results/benchmarks": (".md", benchmarks_page()),
            "results/validation": (".md", validation_page()),
            "results/fit": (".md", fit_page())}


def setup(app) -> None:
    app.add_role("result", result_role)
    app.add_directive("trade-table", TradeTable)
