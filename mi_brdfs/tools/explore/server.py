"""The explorer's web server (aiohttp): the page, its API and its websocket.

Routes (documented for users on the site's explore page):

=========================  =================================================
``GET /``                  the page
``GET /static/NAME``       its script and style, and Plotly.js (from the
                           installed ``plotly`` package); nothing else
``GET /api/models``        every model with its parameters and options
``POST /api/plots``        ``{"material", "theta_i"}``: lobes and albedo
``POST /api/render``       ``{"material", "res", "spp"}``: a preview image
``POST /api/walk``         ``{"material"}``: the random walk's furnace curve
``POST /api/material``     ``{"material"}``: the material as XML and Python
``POST /api/fit``          ``{"left", "right"}``: left's parameters fitted
``GET /ws``                a websocket: the same operations, as messages
                           ``{"op", "id", "side", ...}``; renders are pushed
                           pass after pass, and a newer message of the same
                           operation and side supersedes an older one
=========================  =================================================

Every error is JSON, ``{"error": "one line"}``, with status 400 for a bad
request, 403, 404, 405 or 413 as HTTP has them, 500 for a failure of ours;
never a traceback. Requests from another origin (a page of another site in
the user's browser) are refused, and so, on loopback, are requests that name
another host (DNS rebinding).
"""
from __future__ import annotations

import asyncio
import itertools
import json
import os
import signal
import sys
import threading
import webbrowser
from importlib import util
from urllib.parse import urlsplit

from aiohttp import WSMsgType, web

from .backend import MaterialError, message
from .material import RequestError
from .session import Explorer
from .worker import Worker

STATIC = os.path.join(os.path.dirname(__file__), "static")
FILES = {"explore.js": "application/javascript", "explore.css": "text/css"}
MAX_BODY = 256 * 1024          # bytes of a request (a material is a few hundred)


def plotly_js() -> str:
    """The path of the Plotly.js bundle shipped inside the plotly package."""
    spec = util.find_spec("plotly")
    path = spec and spec.origin and os.path.join(os.path.dirname(spec.origin), "package_data",
                                                 "plotly.min.js")
    if not path or not os.path.isfile(path):
        raise RuntimeError("the plotly package holds no plotly.min.js; explore needs it: "
                           "pip install 'mi_brdfs[explore]'")
    return path


def dumps(data) -> str:
    return json.dumps(data, allow_nan=False, separators=(",", ":"))


def error_response(status: int, text: str) -> web.Response:
    return web.json_response({"error": text}, status=status, dumps=dumps)


# ----------------------------------------------------------------------------
#  The operations, shared by the HTTP API and the websocket
# ----------------------------------------------------------------------------

def _field(payload: dict, name: str, default=None, required: bool = False):
    if name not in payload:
        if required:
            raise RequestError(f"'{name}' is missing")
        return default
    return payload[name]


class Operations:
    """What a request may ask for: each operation's worker and work."""

    def __init__(self, explorer, jit, walker):
        self.explorer, self.jit, self.walker = explorer, jit, walker

    def job(self, op: str, payload: dict):
        """(worker, work) for an operation; RequestError if unknown or malformed."""
        ex = self.explorer
        if not isinstance(payload, dict):
            raise RequestError("a request is a JSON object")
        if op == "plots":
            material = _field(payload, "material", required=True)
            theta_i = _field(payload, "theta_i", 30.0)
            return self.jit, lambda: ex.plots(material, theta_i)
        if op == "render":
            material = _field(payload, "material", required=True)
            res, spp = _field(payload, "res", 128), _field(payload, "spp", 256)
            return self.jit, lambda: ex.frames(material, res, spp)
        if op == "walk":
            material = _field(payload, "material", required=True)
            return self.walker, lambda: ex.walk(material)
        if op == "material":
            material = _field(payload, "material", required=True)
            return self.jit, lambda: ex.strings(material)
        if op == "fit":
            left, right = (_field(payload, k, required=True) for k in ("left", "right"))
            return self.jit, lambda: ex.fit(left, right)
        raise RequestError(f"operation {op!r} is unknown; valid: plots, render, walk, "
                           "material, fit")


# ----------------------------------------------------------------------------
#  HTTP
# ----------------------------------------------------------------------------

LOOPBACK_NAMES = {"127.0.0.1", "localhost", "::1"}


