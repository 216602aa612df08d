"""The explorer's page in a real browser: the system's Chromium, headless,
driven by Playwright (never `playwright install`; mi_brdfs/tools/explore/
browser.py). Load the page, move a slider and see the lobe change, see the
preview arrive, copy the XML and load it, type a bad value and read the
loader's message, fit, and fetch nothing from any other host; and under use:
the plots follow a drag, nothing overflows a 1280 px window, the copied
numbers are short, the 3-D lobe stays in its panel. Nothing here is timed:
the latencies are measured (tools/explore/latency.py), not asserted."""
from __future__ import annotations

import re
import shutil

import numpy as np
import pytest

pytest.importorskip("aiohttp")
pytest.importorskip("playwright")
if not shutil.which("chromium"):
    pytest.skip("no system Chromium (apt-get install chromium)", allow_module_level=True)

import mitsuba as mi                                          # noqa: E402

import mi_brdfs                                               # noqa: E402,F401
from mi_brdfs.tools.explore.browser import Server, chromium, column, open_page   # noqa: E402

LOBE = "document.querySelector('.column[data-side=left] .lobe').data"


@pytest.fixture(scope="module")
def session():
    """(server, page, the URL of every request the page made, its errors)."""
    with Server() as server, chromium() as context:
        requests, errors = [], []
        context.on("request", lambda r: requests.append(r.url))
        page = open_page(context, server.url)
        page.on("pageerror", lambda e: errors.append(str(e)))
        yield server, page, requests, errors
    assert server.returncode == 0 and "Traceback" not in server.stderr, server.stderr


def test_the_page_loads_every_view_from_this_server_only(session):
    server, page, requests, errors = session
    assert page.title() == "mi-brdfs explore"
    for side in ("left", "right"):
        views = column(page, side)
        assert views.locator(".lobe .main-svg").count() > 0          # Plotly drew them
        assert views.locator(".albedo .main-svg").count() > 0
        assert views.locator(".lobe3d .gl-container canvas, .lobe3d canvas").count() > 0
    assert requests and all(url.startswith(server.url) or url.startswith("data:")
                            for url in requests), requests
    assert errors == []


def test_a_preview_image_arrives_and_refines(session):
    _, page, _, _ = session
    img = column(page, "left").locator(".preview")
    page.wait_for_function("document.querySelector('.column[data-side=left] .preview')"
                           ".dataset.spp == 256", timeout=120_000)
    assert img.get_attribute("src").startswith("data:image/png;base64,")
    size = page.evaluate("(() => { const i = document.querySelector('.column[data-side=left] "
                         ".preview'); return [i.naturalWidth, i.naturalHeight]; })()")
    assert size == [128, 128]
    assert "256 spp" in column(page, "left").locator(".spp").inner_text()


def test_moving_a_slider_changes_the_lobe(session):
    _, page, _, _ = session
    before = page.evaluate(f"{LOBE}[0].r")
    plots_id = column(page, "left").get_attribute("data-plots")
    slider = column(page, "left").locator("input[type=range][data-name=alpha]")
    box = slider.bounding_box()
    page.mouse.click(box["x"] + box["width"] * 0.08, box["y"] + box["height"] / 2)   # smoother
    page.wait_for_function(f"document.querySelector('.column[data-side=left]').dataset.plots "
                           f"!= '{plots_id}'")
    after = page.evaluate(f"{LOBE}[0].r")
    alpha = shown_value(page, "left", "alpha")
    assert alpha < 0.15
    assert max(after) > 2 * max(before)                    # a sharper, higher peak


def copied(page, side: str, button: str) -> str:
    """What a copy button put on the clipboard (the status line says when)."""
    page.evaluate("navigator.clipboard.writeText('').then(() => "
                  "{ document.getElementById('status').textContent = ''; })")
    column(page, side).locator(button).click()
    page.wait_for_function("document.getElementById('status').textContent.endsWith('copied')")
    return page.evaluate("navigator.clipboard.readText()")


def shown_value(page, side: str, name: str) -> float:
    return float(column(page, side).locator(f"input[type=text][data-name={name}]").input_value())


def traversed(bsdf, key: str) -> float:
    return float(mi.traverse(bsdf)[key].numpy().ravel()[0])


