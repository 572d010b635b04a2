"""The 3D view shares the map's area: beside the map with a divider that the operator
drags or moves with the arrow keys (remembered), and instead of the map on a phone,
with a way back. Measured in headless Chromium at the three screen sizes."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from playwright.sync_api import Browser, Page, expect

from gcs.launcher import LocalFleet
from tests.browser.conftest import SIZES, checked_page, log_in

pytestmark = [pytest.mark.browser, pytest.mark.integration]

OUTPUT = Path(os.environ.get("GCS_TEST_OUTPUT", "test-output")) / "viz3d"
SPLIT = ".viz3d-split"
DIVIDER = ".viz3d-divider"
# Half a pixel each side, as boxes are measured in fractional CSS pixels.
PX = 1.5


def _box(page: Page, selector: str) -> dict[str, float]:
    box = page.locator(selector).bounding_box()
    assert box is not None, f"{selector} is not shown"
    return box


def _open(page: Page, fleet: LocalFleet) -> dict[str, float]:
    """Logged in with the 3D view open; the map's box before it opened."""
    log_in(page, fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    expect(page.locator(".viz3d-toggle")).to_be_visible(timeout=30_000)
    area = _box(page, "#map")
    page.locator(".viz3d-toggle").click()
    expect(page.locator(SPLIT)).to_be_visible()
    # viser's client runs on this page's thread (same origin): measuring and tapping wait
    # for it to have loaded, as an operator would.
    expect(page.frame_locator(".viz3d-pane iframe").locator("canvas").first).to_be_visible(
        timeout=60_000
    )
    return area


def _on_top(page: Page, x: float, y: float) -> bool:
    """Whether the 3D view's part is what a tap at (x, y) reaches (nothing lies over it)."""
    return bool(
        page.evaluate(
            "([x, y]) => !!document.elementFromPoint(x, y)?.closest('.viz3d-split')", [x, y]
        )
    )


def _assert_beside(page: Page, area: dict[str, float]) -> dict[str, float]:
    """The view fills the map's area right of the map, full height; the map the rest."""
    split, map_box = _box(page, SPLIT), _box(page, "#map")
    assert page.locator(SPLIT).get_attribute("data-mode") == "beside"
    assert abs(split["y"] - area["y"]) < PX
    assert abs(split["height"] - area["height"]) < PX
    assert abs(map_box["x"] + map_box["width"] - split["x"]) < PX, (map_box, split)
    assert abs(split["x"] + split["width"] - (area["x"] + area["width"])) < PX, (split, area)
    # The map's own buttons moved left with it: none lies over the 3D view.
    for control in page.locator(".leaflet-control-container .leaflet-right").all():
        box = control.bounding_box()
        assert box is None or box["x"] + box["width"] <= split["x"] + PX
    assert _on_top(page, split["x"] + split["width"] / 2, split["y"] + 20)
    return split


def test_the_3d_view_is_beside_the_map_and_resizes_by_drag_and_by_keyboard(
    browser: Browser, fleet: LocalFleet
) -> None:
    OUTPUT.mkdir(parents=True, exist_ok=True)
    width, height = SIZES["desktop"]
    with checked_page(browser, width, height) as page:
        area = _open(page, fleet)
        split = _assert_beside(page, area)
        assert abs(split["width"] - area["width"] / 2) < 2  # half, the first time
        page.screenshot(path=str(OUTPUT / "split-desktop.png"))

        # Dragged 150 px to the left: the 3D view is 150 px wider, the map narrower.
        divider = _box(page, DIVIDER)
        x, y = divider["x"] + divider["width"] / 2, divider["y"] + divider["height"] / 2
        page.mouse.move(x, y)
        page.mouse.down()
        page.mouse.move(x - 75, y, steps=3)
        page.mouse.move(x - 150, y, steps=3)
        page.mouse.up()
        dragged = _assert_beside(page, area)
        assert abs(dragged["width"] - (split["width"] + 150)) < 2, (dragged, split)

        # Two presses of the right arrow give the map back a tenth of the area.
        page.locator(DIVIDER).focus()
        before = int(page.locator(DIVIDER).get_attribute("aria-valuenow") or "0")
        page.keyboard.press("ArrowRight")
        page.keyboard.press("ArrowRight")
        keyed = _assert_beside(page, area)
        assert abs(keyed["width"] - (dragged["width"] - area["width"] / 10)) < 2
        expect(page.locator(DIVIDER)).to_have_attribute("aria-valuenow", str(before + 10))

        # Remembered (splitShare.test.ts: read back at the next opening).
        stored = page.evaluate("() => JSON.parse(localStorage.getItem('gcs.viz3d.split'))")
        assert abs(stored["share"] * area["width"] - keyed["width"]) < 2, stored


def test_on_a_tablet_the_3d_view_is_beside_the_map_or_instead_of_it(
    browser: Browser, fleet: LocalFleet
) -> None:
    OUTPUT.mkdir(parents=True, exist_ok=True)
    width, height = SIZES["tablet"]
    with checked_page(browser, width, height, has_touch=True) as page:
        area = _open(page, fleet)
        _assert_beside(page, area)
        page.screenshot(path=str(OUTPUT / "split-tablet.png"))
        # Instead of the map, and back beside it; closed, the map has its area again.
        page.get_by_role("button", name="Instead of the map").tap()
        expect(page.locator(SPLIT)).to_have_attribute("data-mode", "instead")
        full = _box(page, SPLIT)
        assert abs(full["x"] - area["x"]) < PX
        assert abs(full["width"] - area["width"]) < PX
        page.get_by_role("button", name="Beside the map").tap()
        _assert_beside(page, area)
        page.get_by_role("button", name="Close 3D view").tap()
        expect(page.locator(SPLIT)).to_be_hidden()
        assert abs(_box(page, "#map")["width"] - area["width"]) < PX


def test_on_a_phone_the_3d_view_replaces_the_map_and_gives_it_back(
    browser: Browser, fleet: LocalFleet
) -> None:
    OUTPUT.mkdir(parents=True, exist_ok=True)
    width, height = SIZES["phone"]
    with checked_page(browser, width, height, has_touch=True) as page:
        area = _open(page, fleet)
        split = _box(page, SPLIT)
        expect(page.locator(SPLIT)).to_have_attribute("data-mode", "instead")
        for key in ("x", "y", "width", "height"):
            assert abs(split[key] - area[key]) < PX, (split, area)
        expect(page.locator(DIVIDER)).to_be_hidden()
        # Nothing of the map's lies over it: its middle and its corners are the 3D view's.
        for fx, fy in ((0.5, 0.5), (0.9, 0.1), (0.1, 0.9), (0.9, 0.9)):
            x, y = split["x"] + split["width"] * fx, split["y"] + split["height"] * fy
            assert _on_top(page, x, y), (fx, fy)
        page.screenshot(path=str(OUTPUT / "split-phone.png"))
        back = page.get_by_role("button", name="Back to map")
        expect(back).to_be_visible()
        back.tap()
        expect(page.locator(SPLIT)).to_be_hidden()
        expect(page.locator(".viz3d-pane iframe")).to_have_count(0)
        expect(page.locator(".viz3d-toggle")).to_have_attribute("aria-pressed", "false")
        assert abs(_box(page, "#map")["width"] - area["width"]) < PX
