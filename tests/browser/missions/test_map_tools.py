"""One map tool at a time, in headless Chromium at each screen size against the package's
fleet (conftest.py): the survey's "Draw area" and the mission editor's waypoints never
share the map's clicks, folding a panel ends its tool, Esc and the banner's Done end the
active one, and "fly here" does not open while a tool is on. Screenshots of the banner go
to test-output/missions/ (map-tool-*)."""

from __future__ import annotations

import math

import httpx
import pytest
from playwright.sync_api import Locator, Page, expect

from gcs.launcher import LocalFleet
from tests.browser.conftest import log_in
from tests.support.mission_editor import collapse_panel, expand_panel, select, shot

VEHICLE = "sim_2"

# A point on the open map: inside #map, on no control, panel, marker, vehicle label (a
# button that selects its vehicle), drawn shape or banner.
OPEN_POINTS_JS = """() => {
    const map = document.querySelector('#map');
    const r = map.getBoundingClientRect();
    const points = [];
    for (let y = r.top + 80; y < r.bottom - 60; y += 17) {
        for (let x = r.left + 20; x < r.right - 20; x += 17) {
            const e = document.elementFromPoint(x, y);
            if (!e || !map.contains(e)) continue;
            if (e.closest('.leaflet-control, .mission-panel, .map-panel, .drawer-toggles, '
                + '.leaflet-marker-icon, .leaflet-interactive, .leaflet-popup, '
                + '.leaflet-tooltip, .map-tool-banner, .vehicle-labels, button')) continue;
            points.push([x, y]);
        }
    }
    return points;
}"""


def _click_open_map(page: Page, clicked: list[tuple[float, float]]) -> None:
    """Click a point of the open map at least 60 px from every point clicked before."""
    points = page.evaluate(OPEN_POINTS_JS)
    far = [p for p in points if all(math.dist(p, c) >= 60 for c in clicked)]
    assert far, "no open map left to click"
    x, y = far[len(far) // 2]
    page.mouse.click(x, y)
    clicked.append((x, y))


def _banner(page: Page) -> Locator:
    return page.locator('[data-field="map-tool-banner"]')


@pytest.mark.slow
def test_one_map_tool_at_a_time(
    sized_page: tuple[Page, str], mission_fleet: LocalFleet, api: httpx.Client
) -> None:
    page, size = sized_page  # `api`: every vehicle has a position
    log_in(page, mission_fleet.plan.hub_http, "admin", mission_fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
    select(page, size, VEHICLE)
    expand_panel(page)
    banner, rows = _banner(page), page.locator(".mission-row")
    edit = page.locator('[data-action="mission-edit"]')
    expect(banner).to_be_hidden()

    # The mission editor takes the map: the banner says so.
    edit.click()
    expect(banner).to_contain_text("Adding mission waypoints — Esc or Done to finish")
    expect(edit).to_have_text("Done")
    waypoints = rows.count()
    collapse_panel(page)  # folding the panel ends its tool
    expect(banner).to_be_hidden()
    clicked: list[tuple[float, float]] = []
    _click_open_map(page, clicked)
    expand_panel(page)
    expect(edit).to_have_text("Edit")
    expect(rows).to_have_count(waypoints)  # the folded editor took no click
    collapse_panel(page)

    # The survey's "Draw area" ends the editor and takes the clicks for its corners.
    expand_panel(page)
    edit.click()
    expect(banner).to_contain_text("Adding mission waypoints")
    page.locator('[data-action="survey-toggle"]').click()
    page.locator('[data-action="survey-draw"]').click()
    expect(banner).to_contain_text("Drawing survey area — Esc or Done to finish")
    expect(edit).to_have_text("Edit")
    collapse_panel(page)  # the mission panel's fold leaves the survey's tool alone
    expect(banner).to_contain_text("Drawing survey area")
    shot(page, "map-tool-banner", size)
    for _ in range(3):
        _click_open_map(page, clicked)
    # Fly here waits while a tool is on: a right-click opens no go-to.
    page.mouse.click(*clicked[-1], button="right")
    expect(page.locator(".go-here")).to_have_count(0)
    page.keyboard.press("Escape")  # Esc ends it: three corners close the ring
    expect(banner).to_be_hidden()
    expect(page.locator(".survey-panel")).to_have_attribute("data-rings", "1")
    expand_panel(page)
    expect(rows).to_have_count(waypoints)  # no survey corner became a waypoint

    # The editor again: its clicks are waypoints, and the survey draws nothing.
    edit.click()
    expect(banner).to_contain_text("Adding mission waypoints")
    collapse_panel(page)  # ends it, on a phone the panel covers the map
    expand_panel(page)
    edit.click()
    before = rows.count()
    page.locator('[data-action="survey-toggle"]').click()  # folded: out of the way
    _click_open_map(page, clicked)
    expect(rows).to_have_count(before + 1)
    expect(page.locator(".survey-panel")).to_have_attribute("data-rings", "1")
    page.locator('[data-action="map-tool-done"]').click()  # the banner's Done
    expect(banner).to_be_hidden()
    expect(edit).to_have_text("Edit")
    _click_open_map(page, clicked)
    expect(rows).to_have_count(before + 1)  # the plan stays; no tool took the click
