"""The explorer's latencies (the bench group ``explore``).

**What the page sees** (:func:`page_latency`, rows ``page: ...``): the page
itself in the system's Chromium (headless, driven by Playwright, 1280 px
wide; :mod:`.browser`), a server in a process of its own. A slider is moved
as a user does, and every request a change sends (plots, render and walk,
for the column, together) is timed from the slider's ``input`` event to the
answer drawn, in the page's own clock (the page reports what it sends and
shows as ``explore`` events on its document):

- ``page: drag -> plots``, ``... -> 3-D lobe``, ``... -> first pass``: a drag of
  the left column's ``alpha`` slider, ``DRAG_MOVES`` moves ``DRAG_GAP_MS``
  apart, the button held down: for each move, the time until the page shows
  an answer to a request sent after it (the page keeps one request of each
  kind in flight and sends the newest state when it answers; the walk waits
  for the release);
- ``page: change -> plots``, ``... -> 3-D lobe``, ``... -> first pass``
  (the first pass of the 128² render), ``... -> walk``, ``... -> all``:
  single clicks on the slider, each after the page has gone quiet; ``all``
  is the last of them.

**One request at a time** (:func:`measure`): one websocket client that does
what the page does, waiting for each answer before the next request (the
server's own speed, without the page or the other requests of a change):

- ``startup``: from starting the process to its "serving" line;
- ``first image``: the first preview pass (128², 4 spp) of a configuration
  the server has not loaded yet (its kernels may come from Dr.Jit's disk cache
  when an earlier run compiled them);
- ``slider -> plots``: a new parameter value to the lobe, 3-D lobe and albedo
  data, received (the page's 100 ms budget);
- ``re-render``: a new parameter value to its first preview pass;
- ``256 spp``: a new value to the last pass of its progressive render;
- ``fit``: the "Fit left to right" button's answer.
"""
from __future__ import annotations

import argparse
import asyncio
import json
import os
import statistics
import sys
import time

from .browser import Server, chromium, chromium_path, open_page

CONFIGS = [
    ("cook_torrance ggx smith", {"type": "cook_torrance", "distribution": "ggx",
                                 "geometry": "smith"}),
    ("cook_torrance ggx smith +ec", {"type": "cook_torrance", "distribution": "ggx",
                                     "geometry": "smith", "energy_compensation": True}),
    ("phong scanline", {"type": "phong", "mode": "scanline"}),
    ("roughconductor (Mitsuba)", {"type": "roughconductor", "distribution": "ggx"}),
]
SWEPT = {"cook_torrance": "alpha", "phong": "exponent", "roughconductor": "alpha"}


class Client:
    """One websocket, one request at a time; each answer timed."""

    def __init__(self, ws):
        self.ws, self.id = ws, 0

    async def ask(self, op: str, until, **payload) -> float:
        """Seconds from sending ``op`` to the first answer of it for which ``until(answer)``."""
        self.id += 1
        start = time.perf_counter()
        await self.ws.send_str(json.dumps({"op": op, "id": self.id, "side": "left", **payload}))
        async for msg in self.ws:
            answer = json.loads(msg.data)
            if answer.get("id") != self.id:
                continue
            if "error" in answer:
                raise RuntimeError(f"explore {op}: {answer['error']}")
            if until(answer):
                return time.perf_counter() - start
        raise RuntimeError("explore: the websocket closed")


def _row(measure: str, config: str, seconds: list[float]) -> dict:
    ms = [1000.0 * s for s in seconds]
    return {"measure": measure, "config": config, "n": len(ms),
            "median_ms": statistics.median(ms), "max_ms": max(ms)}


async def _measure(url: str, moves: int) -> list[dict]:
    import aiohttp              # optional: the explore extra
    rows = []
    first = lambda answer: True                                  # noqa: E731
    final = lambda answer: answer.get("final", False)            # noqa: E731
    async with aiohttp.ClientSession() as session:
        async with session.ws_connect(url.replace("http", "ws", 1) + "ws") as ws:
            client = Client(ws)
            for label, material in CONFIGS:
                rows.append(_row("first image", label, [
                    await client.ask("render", first, material=material, res=128)]))
                name = SWEPT[material["type"]]
                values = [0.05 + 0.9 * i / max(moves - 1, 1) for i in range(moves)]
                if name == "exponent":
                    values = [10.0 + 990.0 * v for v in values]
                plots, renders, finals = [], [], []
                for i, v in enumerate(values):
                    changed = {**material, name: v}
                    plots.append(await client.ask("plots", first, material=changed, theta_i=30))
                    if i % 3 == 0:
                        renders.append(await client.ask("render", first, material=changed))
                    else:
                        finals.append(await client.ask("render", final, material=changed))
                rows += [_row("slider -> plots", label, plots),
                         _row("re-render", label, renders),
                         _row("256 spp", label, finals)]
            (left, model), (right, target) = CONFIGS[0], CONFIGS[-1]
            rows.append(_row("fit", f"{left} to {right}", [
                await client.ask("fit", first, left=model, right={**target, "alpha": 0.3})]))
    return rows


