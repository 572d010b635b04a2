"""The dashboard's layout on a four-drone fleet at a desktop, a tablet and a phone size
(issue 33, "the map is the room"): in every state an operator opens (the fleet list
folded and unfolded, the selected vehicle's and the pilot's panels, each planning panel,
the phone's header menu) no element reaches past the screen's sides and no visible
control is covered by another element. A screenshot of each state is saved under
test-output/layout/."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from playwright.sync_api import Browser, Page, expect

from gcs.launcher import LocalFleet
from tests.browser.conftest import SIZES, checked_page, log_in
from tests.conftest import FLEET_SPEEDUP
from tests.support.layout_checks import covered_controls, overflowing_elements
from tests.support.processes import running_fleet

pytestmark = [pytest.mark.browser, pytest.mark.integration, pytest.mark.slow]

OUTPUT = Path(__file__).resolve().parents[2] / "test-output" / "layout"
VEHICLES = 4
PLANNING_PANELS = ("mission", "survey", "formation")


@pytest.fixture(scope="module")
def four_drones(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    with running_fleet(
        tmp_path_factory.mktemp("layout"), vehicles=VEHICLES, speedup=FLEET_SPEEDUP
    ) as fleet:
        yield fleet


@pytest.fixture(params=list(SIZES))
def sized_page(request: pytest.FixtureRequest, browser: Browser) -> Iterator[tuple[Page, str]]:
    small = request.param != "desktop"
    with checked_page(browser, *SIZES[request.param], has_touch=small) as page:
        yield page, request.param


def _assert_fits(page: Page, size: str, state: str, menu: str | None = None) -> None:
    """Nothing past the screen's sides, no control under another (but under ``menu``, one
    opened over the page on purpose); a screenshot of it."""
    OUTPUT.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=OUTPUT / f"{size}-{state}.png")
    assert overflowing_elements(page) == [], f"{size}, {state}"
    assert covered_controls(page, allowed_over=menu) == [], f"{size}, {state}"


def _drawer(page: Page, size: str, drawer: str, open_: bool) -> None:
    """Below desktop size the fleet list and the panels are drawers beside the map."""
    if size == "desktop":
        return
    button = page.locator(f'button[data-action="drawer-{drawer}"]')
    if (button.get_attribute("aria-expanded") == "true") != open_:
        button.click()
    expect(button).to_have_attribute("aria-expanded", str(open_).lower())


def test_every_panel_fits_the_screen_and_covers_no_control(
    sized_page: tuple[Page, str], four_drones: LocalFleet
) -> None:
    page, size = sized_page
    log_in(page, four_drones.plan.hub_http, "admin", four_drones.plan.admin_password)
    rows = page.locator("tr[data-vehicle-id]")
    expect(rows).to_have_count(VEHICLES, timeout=30_000)
    expect(rows.first.locator('[data-field="gps"]')).not_to_have_text("—", timeout=30_000)
    _assert_fits(page, size, "map")

    # The fleet's cards, a vehicle selected, then folded to their heading and back.
    _drawer(page, size, "fleet", True)
    rows.nth(1).locator('td[data-field="mode"]').click()
    expect(rows.nth(1)).to_have_attribute("aria-selected", "true")
    _assert_fits(page, size, "fleet")
    fold = page.locator('button[data-action="fold-fleet"]')
    fold.click()
    expect(fold).to_have_attribute("aria-expanded", "false")
    expect(rows.first).to_be_hidden()
    _assert_fits(page, size, "fleet-folded")
    fold.click()
    expect(rows.first).to_be_visible()

    # The selected vehicle's panel with the pilot's ("Fly by hand") and the events.
    _drawer(page, size, "ops", True)
    pilot = page.locator('[data-panel="pilot"]')
    expect(pilot.locator('[data-field="pilot-status"]')).to_have_text("not flown by hand")
    pilot.scroll_into_view_if_needed()
    _assert_fits(page, size, "pilot")
    _drawer(page, size, "ops", False)

    # Each planning panel in turn: docked beside (a phone: under) the map, not over it.
    map_box = page.locator("#map").bounding_box()
    assert map_box is not None
    for name in PLANNING_PANELS:
        toggle = page.locator(f'[data-action="{name}-toggle"]')
        toggle.click()
        panel = page.locator(f".{name}-panel")
        expect(page.locator(".map-dock")).to_contain_text(toggle.inner_text())
        expect(page.locator(f".map-dock .{name}-panel")).to_be_visible()
        _assert_fits(page, size, name)
        box, area = panel.bounding_box(), page.locator("#map").bounding_box()
        assert box is not None
        assert area is not None
        beside = box["x"] >= area["x"] + area["width"] - 1
        under = box["y"] >= area["y"] + area["height"] - 1
        assert beside or under, f"{name} panel {box} over the map {area}"
        page.locator(f'.map-dock [data-action="{name}-toggle"]').click()
        expect(page.locator(".map-dock")).to_be_hidden()
        # Leaflet's base-map list opens while the pointer is over it (the folded panel came
        # back under the pointer): in and out again folds it.
        page.locator(".leaflet-control-layers").hover()
        page.mouse.move(SIZES[size][0] / 2, 2)

    if size == "phone":
        menu = page.locator('button[data-action="header-menu"]')
        expect(page.locator('button[data-action="logout"]')).to_be_hidden()
        menu.click()
        expect(page.locator('button[data-action="logout"]')).to_be_visible()
        expect(page.locator('button[data-action="show-flights"]')).to_be_visible()
        _assert_fits(page, size, "menu", menu="#user-menu")
    page.locator('button[data-action="show-flights"]').click()
    expect(page.locator("#replay-panel")).to_be_visible()
    _assert_fits(page, size, "flights")
