"""mi-brdfs explore as a server, in a process of its own: the API, malformed
requests, many clients and clients that leave mid-render, the newest request
winning, no CPU when idle, loopback only, and a clean stop on Ctrl-C."""
from __future__ import annotations

import asyncio
import http.client
import json
import subprocess
import sys
import time
from urllib.parse import urlsplit

import pytest

aiohttp = pytest.importorskip("aiohttp")

from mi_brdfs import PLUGINS                              # noqa: E402
from mi_brdfs.tools.explore.browser import Server         # noqa: E402

BUILTINS = ["diffuse", "roughconductor", "roughplastic", "principled"]


@pytest.fixture(scope="module")
def server():
    with Server() as s:
        yield s
    assert s.returncode == 0 and "Traceback" not in s.stderr, s.stderr


def request(server, method: str, path: str, body=None, headers=None):
    """(status, content type, decoded JSON or text) of one HTTP request."""
    url = urlsplit(server.url)
    conn = http.client.HTTPConnection(url.hostname, url.port, timeout=120)
    data = body if isinstance(body, (bytes, type(None))) else json.dumps(body).encode()
    conn.request(method, path, body=data, headers={"Content-Type": "application/json",
                                                    **(headers or {})})
    response = conn.getresponse()
    text = response.read().decode()
    kind = response.getheader("Content-Type", "")
    conn.close()
    return response.status, kind, (json.loads(text) if kind.startswith("application/json")
                                   else text)