def measure(moves: int) -> list[dict]:
    """Every latency, each of ``moves`` slider moves per configuration."""
    start = time.perf_counter()
    with Server() as server:
        startup = time.perf_counter() - start
        rows = asyncio.run(_measure(server.url, moves))
    if server.returncode != 0:
        raise RuntimeError(f"explore: the server ended with status {server.returncode}: "
                           f"{server.stderr[-2000:]}")
    return [_row("startup", "", [startup])] + rows


# ----------------------------------------------------------------------------
#  What the page sees
# ----------------------------------------------------------------------------

DRAG_MOVES = 20
DRAG_GAP_MS = 30
CHANGES = 8
# (the row's name, the request sent, the view shown): the plots' answer draws
# the lobe and the albedo at once, and the 3-D lobe at the next frame
VIEWS = (("plots", "plots", "plots"), ("3-D lobe", "plots", "lobe3d"),
         ("first pass", "render", "render"), ("walk", "walk", "walk"))
PAGE_CONFIG = "cook_torrance ggx smith, page"
PAGE_WIDTH = 1280

RECORD = """() => {
  const log = window.__latency = {events: [], moves: []};
  document.addEventListener("explore", e => log.events.push(e.detail));
  document.addEventListener("input", e => {          // before the page's own handler
    const column = e.target.closest(".column");
    log.moves.push({t: performance.now(), name: e.target.dataset.name ?? e.target.id,
                    side: column ? column.dataset.side : null});
  }, true);
}"""

# Quiet: nothing is waiting to be sent, and every request of each kind and
# column sent has been answered (the plots' 3-D lobe drawn too).
QUIET = """() => {
  const log = window.__latency, last = {}, shown = new Set();
  for (const e of log.events) {
    const key = e.side + " " + e.op;
    if (e.what === "sent") last[key] = e.id;
    else shown.add(key + " " + e.id);
  }
  const waiting = Object.values(page.columns).some(      // the page's own state: none to send
    c => c.pending || Object.values(c.wanted).some(Boolean));
  return !waiting && Object.entries(last).every(([key, id]) => shown.has(key + " " + id)
    && (!key.endsWith(" plots") || shown.has(key.replace(" plots", " lobe3d") + " " + id)));
}"""


def _answers(events: list[dict], side: str, op: str, view: str) -> list[tuple[float, float]]:
    """(sent, first shown) in ms of each request of ``op`` from ``side`` whose
    answer ``view`` showed."""
    sent, shown = {}, {}
    for e in events:
        if e["side"] != side:
            continue
        if e["what"] == "sent" and e["op"] == op:
            sent[e["id"]] = e["t"]
        elif e["what"] == "shown" and e["op"] == view and e["id"] not in shown:
            shown[e["id"]] = e["t"]
    return [(sent[i], shown[i]) for i in shown if i in sent]


def after_moves(moves: list[float], answers: list[tuple[float, float]]) -> list[float]:
    """For each move (ms), the time until the first answer drawn to a request
    sent after it: the move's value (or a later one) on the screen."""
    out = []
    for m in moves:
        waits = [shown - m for sent, shown in answers if sent >= m]
        if waits:
            out.append(min(waits))
    return out


def _settle(page, timeout_ms: float = 120_000) -> None:
    page.wait_for_timeout(100)                   # a change's requests leave at the next frame
    page.wait_for_function(QUIET, timeout=timeout_ms)


def _log(page) -> tuple[list[dict], list[dict]]:
    log = page.evaluate("() => { const l = window.__latency; const out = [l.events, l.moves]; "
                        "l.events = []; l.moves = []; return out; }")
    return log[0], [m for m in log[1] if m["side"] == "left" and m["name"] == "alpha"]


def _rows(kind: str, moves: list[dict], events: list[dict]) -> list[dict]:
    times = [m["t"] for m in moves]
    rows, every = [], []
    for label, op, view in VIEWS:
        if kind == "drag" and op == "walk":
            continue                            # sent at the release, by design
        waits = after_moves(times, _answers(events, "left", op, view))
        if waits:
            rows.append(_row(f"page: {kind} -> {label}", PAGE_CONFIG, [w / 1000 for w in waits]))
            every.append(waits)
    if kind == "change" and len(every) == len(VIEWS):
        rows.append(_row("page: change -> all", PAGE_CONFIG,
                         [max(w) / 1000 for w in zip(*every)]))
    return rows


