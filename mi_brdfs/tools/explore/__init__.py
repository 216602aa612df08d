"""``mi-brdfs explore [--port N] [--host ADDR] [--no-browser]``: the course
models in the browser, live.

A local web app: pick a plugin, its mode and options; move a slider (each
generated from the parameter's declaration) and see the lobe in the plane of
incidence per colour channel, the lobe over the hemisphere in 3-D, the
directional albedo of the material and of its white configurations (with and
without energy compensation; the random walk on the microsurface for
``cook_torrance`` with Beckmann or GGX), the white furnace's value, and a
progressive render of a preview sphere — beside a second column with another
model or a Mitsuba built-in. "Fit" fits the left model to the right one;
"Copy XML" and "Copy Python" give the material as Mitsuba loads it.

The package, by concern:

- :mod:`.backend` — everything taken from the rest of mi_brdfs (one module);
- :mod:`.builtins` — the Mitsuba built-ins it compares with;
- :mod:`.material` — materials checked, completed and written as XML/Python;
- :mod:`.preview` — the preview scene and its procedural environment;
- :mod:`.session` — the computations and the Dr.Jit state;
- :mod:`.worker` — the one thread that runs them, newest request first;
- :mod:`.server` — HTTP, the API and the websocket (aiohttp);
- :mod:`.browser` — the headless Chromium that tests the page and takes the
  documentation's screenshots;
- ``static/`` — the page, its script and its style (Plotly.js comes from the
  ``plotly`` package).

It listens on 127.0.0.1 unless ``--host`` says otherwise (with a warning:
it has no authentication), and opens the page in the user's browser unless
``--no-browser``. Ctrl-C stops it (exit status 0).
"""
from __future__ import annotations

import sys

DEFAULT_PORT = 8765
LOOPBACK = ("127.0.0.1", "localhost", "::1")


def add_parser(sub, common) -> None:
    """The ``explore`` subcommand of ``mi-brdfs`` (``common``: the shared flags)."""
    from .backend import port_number
    e = sub.add_parser("explore", parents=[common()],
                       help="explore the models in the browser: lobes, albedo, live renders")
    e.add_argument("--port", type=port_number(), default=DEFAULT_PORT,
                   help=f"the port (default {DEFAULT_PORT}; 0: any free port)")
    e.add_argument("--host", default="127.0.0.1",
                   help="the address to listen on (default 127.0.0.1, this machine only)")
    e.add_argument("--no-browser", action="store_true", help="do not open the page")
    e.set_defaults(run=command)


def command(args) -> int:
    from .backend import configure
    try:
        import aiohttp  # noqa: F401
        import plotly  # noqa: F401
    except ModuleNotFoundError as error:
        raise RuntimeError(f"{error.name} is not installed; mi-brdfs explore needs it: "
                           "pip install 'mi_brdfs[explore]'") from None
    configure(args.threads, args.verbose)
    if args.host not in LOOPBACK:
        print(f"{args.prog}: warning: listening on {args.host}: anyone who can reach this "
              "machine on that address can use the explorer (it has no authentication)",
              file=sys.stderr)
    import asyncio
    return asyncio.run(serve(args.host, args.port, not args.no_browser, args.prog))


async def serve(host: str, port: int, browser: bool, prog: str = "mi-brdfs explore") -> int:
    """Serve until SIGINT or SIGTERM; 0 after a clean stop."""
    import asyncio
    import os
    import signal

    from aiohttp import web

    from .server import make_app
    from .session import Explorer
    from .worker import Worker

    jit, walker = Worker("explore-jit"), Worker("explore-walk")
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
    import os
    import threading
    import webbrowser
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY")
                                                 or os.environ.get("WAYLAND_DISPLAY")):
        print(f"{prog}: no display: open {url} in a browser", flush=True)
        return
    threading.Thread(target=webbrowser.open, args=(url,), daemon=True).start()
