"""What the HTML reports share: the page, its tables and figures.

``mi-brdfs compare``, ``validate``, ``bench`` and ``fit`` each write an
``index.html`` beside their images; every one is made here, so that they look
alike and a change to how a report reads is made once. The pages are
self-contained: no script, no font, nothing fetched from the network.
"""
from __future__ import annotations

import html
from typing import Iterable, Sequence

esc = html.escape
DIGITS = 4                   # significant digits of a number in a table

CSS = """
body { font-family: sans-serif; margin: 2em; max-width: 90em; }
table { border-collapse: collapse; margin: 1em 0; }
td, th { border: 1px solid #ccc; padding: 0.2em 0.5em; text-align: right; }
td.text, th.text { text-align: left; }
.scroll { overflow-x: auto; }
.fail { color: #b00; font-weight: bold; } .pass { color: #070; }
.none { color: #555; } .known { color: #a60; } .documented { color: #246; }
tr.front td:first-child { font-weight: bold; }
.figs { display: flex; flex-wrap: wrap; gap: 0.8em; align-items: flex-start; }
.figs img { max-width: 100%; height: auto; }
img.render { width: 240px; image-rendering: pixelated; }
img.wide { width: 360px; }
figure { margin: 0; } figcaption { font-size: 0.9em; }
"""


def page(title: str, body: str, css: str = "") -> str:
    """A whole report page: its title as the heading, then ``body`` (HTML)."""
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            f"<title>{esc(title)}</title>\n<style>{CSS}{css}</style></head><body>\n"
            f"<h1>{esc(title)}</h1>\n{body}\n</body></html>\n")


def cell(value, digits: int = DIGITS) -> str:
    """A table cell: a number to ``digits`` significant digits, right-aligned;
    text escaped and left-aligned."""
    if isinstance(value, float):
        return f"<td>{value:.{digits}g}</td>"
    if isinstance(value, int):
        return f"<td>{value}</td>"
    return f"<td class='text'>{esc(str(value))}</td>"


def table(header: Sequence[str], rows: Iterable[Sequence], classes: Iterable[str] = (),
          cls: str = "", digits: int = DIGITS) -> str:
    """An HTML table in a horizontally scrolling box: ``header`` names, one
    ``row`` of values each (see :func:`cell`), ``classes`` a CSS class per
    row (e.g. "pass", "fail", "front")."""
    classes = list(classes)
    head = "".join(f"<th>{esc(h)}</th>" for h in header)
    body = []
    for i, row in enumerate(rows):
        c = f" class='{classes[i]}'" if i < len(classes) and classes[i] else ""
        body.append(f"<tr{c}>" + "".join(cell(v, digits) for v in row) + "</tr>")
    attr = f" class='{cls}'" if cls else ""
    return f"<div class='scroll'><table{attr}><tr>{head}</tr>{''.join(body)}</table></div>"


def figure(src: str, caption: str, cls: str = "") -> str:
    attr = f" class='{cls}'" if cls else ""
    return (f"<figure><img{attr} src='{esc(src)}' alt='{esc(caption)}'>"
            f"<figcaption>{esc(caption)}</figcaption></figure>")


def figures(items: Iterable[tuple[str, str]], cls: str = "") -> str:
    """A row of figures: (image file, caption) each."""
    return "<div class='figs'>" + "".join(figure(s, c, cls) for s, c in items) + "</div>"

