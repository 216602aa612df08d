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
- :mod:`.server` — HTTP, the API and the websocket (aiohttp), and serving
  them until Ctrl-C;
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

from .backend import configure, port_number

DEFAULT_PORT = 8765
LOOPBACK = ("127.0.0.1", "localhost", "::1")


def add_parser(sub, common) -> None:
    """The ``explore`` subcommand of ``mi-brdfs`` (``common``: the shared flags)."""
    e = sub.add_parser("explore", parents=[common()],
                       help="explore the models in the browser: lobes, albedo, live renders")
    e.add_argument("--port", type=port_number(), default=DEFAULT_PORT,
                   help=f"the port (default {DEFAULT_PORT}; 0: any free port)")
    e.add_argument("--host", default="127.0.0.1",
                   help="the address to listen on (default 127.0.0.1, this machine only)")
    e.add_argument("--no-browser", action="store_true", help="do not open the page")
    e.set_defaults(run=command)


def command(args) -> int:
    try:                        # the explore extra: checked first, for a one-line error
        import aiohttp  # noqa: F401
        import plotly  # noqa: F401
    except ModuleNotFoundError as error:
        raise RuntimeError(f"{error.name} is not installed; mi-brdfs explore needs it: "
                           "pip install 'mi_brdfs[explore]'") from None
    from . import server        # here: it imports aiohttp
    configure(args.threads, args.verbose)
    if args.host not in LOOPBACK:
        print(f"{args.prog}: warning: listening on {args.host}: anyone who can reach this "
              "machine on that address can use the explorer (it has no authentication)",
              file=sys.stderr)
    return server.run(args.host, args.port, not args.no_browser, args.prog)