def cpu_ticks(pid: int) -> int:
    """User + system CPU time of a process, in clock ticks (/proc/PID/stat)."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return int(fields[11]) + int(fields[12])


# ----------------------------------------------------------------------------
#  HTTP
# ----------------------------------------------------------------------------

def test_models_lists_every_plugin_with_its_parameters(server):
    status, kind, models = request(server, "GET", "/api/models")
    assert status == 200 and kind.startswith("application/json")
    assert [m["name"] for m in models] == [cls.name for cls in PLUGINS] + BUILTINS
    for model in models:
        for p in model["params"]:
            assert {"name", "kind", "default", "lo", "hi", "control"} <= set(p), p
        for o in model["options"]:
            assert {"name", "type", "default", "choices"} <= set(o), o
    phong = next(m for m in models if m["name"] == "phong")
    exponent = next(p for p in phong["params"] if p["name"] == "exponent")
    assert (exponent["default"], exponent["lo"], exponent["hi"]) == (100.0, 0.0, 1e8)


def test_the_page_and_its_files_are_served_and_nothing_else(server):
    status, kind, page = request(server, "GET", "/")
    assert status == 200 and kind.startswith("text/html") and "explore.js" in page
    for name in ("explore.js", "explore.css", "plotly.min.js"):
        assert request(server, "GET", f"/static/{name}")[0] == 200, name
    for path in ("/static/../pyproject.toml", "/static/..%2F..%2Fbackend.py",
                 "/static/index.html%00", "/static/backend.py"):
        status, kind, body = request(server, "GET", path)
        assert status == 404 and kind.startswith("application/json"), path


def test_the_api_computes_what_the_page_shows(server):
    status, _, plots = request(server, "POST", "/api/plots",
                               {"material": {"type": "lambert", "reflectance": 0.5},
                                "theta_i": 10})
    assert status == 200 and plots["furnace"]["mean"] == pytest.approx(1.0, abs=3e-3)
    status, _, image = request(server, "POST", "/api/render",
                               {"material": {"type": "lambert"}, "spp": 8})
    assert status == 200 and image["spp"] == 8 and image["final"]
    assert image["image"].startswith("data:image/png;base64,")
    status, _, strings = request(server, "POST", "/api/material", {"material": {"type": "ward"}})
    assert status == 200 and strings["xml"].startswith('<bsdf type="ward"')


TOO_BIG = json.dumps({"material": {"type": "lambert"}, "pad": "x" * 300_000}).encode()


@pytest.mark.parametrize("method, path, body, headers, status, message", [
    ("POST", "/api/plots", b"{not json", None, 400, "the request body is not JSON"),
    ("POST", "/api/plots", [1, 2], None, 400, "a request is a JSON object"),
    ("POST", "/api/plots", {}, None, 400, "'material' is missing"),
    ("POST", "/api/nonesuch", {}, None, 400, "operation 'nonesuch' is unknown"),
    ("POST", "/api/plots", {"material": {"type": "cook_torrance", "alpha": -1}}, None, 400,
     "cook_torrance: parameter 'alpha' = -1.0 is invalid; valid: [0, 3.402823e+38]"),
    ("POST", "/api/plots", {"material": {"type": "phong"}, "theta_i": 95}, None, 400,
     "theta_i = 95 is invalid; valid: a number in [0, 89]"),
    ("POST", "/api/render", {"material": {"type": "phong"}, "spp": 0}, None, 400,
     "spp = 0 is invalid"),
    ("POST", "/api/fit", {"left": {"type": "phong"}}, None, 400, "'right' is missing"),
    ("POST", "/api/plots", TOO_BIG, None, 413, ""),
    ("POST", "/api/plots", {"material": {"type": "phong"}}, {"Origin": "http://example.org"},
     403, "requests from another origin are refused"),
    ("GET", "/api/models", None, {"Host": "rebound.example:8765"}, 403,
     "this server answers to 127.0.0.1 or localhost, not rebound.example:8765"),
    ("GET", "/api/plots", None, None, 405, ""),
    ("GET", "/nonesuch", None, None, 404, ""),
])
def test_a_malformed_request_gets_a_one_line_json_error(server, method, path, body, headers,
                                                        status, message):
    got, kind, answer = request(server, method, path, body, headers)
    assert (got, kind.split(";")[0]) == (status, "application/json"), answer
    assert answer["error"].startswith(message) and "\n" not in answer["error"], answer
    assert "Traceback" not in answer["error"]


# ----------------------------------------------------------------------------
#  The websocket
# ----------------------------------------------------------------------------

async def exchange(url: str, messages: list[dict], until, leave_early: bool = False) -> list[dict]:
    """Send ``messages`` on one websocket; collect replies until ``until(replies)``
    (or, with ``leave_early``, close as soon as a first image came)."""
    replies = []
    async with aiohttp.ClientSession() as session:
        async with session.ws_connect(url.replace("http", "ws") + "ws") as ws:
            for m in messages:
                await ws.send_str(json.dumps(m) if isinstance(m, dict) else m)
            async for msg in ws:
                replies.append(json.loads(msg.data))
                if until(replies) or (leave_early and "image" in replies[-1]):
                    break
    return replies


def final_image(ident):
    return lambda replies: any(r.get("id") == ident and r.get("final") for r in replies)


def test_many_clients_and_clients_that_leave_mid_render(server):
    """Eight clients at once; four leave after their first image. The others
    get their final images and plots; the server goes on serving."""
    def client(i: int):
        material = {"type": "phong", "exponent": 10.0 + i}
        return exchange(server.url, [
            {"op": "render", "id": 1, "side": "left", "material": material, "spp": 64},
            {"op": "plots", "id": 2, "side": "left", "material": material, "theta_i": i}],
            lambda r: final_image(1)(r) and any(x["op"] == "plots" for x in r),
            leave_early=i % 2 == 0)

    async def crowd():
        return await asyncio.wait_for(asyncio.gather(*(client(i) for i in range(8))), 300)
    results = asyncio.run(crowd())
    for i, replies in enumerate(results):
        assert not any("error" in r for r in replies), replies
        if i % 2:
            assert final_image(1)(replies) and replies[-1]["spp"] <= 64
            plots = next(r for r in replies if r["op"] == "plots")
            assert plots["theta_i"] == i
    assert request(server, "POST", "/api/walk", {"material": {"type": "phong"}})[0] == 200


def test_a_newer_render_supersedes_the_older_one(server):
    """Two renders of one column in a row: only the newer one finishes."""
    old = {"op": "render", "id": 1, "side": "right", "material": {"type": "blinn"}, "spp": 256}
    new = {**old, "id": 2, "material": {"type": "blinn", "exponent": 20.0}}
    replies = asyncio.run(exchange(server.url, [old, new], final_image(2)))
    assert final_image(2)(replies) and not final_image(1)(replies)
    assert sum(r["id"] == 1 for r in replies) <= 1          # at most the pass that was running


def test_malformed_messages_get_errors_and_the_socket_stays(server):
    replies = asyncio.run(exchange(server.url, [
        "{not json", "[1]", {"op": "nonesuch", "id": 3, "side": "left"},
        {"op": "plots", "id": 4, "side": "left", "material": {"type": "lambert", "reflectance": -1}},
        {"op": "material", "id": 5, "side": "left", "material": {"type": "lambert"}}],
        lambda r: any(x.get("id") == 5 for x in r)))
    errors = [r["error"] for r in replies if "error" in r]
    assert errors[:2] == ["a message is a JSON object (Expecting property name enclosed in "
                          "double quotes: line 1 column 2 (char 1))", "a message is a JSON object"]
    assert errors[2].startswith("operation 'nonesuch' is unknown")
    assert errors[3] == "lambert: parameter 'reflectance' = -1.0 is invalid; valid: [0, 1e+06]"
    assert replies[-1]["xml"].startswith('<bsdf type="lambert"')


# ----------------------------------------------------------------------------
#  The process
# ----------------------------------------------------------------------------

def test_an_idle_server_uses_no_cpu(server):
    """After work, an idle server takes no CPU time (no polling loop): at most
    2 clock ticks (20 ms) in 3 s, read from /proc/PID/stat."""
    request(server, "POST", "/api/render", {"material": {"type": "ward"}, "spp": 16})
    time.sleep(1.0)
    before = cpu_ticks(server.pid)
    time.sleep(3.0)
    assert cpu_ticks(server.pid) - before <= 2


def listening(port: int) -> list[str]:
    """The local addresses (hex, as /proc/net/tcp* has them) listening on ``port``."""
    found = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            lines = open(table).read().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            local, state = line.split()[1], line.split()[3]
            address, hex_port = local.split(":")
            if state == "0A" and int(hex_port, 16) == port:          # LISTEN
                found.append(address)
    return found


def test_it_listens_on_loopback_only(server):
    addresses = listening(urlsplit(server.url).port)
    assert addresses == ["0100007F"]                      # 127.0.0.1, and nothing else


def test_another_host_warns_and_ctrl_c_stops_it_cleanly():
    """--host with an address other than loopback's name warns (127.0.0.2 is
    still this machine); SIGINT, as Ctrl-C sends it, stops it with status 0."""
    with Server("--host", "127.0.0.2") as other:
        assert other.url.startswith("http://127.0.0.2:")
        assert request(other, "GET", "/api/models")[0] == 200
        assert listening(urlsplit(other.url).port) == ["0200007F"]
    assert other.returncode == 0
    assert "warning: listening on 127.0.0.2" in other.stderr and "Traceback" not in other.stderr
    assert other.stdout.strip().endswith("stopped")


def test_a_port_in_use_is_a_one_line_error(server):
    port = urlsplit(server.url).port
    run = subprocess.run([sys.executable, "-m", "mi_brdfs", "explore", "--no-browser",
                          "--port", str(port)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 1
    assert run.stderr.strip() == (f"mi-brdfs explore: error: cannot listen on 127.0.0.1:{port}: "
                                  "address already in use")