def same_origin(request: web.Request) -> bool:
    """No Origin header (a script), or the server's own."""
    origin = request.headers.get("Origin")
    return origin is None or urlsplit(origin).netloc == request.host


def trusted_host(request: web.Request, names: set[str] | None) -> bool:
    """A server on loopback answers only to loopback's names: a page of
    another site whose name was made to point at 127.0.0.1 (DNS rebinding)
    is refused. ``names`` None: any name (the user chose another address)."""
    if names is None:
        return True
    host = urlsplit("//" + request.host).hostname if request.host else None
    return host in names


@web.middleware
async def json_errors(request: web.Request, handler):
    try:
        if not trusted_host(request, request.app["hosts"]):
            raise web.HTTPForbidden(reason=f"this server answers to 127.0.0.1 or localhost, "
                                           f"not {request.host}")
        return await handler(request)
    except web.HTTPException as error:
        if error.status < 400:
            raise
        return error_response(error.status, error.reason or "error")
    except (RequestError, MaterialError) as error:
        return error_response(400, str(error))
    except Exception as error:                        # noqa: BLE001  (one line, never a traceback)
        return error_response(500, message(error))


def make_app(explorer, jit, walker, host: str = "127.0.0.1") -> web.Application:
    """The application; ``host``: the address it listens on (on loopback it
    answers to loopback's names only)."""
    ops = Operations(explorer, jit, walker)
    app = web.Application(middlewares=[json_errors], client_max_size=MAX_BODY)
    app["sockets"] = set()
    app["hosts"] = LOOPBACK_NAMES | {host} if host in LOOPBACK_NAMES else None
    files = {name: os.path.join(STATIC, name) for name in FILES}
    files["plotly.min.js"] = plotly_js()
    counter = itertools.count()

    async def page(request):
        return web.FileResponse(os.path.join(STATIC, "index.html"),
                                headers={"Content-Type": "text/html; charset=utf-8"})

    async def static(request):
        name = request.match_info["name"]
        if name not in files:
            raise web.HTTPNotFound(reason=f"no file {name!r} here")
        return web.FileResponse(files[name])

    async def models(request):
        return web.json_response(explorer.public_models(), dumps=dumps)

    async def api(request):
        op = request.match_info["op"]
        if not same_origin(request):
            raise web.HTTPForbidden(reason="requests from another origin are refused")
        try:
            payload = await request.json()
        except (ValueError, UnicodeDecodeError) as error:
            raise RequestError(f"the request body is not JSON ({message(error)})") from None
        worker, work = ops.job(op, payload)
        loop, answer, last = asyncio.get_running_loop(), asyncio.Future(), {}

        def deliver(result, error, finished):
            if result is not None:
                last["result"] = result
            if finished:
                loop.call_soon_threadsafe(_settle, answer, last.get("result"), error)
        worker.submit(("http", next(counter), op), work, deliver)
        result = await answer
        return web.json_response(result, dumps=dumps)

    async def socket(request):
        if not same_origin(request):
            raise web.HTTPForbidden(reason="websockets from another origin are refused")
        # No per-message deflate: aiohttp compresses a large frame in a task
        # of its own that outlives a cancelled send, and when the page has
        # gone meanwhile that task's error is logged as never retrieved.  On a
        # local socket compression saves nothing worth that.
        ws = web.WebSocketResponse(heartbeat=None, max_msg_size=MAX_BODY, compress=False)
        await ws.prepare(request)
        await Client(ws, ops, next(counter)).serve(request.app["sockets"])
        return ws

    async def close_sockets(app):
        for ws in list(app["sockets"]):
            await ws.close()

    app.on_shutdown.append(close_sockets)
    app.router.add_get("/", page)
    app.router.add_get("/favicon.ico", favicon)
    app.router.add_get("/static/{name}", static)
    app.router.add_get("/api/models", models)
    app.router.add_post("/api/{op}", api)
    app.router.add_get("/ws", socket)
    return app


async def favicon(request) -> web.Response:
    return web.Response(status=204)        # none: a quiet browser console


def _settle(future: asyncio.Future, result, error) -> None:
    if future.done():
        return
    if error is not None:
        future.set_exception(RequestError(error))
    else:
        future.set_result(result)


# ----------------------------------------------------------------------------
#  The websocket
# ----------------------------------------------------------------------------

