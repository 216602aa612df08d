"""Regenerate what the repository keeps that is made from the models' modules
(in a checkout of the repository: it writes its README and docs):

    python -m mi_brdfs.tools.regenerate            # all of it
    python -m mi_brdfs.tools.regenerate --check    # say what is out of date, change nothing

1. the albedo tables a model declares (its ``tables()``) that the shipped
   file lacks or holds with other axes (``python -m mi_brdfs.tools.tables
   --only ...``; the tables already there are kept: rebuild one on purpose
   with that command);
2. the README's tables, each between its markers: the plugins (``<!--
   plugins -->``, from each module's title line and its cases' ``checked``)
   and which model for which material (``<!-- which-model -->``, from the
   committed trade sweep ``docs/benchmarks/trade/fits.json``, which
   ``python -m mi_brdfs.tools.fit.trade -o docs/benchmarks/trade`` makes);
3. the committed validation report (``mi-brdfs validate -o docs/validation``),
   where every model's χ², furnace, negative control and lobe plot come from
   its cases (``--check`` compares what the report ran with what the cases
   declare now: a model, a furnace configuration, a χ² test missing or gone).

Everything else is derived when it runs: the battery's cases, the bench's
rows, the fit's models and the plugin pages (the documentation build). Adding
a model is its module, one line of the registry, its lecture-transcription
test, and this command (CONTRIBUTING.md).
"""
from __future__ import annotations

import argparse
import inspect
import json
import os
import subprocess
import sys

from ..bsdfs import PLUGINS, cases, compensation
from ..render.exr import write_atomically
from .fit import trade
from .tables import specs

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
README = os.path.join(ROOT, "README.md")
REPORT = os.path.join(ROOT, "docs", "validation", "results.json")
TRADE = os.path.join(ROOT, "docs", "benchmarks", "trade", "fits.json")


def plugin_table() -> str:
    """The README's table of plugins: name (linking its module), what it is
    (its module's title), what it is checked against."""
    rows = ["| plugin | model | checked against |", "|---|---|---|"]
    for cls in PLUGINS:
        module = sys.modules[cls.__module__]
        title = inspect.getdoc(module).strip().splitlines()[0].split(" — ", 1)[-1]
        path = os.path.relpath(module.__file__, ROOT)
        rows.append(f"| [`{cls.name}`]({path}) | {title} | {cases.of(cls.name).checked} |")
    return "\n".join(rows)


def which_model_table() -> str:
    """The README's table "which model for my material", from the committed
    trade sweep, and what each rung buys and costs (:func:`.fit.trade.ladder`,
    once the sweep has rung fits)."""
    with open(TRADE, encoding="utf-8") as f:
        records = json.load(f)
    labels = dict((spec, label) for label, spec in trade.TARGETS)
    rungs = trade.ladder(records, labels)
    return trade.summary(records, labels) + ("\n" + rungs.rstrip("\n") if rungs else "")


TABLES = {"plugins": plugin_table, "which-model": which_model_table}   # README marker: its table


def readme_with_tables(text: str) -> str:
    """The README with every table of :data:`TABLES` made afresh between its
    ``<!-- NAME -->`` and ``<!-- /NAME -->`` markers."""
    for name, make in TABLES.items():
        begin = text.index(f"<!-- {name} -->") + len(f"<!-- {name} -->")
        end = text.index(f"<!-- /{name} -->")
        text = text[:begin] + "\n" + make() + "\n" + text[end:]
    return text


def missing_tables() -> list[str]:
    """The names of the declared tables the shipped file lacks (or holds with
    other axes)."""
    missing = []
    for spec in specs():
        try:
            compensation.shipped(spec)
        except compensation.TableError:
            missing.append(spec.name)
    return missing


def report_runs(results: dict) -> set[tuple]:
    """What a validation report ran, by name: each model's lobe plot, its
    furnace configurations and its χ² tests (configuration, θ, φ)."""
    return ({("lobes", r["model"]) for r in results["lobes"]}
            | {("furnace", r["model"], r["config"]) for r in results["furnace"]}
            | {("sampling", r["model"], r["config"], r["theta"], float(r["phi"]))
               for r in results["sampling"]})


def planned_runs() -> set[tuple]:
    """What ``mi-brdfs validate`` (full) would run now, from the models' cases."""
    return ({("lobes", name) for name in cases.lobe_configs()}
            | {("furnace", name, label) for name in cases.ALL
               for label, _ in cases.report_furnace(name)}
            | {("sampling", name, label, theta, float(case.phi))
               for name, tests in cases.report_chi2(False).items()
               for label, case in tests for theta in case.thetas})


def stale_report() -> list[str]:
    """What the committed validation report lacks of the models' cases, and
    what it ran that they no longer declare (one line each; empty if none)."""
    if not os.path.exists(REPORT):
        return [f"{os.path.relpath(REPORT, ROOT)} is missing"]
    with open(REPORT, encoding="utf-8") as f:
        done = report_runs(json.load(f))
    planned = planned_runs()
    name = lambda run: " ".join(str(x) for x in run)          # noqa: E731
    return ([f"the validation report lacks {name(r)}" for r in sorted(planned - done, key=str)]
            + [f"the validation report has {name(r)}, which no case declares"
               for r in sorted(done - planned, key=str)])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m mi_brdfs.tools.regenerate",
        description="Regenerate the albedo tables, the README's tables and the validation "
                    "report from the models' modules.")
    parser.add_argument("--check", action="store_true",
                        help="say what is out of date and exit 1 if anything is; change nothing")
    parser.add_argument("--no-report", action="store_true",
                        help="leave the validation report (about a minute and a half)")
    args = parser.parse_args(argv)
    stale = []
    tables = missing_tables()
    if tables:
        stale.append(f"albedo tables missing: {', '.join(tables)}")
    with open(README, encoding="utf-8") as f:
        readme = f.read()
    if readme_with_tables(readme) != readme:
        stale.append("README.md's tables")
    if not args.no_report:
        stale += stale_report()
    if args.check:
        for line in stale:
            print(f"out of date: {line}")
        return 1 if stale else 0
    if tables:
        subprocess.run([sys.executable, "-m", "mi_brdfs.tools.tables", "--only", *tables],
                       check=True)
    if readme_with_tables(readme) != readme:
        def write(tmp: str) -> None:
            with open(tmp, "w", encoding="utf-8") as f:
                f.write(readme_with_tables(readme))
        write_atomically(README, write)
        print("wrote README.md's tables")
    if not args.no_report:
        subprocess.run([sys.executable, "-m", "mi_brdfs", "validate", "-o",
                        os.path.join(ROOT, "docs", "validation")], check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
