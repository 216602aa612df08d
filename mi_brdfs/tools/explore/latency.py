"""The explorer's latencies as its page sees them (the bench group ``explore``).

A server in a process of its own (``mi-brdfs explore --port 0``) and one
websocket client that does what the page does, one request at a time:

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

import asyncio
import json
import statistics
import time

from .browser import Server

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


def finding(rows: list[dict]) -> str:
    """The slowest configuration's medians against the issue's budgets."""
    def worst(measure: str, key: str = "median_ms") -> dict:
        return max((r for r in rows if r["measure"] == measure), key=lambda r: r[key])
    plots, first, again = worst("slider -> plots"), worst("first image"), worst("re-render")
    startup = worst("startup")
    return (f"A slider move gives the page its plot data in {plots['median_ms']:.0f} ms "
            f"(median; at most {plots['max_ms']:.0f} ms), {plots['config']} the slowest "
            f"(budget 100 ms); a configuration's first 128² image arrives in "
            f"{first['median_ms']:.0f} ms at worst ({first['config']}; budget 1 s), a "
            f"re-render's first pass after a change in {again['median_ms']:.0f} ms "
            f"(median, {again['config']}). The server starts in "
            f"{startup['median_ms'] / 1000:.1f} s.")