def page_latency(drag_moves: int = DRAG_MOVES, changes: int = CHANGES) -> list[dict]:
    """What the page sees (the module's docstring), with the load average
    of the machine at the start in each row (``load``)."""
    load = os.getloadavg()[0]
    with Server() as server, chromium(permissions=()) as context:
        page = open_page(context, server.url, width=PAGE_WIDTH)
        page.evaluate(RECORD)
        _settle(page)
        _log(page)
        box = page.locator(".column[data-side=left] input[type=range][data-name=alpha]") \
            .bounding_box()
        y = box["y"] + box["height"] / 2
        at = lambda f: box["x"] + box["width"] * f                      # noqa: E731
        rows = []
        # single changes, each after the page has gone quiet
        for i in range(changes):
            page.mouse.click(at(0.15 + 0.6 * i / max(changes - 1, 1)), y)
            _settle(page)
        events, moves = _log(page)
        rows += _rows("change", moves, events)
        # a drag: the button held, a move every DRAG_GAP_MS
        page.mouse.move(at(0.15), y)
        page.mouse.down()
        for i in range(drag_moves):
            page.mouse.move(at(0.15 + 0.6 * (i + 1) / drag_moves), y)
            page.wait_for_timeout(DRAG_GAP_MS)
        page.mouse.up()
        _settle(page)
        events, moves = _log(page)
        rows += _rows("drag", moves, events)
    if server.returncode != 0:
        raise RuntimeError(f"explore: the server ended with status {server.returncode}: "
                           f"{server.stderr[-2000:]}")
    return [{**r, "load": round(load, 1)} for r in rows]


def page_available() -> bool:
    """Whether :func:`page_latency` can run: Playwright and a system Chromium."""
    try:
        import playwright.sync_api  # noqa: F401
        chromium_path()
    except (ImportError, RuntimeError):
        return False
    return True


def both(drag_moves: int, moves: int, changes: int = CHANGES) -> list[dict]:
    """What the page sees (if a browser is there), then one request at a time."""
    return (page_latency(drag_moves, changes) if page_available() else []) + measure(moves)


def finding(rows: list[dict]) -> str:
    """What the page sees against the issue's budgets, then the slowest
    configuration's medians one request at a time."""
    def worst(measure: str, key: str = "median_ms") -> dict:
        return max((r for r in rows if r["measure"] == measure), key=lambda r: r[key])
    page = {r["measure"]: r for r in rows if r["measure"].startswith("page: ")}
    seen = (f"What the page sees (Chromium, load average {page['page: drag -> plots']['load']}"
            f" on {os.cpu_count()} cores): during a drag the plots follow each move in "
            f"{page['page: drag -> plots']['median_ms']:.0f} ms (median; goal 100 ms, quiet), "
            f"the render's first pass in {page['page: drag -> first pass']['median_ms']:.0f} ms; "
            f"after a single change the plots take "
            f"{page['page: change -> plots']['median_ms']:.0f} ms, the first pass of the 128² "
            f"render {page['page: change -> first pass']['median_ms']:.0f} ms (goal 250 ms), "
            f"every request of the change {page['page: change -> all']['median_ms']:.0f} ms. "
            if {"page: drag -> plots", "page: change -> all"} <= set(page)
            else "What the page sees: not measured (no Playwright or no system Chromium). ")
    plots, first, again = worst("slider -> plots"), worst("first image"), worst("re-render")
    startup = worst("startup")
    return seen + (f"One request at a time, a slider move gives the page its plot data in "
                   f"{plots['median_ms']:.0f} ms "
            f"(median; at most {plots['max_ms']:.0f} ms), {plots['config']} the slowest "
            f"(budget 100 ms); a configuration's first 128² image arrives in "
            f"{first['median_ms']:.0f} ms at worst ({first['config']}; budget 1 s), a "
            f"re-render's first pass after a change in {again['median_ms']:.0f} ms "
            f"(median, {again['config']}). The server starts in "
            f"{startup['median_ms'] / 1000:.1f} s.")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m mi_brdfs.tools.explore.latency",
                                description="the explorer's latencies: what the page sees "
                                            "in Chromium, and one request at a time")
    p.add_argument("--page-only", action="store_true", help="only what the page sees")
    p.add_argument("--moves", type=int, default=DRAG_MOVES, help="moves of the drag")
    args = p.parse_args(argv)
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}, "
          f"{os.cpu_count()} cores")
    rows = page_latency(args.moves) if args.page_only else both(args.moves, args.moves)
    for r in rows:
        print(f"{r['measure']:<28} {r['config']:<32} n={r['n']:<3} "
              f"median {r['median_ms']:7.1f} ms  max {r['max_ms']:7.1f} ms")
    if not args.page_only:
        print(finding(rows))
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