def test_copy_xml_and_python_load_as_the_page_shows(session):
    _, page, _, _ = session
    xml = copied(page, "left", ".copy-xml")
    assert xml.startswith('<bsdf type="cook_torrance"')
    assert column(page, "left").locator(".copied").inner_text() == xml
    bsdf = mi.load_string(xml)
    assert traversed(bsdf, "alpha.value") == pytest.approx(shown_value(page, "left", "alpha"),
                                                            rel=1e-6)
    python = copied(page, "right", ".copy-python")
    scope: dict = {}
    exec(python, scope)                                    # as a user pastes it
    assert '"type": "roughconductor"' in python
    assert traversed(scope["bsdf"], "alpha.value") == pytest.approx(
        shown_value(page, "right", "alpha"), rel=1e-6)


def test_a_bad_value_shows_the_loaders_message(session):
    _, page, _, _ = session
    text = column(page, "left").locator("input[type=text][data-name=k]")
    text.fill("1.5")
    text.press("Enter")
    error = column(page, "left").locator(".error")
    page.wait_for_function("document.querySelector('.column[data-side=left] .error')"
                           ".textContent.length > 0")
    assert error.inner_text() == "cook_torrance: parameter 'k' = 1.5 is invalid; valid: [0, 1]"
    text.fill("0.2")
    text.press("Enter")
    page.wait_for_function("document.querySelector('.column[data-side=left] .error')"
                           ".textContent === ''")


def test_a_fresnel_form_shows_the_controls_of_its_parameters(session):
    _, page, _, errors = session
    left = column(page, "left")
    names = "Array.from(document.querySelectorAll('.column[data-side=left] .params " \
            "input[type=text]')).map(e => e.dataset.name)"
    assert not {"eta", "kappa", "int_ior", "f82_tint"} & set(page.evaluate(names))
    left.locator("select[data-name=fresnel]").select_option("conductor")
    page.wait_for_function(f"{names}.includes('kappa')")
    shown = set(page.evaluate(names))
    assert {"eta", "kappa"} <= shown and not {"int_ior", "f82_tint"} & shown
    left.locator("select[data-name=fresnel]").select_option("schlick")
    page.wait_for_function(f"!{names}.includes('kappa')")
    assert not {"eta", "kappa"} & set(page.evaluate(names))
    page.wait_for_function("document.querySelector('.column[data-side=left] .error')"
                           ".textContent === ''")
    assert errors == []


def test_fit_moves_the_left_sliders_to_the_right_material(session):
    _, page, _, _ = session
    right = column(page, "right").locator("input[type=text][data-name=alpha]")
    right.fill("0.5")
    right.press("Enter")
    page.click("#fit")
    page.wait_for_function("document.getElementById('status').textContent.startsWith('fitted')",
                           timeout=120_000)
    assert shown_value(page, "left", "alpha") == pytest.approx(0.5, rel=0.15)           # GGX fitted to GGX gold


# ----------------------------------------------------------------------------
#  The page under use: a drag, the page's width, the copied numbers, the 3-D lobe
# ----------------------------------------------------------------------------

WIDTH = 1280

DRAWN = """() => { window.__drawn = [];
  new MutationObserver(() => window.__drawn.push(
      document.querySelector('.column[data-side=left]').dataset.plots))
    .observe(document.querySelector('.column[data-side=left]'),
             {attributes: true, attributeFilter: ['data-plots']}); }"""


# A drag as the slider reports it: an ``input`` event every 5 ms (faster than
# any answer), and no ``change`` (the button is held), until stopped.
DRAG = """() => { const s = document.querySelector(
      '.column[data-side=left] input[type=range][data-name=alpha]');
  let i = 0;
  window.__drag = setInterval(() => {
    s.value = 300 + 40 * (i++ % 7);
    s.dispatchEvent(new Event('input', {bubbles: true}));
  }, 5); }"""


# The left column's plots requests on the websocket: those not answered yet,
# and the most ever waiting at once.
OUTSTANDING = """() => { const ws = page.ws, send = ws.send.bind(ws);
  const out = window.__out = new Set(); window.__most = 0;
  const left = text => { const m = JSON.parse(text);
                         return m.op === 'plots' && m.side === 'left' ? m.id : null; };
  ws.send = text => { const id = left(text);
    if (id !== null) { out.add(id); window.__most = Math.max(window.__most, out.size); }
    send(text); };
  const receive = ws.onmessage;                  // an answer counts before the page acts on it
  ws.onmessage = e => { out.delete(left(e.data)); receive(e); }; }"""


