"""The command-line reference, generated from the argparse parsers of
:mod:`mi_brdfs.tools.cli` (help texts become sentences: a capital letter and
a full stop), with each command's exit statuses."""
from __future__ import annotations

import argparse
import re
import textwrap

# Each command's exit statuses (what its function in mi_brdfs.tools.cli returns);
# every command: 1 on an error (one line on stderr), 130 when interrupted by Ctrl-C.
INTERRUPTED = "130: interrupted (Ctrl-C)."
EXIT_STATUS = {
    "render": ["0: the outputs are written.", "1: an error."],
    "scenes": ["0: the list is printed."],
    "compare": ["0: every test image is within the thresholds (or none was given).",
                "3: a test image exceeds a threshold (the report is written).",
                "1: an error."],
    "validate": ["0: no check fails (documented behaviour and known limitations included).",
                 "1: a check fails (the report is written), or an error."],
    "bench": ["0: the results are written.", "1: an error."],
    "fit": ["0: every fit succeeded.", "1: a fit failed (the report is written), or an error."],
    "explore": ["0: stopped by Ctrl-C or SIGTERM after serving.",
                "1: an error (e.g. the port is taken)."],
}
URL = re.compile(r"\b[a-z][a-z0-9+.-]*://[^\s),;]+")
FLAG = re.compile(r"(?<![\w`-])--?[a-zA-Z][\w-]*")         # -D, --help: literals, not dashes
# A command with its flag ("mi-brdfs COMMAND --help", "mitsuba -m"): one literal.
COMMAND = re.compile(r"\b(?:mi-brdfs|mitsuba)(?: [A-Za-z]+){0,2} --?[a-zA-Z][\w-]*")
LITERAL = re.compile("|".join(f"(?:{r.pattern})" for r in (URL, COMMAND, FLAG)))


def sentence(text: str) -> str:
    """A help text as a sentence of reStructuredText: capitalised, with a full
    stop, URLs, flags and commands as literals (not links, not dashes), reST's
    special characters escaped."""
    text = " ".join((text or "").split())
    if not text:
        return ""
    text = text.replace("\\", "\\\\").replace("*", "\\*").replace("`", "\\`").replace("|", "\\|")
    text = LITERAL.sub(lambda m: f"``{m.group(0)}``", text)
    text = text[0].upper() + text[1:]
    return text if text.endswith((".", "?", "!", ".)")) else text + "."


def subcommands(parser: argparse.ArgumentParser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help for a in action._choices_actions}
            for name, sub in action.choices.items():
                yield name, sub, helps.get(name, "")


def argument_rows(parser: argparse.ArgumentParser) -> list[tuple[str, str]]:
    rows = []
    for a in parser._actions:
        if isinstance(a, argparse._HelpAction):
            continue
        if a.option_strings:
            flag = ", ".join(a.option_strings)
            if a.nargs != 0:
                flag += " " + (a.metavar or a.dest.upper())
        else:
            flag = a.metavar or a.dest
            if a.nargs in ("+", "*"):
                flag += " ..."
        text = sentence(a.help)
        if a.choices and not isinstance(a, argparse._SubParsersAction):
            text += " One of: " + ", ".join(f"``{c}``" for c in a.choices) + "."
        if a.required and a.option_strings:
            text += " Required."
        rows.append((flag, text))
    return rows


def table(rows: list[tuple[str, str]]) -> list[str]:
    if not rows:
        return ["No options.", ""]
    lines = [".. list-table::", "   :header-rows: 1", "   :widths: 30 70", "",
             "   * - Argument", "     - Meaning"]
    for flag, text in rows:
        lines += [f"   * - ``{flag}``", f"     - {text}"]
    return lines + [""]


def page() -> str:
    from mi_brdfs.tools import cli
    top = cli.parser()
    lines = ["Command line: ``mi-brdfs``", "==========================", "",
             sentence(top.description), "",
             "Every command checks its numbers and paths before it starts; an error is "
             "one line, ``mi-brdfs COMMAND: error: ...``, and exit status 1 "
             "(``--traceback`` shows the traceback instead). Ctrl-C stops any command "
             "within a second, with exit status 130. ``python -m mi_brdfs`` is the same "
             "command.", "",
             ".. code-block:: text", "",
             textwrap.indent(top.format_usage().strip(), "   "), ""]
    lines += table(argument_rows(top)[:1])          # --version
    for name, sub, short in subcommands(top):
        title = f"``mi-brdfs {name}``"
        lines += [title, "-" * len(title), "", sentence(short), ""]
        if sub.description:
            lines += [sentence(sub.description), ""]
        usage = sub.format_usage().replace("usage: ", "").strip()
        lines += [".. code-block:: text", "", textwrap.indent(usage, "   "), ""]
        lines += table(argument_rows(sub))
        statuses = EXIT_STATUS[name] + ([] if name == "explore" else [INTERRUPTED])
        lines += ["Exit status:", "", *(f"- {s}" for s in statuses), ""]
    return "\n".join(lines)

