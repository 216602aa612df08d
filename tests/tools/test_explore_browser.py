"""The explorer's page in a real browser: the system's Chromium, headless,
driven by Playwright (never `playwright install`; mi_brdfs/tools/explore/
browser.py). Load the page, move a slider and see the lobe change, see the
preview arrive, copy the XML and load it, type a bad value and read the
loader's message, fit, and fetch nothing from any other host."""
from __future__ import annotations

import shutil

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


def test_fit_moves_the_left_sliders_to_the_right_material(session):
    _, page, _, _ = session
    right = column(page, "right").locator("input[type=text][data-name=alpha]")
    right.fill("0.5")
    right.press("Enter")
    page.click("#fit")
    page.wait_for_function("document.getElementById('status').textContent.startsWith('fitted')",
                           timeout=120_000)
    assert shown_value(page, "left", "alpha") == pytest.approx(0.5, rel=0.15)           # GGX fitted to GGX gold