def test_the_plots_follow_a_dragged_slider_before_it_is_released(session):
    """While the slider moves all the time, the lobe is drawn again and
    again, not only once it stops: one plots request at a time, each answer
    drawn (not a request per move, each superseded before its answer)."""
    _, page, _, _ = session
    page.evaluate(DRAWN)
    page.evaluate(OUTSTANDING)
    page.evaluate(DRAG)
    try:
        page.wait_for_function("window.__drawn.length >= 3", timeout=60_000)
    finally:
        page.evaluate("clearInterval(window.__drag)")
    assert page.evaluate("window.__most") == 1


def overflow(page) -> dict:
    return page.evaluate("""() => ({
        page: document.documentElement.scrollWidth - innerWidth,
        boxes: [...document.querySelectorAll('.params input[type=text]')]
               .filter(i => i.scrollWidth > i.clientWidth).map(i => i.value)})""")


def test_nothing_is_wider_than_a_1280_px_window_even_with_copy_xml_open(session):
    """No horizontal scrolling at 1280 px, the copied XML shown in both
    columns; every text box shows its whole value (a colour's three)."""
    server, first, _, _ = session
    page = open_page(first.context, server.url, width=WIDTH)
    try:
        assert overflow(page) == {"page": 0, "boxes": []}
        for side in ("left", "right"):
            copied(page, side, ".copy-xml")
            assert column(page, side).locator(".copied").is_visible()
        assert overflow(page) == {"page": 0, "boxes": []}
    finally:
        page.close()


def shortest_float32(text: str) -> bool:
    """``text`` reads back as a float32 that no shorter %g text gives
    (NumPy's float32, not the module's writer)."""
    value = np.float32(float(text))
    digits = len(text.lstrip("-").replace(".", "").split("e")[0].lstrip("0").rstrip("0")) or 1
    return all(np.float32(float(f"{float(value):.{d}g}")) != value for d in range(1, digits))


def test_copy_xml_writes_the_digits_a_user_would_type(session):
    """Every number of the copied XML is the shortest text that reads back as
    the float32 the plugin holds, after a drag that gives values such as
    0.30000001192092896 in float64."""
    _, page, _, _ = session
    text = column(page, "left").locator("input[type=text][data-name=f0]")
    text.fill(repr(1 / 3))
    text.press("Enter")
    xml = copied(page, "left", ".copy-xml")
    numbers = [n for v in re.findall(r'<(?:float|rgb) name="\w+" value="([^"]+)"', xml)
               for n in v.split(", ")]
    assert numbers and all(shortest_float32(n) for n in numbers), numbers
    assert 'name="f0" value="0.33333334, 0.33333334, 0.33333334"' in xml    # (a colour)


def viridis_on_the_border(page, side: str, tmp_path) -> tuple[int, int]:
    """(coloured pixels on the 3-D lobe panel's outer 3 px, coloured pixels
    inside): the surface's colours are saturated, the axes grey."""
    path = tmp_path / f"lobe3d-{side}.png"
    column(page, side).locator(".lobe3d").screenshot(path=str(path))
    rgb = np.array(mi.Bitmap(str(path)), dtype=int)[..., :3]
    coloured = (rgb.max(axis=2) - rgb.min(axis=2)) > 60
    border = coloured.copy()
    border[3:-3, 3:-3] = False
    return int(border.sum()), int(coloured.sum())


@pytest.mark.parametrize("alpha, theta", [(0.08, 70), (0.08, 89), (0.05, 20), (1.0, 45)])
def test_the_3d_lobe_stays_inside_its_panel(session, tmp_path, alpha, theta):
    _, page, _, _ = session
    text = column(page, "left").locator("input[type=text][data-name=alpha]")
    text.fill(str(alpha))
    text.press("Enter")
    page.evaluate(f"(() => {{ const s = document.getElementById('theta'); s.value = {theta}; "
                  "s.dispatchEvent(new Event('input')); })()")
    page.wait_for_function(
        "(() => { const c = document.querySelector('.column[data-side=left]'); "
        f"const p = c.querySelector('.lobe').data; return p && c.dataset.lobe3d === c.dataset.plots "
        f"&& Math.abs(p[3].theta[0] - {90 + theta}) < 1e-9 "
        f"&& page.columns.left.plots.material.alpha === {alpha}; }})()", timeout=60_000)
    page.wait_for_timeout(300)                    # WebGL draws at the next frame
    border, inside = viridis_on_the_border(page, "left", tmp_path)
    assert inside > 50                            # the lobe is drawn
    assert border == 0, (alpha, theta)