class Client:
    """One websocket connection: its messages become jobs in slots
    (client, side, op); results go back through one sender task."""

    def __init__(self, ws: web.WebSocketResponse, ops: Operations, number: int):
        self.ws, self.ops, self.id = ws, ops, ("ws", number)
        self.outbox: asyncio.Queue = asyncio.Queue()

    async def serve(self, sockets: set) -> None:
        sockets.add(self.ws)
        sender = asyncio.create_task(self._send())
        try:
            async for msg in self.ws:
                if msg.type == WSMsgType.TEXT:
                    self.receive(msg.data)
                elif msg.type == WSMsgType.BINARY:
                    self.reply({"op": None, "error": "messages are JSON text"})
        finally:
            sockets.discard(self.ws)
            for worker in (self.ops.jit, self.ops.walker):
                worker.cancel(self.id)
            sender.cancel()

    def receive(self, text: str) -> None:
        try:
            request = json.loads(text)
        except ValueError as error:
            self.reply({"op": None, "error": f"a message is a JSON object ({message(error)})"})
            return
        if not isinstance(request, dict):
            self.reply({"op": None, "error": "a message is a JSON object"})
            return
        head = {"op": request.get("op"), "id": request.get("id"), "side": request.get("side")}
        try:
            worker, work = self.ops.job(head["op"], request)
        except RequestError as error:
            self.reply({**head, "error": str(error)})
            return
        loop = asyncio.get_running_loop()

        def deliver(result, error, finished):
            if error is not None:
                loop.call_soon_threadsafe(self.reply, {**head, "error": error})
            elif result is not None:
                loop.call_soon_threadsafe(self.reply, {**head, **result})
        worker.submit((self.id, json.dumps(head["side"]), head["op"]), work, deliver)

    def reply(self, data: dict) -> None:
        self.outbox.put_nowait(data)

    async def _send(self) -> None:
        while True:
            data = await self.outbox.get()
            if self.ws.closed:
                return
            try:
                text = dumps(data)
            except ValueError:                  # NaN or infinity: not JSON
                text = dumps({k: data.get(k) for k in ("op", "id", "side")}
                             | {"error": "the result holds a number that is not finite"})
            try:
                await self.ws.send_str(text)
            except (ConnectionError, RuntimeError):
                return


# ----------------------------------------------------------------------------
#  Serving until stopped
# ----------------------------------------------------------------------------

def run(host: str, port: int, browser: bool, prog: str = "mi-brdfs explore") -> int:
    """:func:`serve` in an event loop of its own."""
    return asyncio.run(serve(host, port, browser, prog))


async def serve(host: str, port: int, browser: bool, prog: str = "mi-brdfs explore") -> int:
    """Serve until SIGINT or SIGTERM; 0 after a clean stop."""
    jit, walker = Worker("explore-jit", urgent=("plots", "material")), Worker("explore-walk")
    try:
        explorer = jit.call(Explorer)
        runner = web.AppRunner(make_app(explorer, jit, walker, host), shutdown_timeout=2.0,
                               access_log=None)
        await runner.setup()
        site = web.TCPSite(runner, host, port)
        try:
            await site.start()
        except OSError as error:
            await runner.cleanup()
            reason = os.strerror(error.errno).lower() if error.errno else str(error)
            raise RuntimeError(f"cannot listen on {host}:{port}: {reason}") from None
        bound = runner.addresses[0][1]
        shown = f"[{host}]" if ":" in host else host
        url = f"http://{shown}:{bound}/"
        print(f"{prog}: serving {url} (Ctrl-C stops it)", flush=True)
        if browser:
            open_browser(url, prog)
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, stop.set)
        await stop.wait()
        await runner.cleanup()
        print(f"{prog}: stopped", flush=True)
        return 0
    finally:
        jit.stop()
        walker.stop()


def open_browser(url: str, prog: str) -> None:
    """Open ``url`` in the user's graphical browser, in a thread of its own (a
    browser may take a while to start); on a machine without a display, say
    where the page is instead (a text browser would take over the terminal)."""
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY")
                                                 or os.environ.get("WAYLAND_DISPLAY")):
        print(f"{prog}: no display: open {url} in a browser", flush=True)
        return
    threading.Thread(target=webbrowser.open, args=(url,), daemon=True).start()
