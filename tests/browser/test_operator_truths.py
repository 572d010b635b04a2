"""What the operator's panels say is true across a page reload (issue 33, "small lies and
gaps"): "In flight" counts from the vehicle's own take-off, not from when the page
opened; the event filter offers every vehicle of the fleet, and the fleet's link-ups,
which came before the page, are in its feed."""

from __future__ import annotations

import re
import time
from collections.abc import Iterator

import httpx
import pytest
from playwright.sync_api import Browser, Page, expect

from gcs.launcher import LocalFleet
from tests.browser.conftest import SIZES, checked_page, log_in
from tests.conftest import FLEET_SPEEDUP
from tests.support.api import access_token, api_client
from tests.support.processes import running_fleet
from tests.support.waiting import poll_until

pytestmark = [pytest.mark.browser, pytest.mark.integration]

VEHICLES = ("sim_1", "sim_2")


@pytest.fixture(scope="module")
def truths_fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    with running_fleet(
        tmp_path_factory.mktemp("truths"), vehicles=len(VEHICLES), speedup=FLEET_SPEEDUP
    ) as fleet:
        yield fleet


@pytest.fixture(scope="module")
def api(truths_fleet: LocalFleet) -> Iterator[httpx.Client]:
    token = access_token(truths_fleet.plan.hub_http, "admin", truths_fleet.plan.admin_password)
    with api_client(truths_fleet.plan.hub_http, token) as client:
        yield client


def _open(page: Page, fleet: LocalFleet, size: str, *, logged_in: bool = False) -> None:
    if not logged_in:
        log_in(page, fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    expect(page.locator("tr[data-vehicle-id]")).to_have_count(len(VEHICLES), timeout=30_000)
    if size != "desktop":  # the panels are a drawer over the map
        page.locator('button[data-action="drawer-ops"]').click()


def _command(api: httpx.Client, vehicle: str, **command: object) -> None:
    response = api.post(f"/api/v1/vehicles/{vehicle}/commands", json=command)
    assert response.json()["outcome"]["status"] == "accepted", response.text


def _seconds(text: str) -> int:
    parts = [int(part) for part in text.split(":")]
    return sum(part * 60**power for power, part in enumerate(reversed(parts)))


@pytest.mark.parametrize("size", list(SIZES))
def test_the_event_filter_offers_every_vehicle_and_the_link_ups_before_the_page(
    browser: Browser, truths_fleet: LocalFleet, size: str
) -> None:
    with checked_page(browser, *SIZES[size]) as page:
        _open(page, truths_fleet, size)
        feed = page.locator('[data-feed="live"]')
        options = feed.locator('[data-field="event-vehicle-filter"] option')
        expect(options).to_have_text(["All vehicles", *VEHICLES])
        for vehicle in VEHICLES:
            link_up = feed.locator(f'li[data-kind="link_up"][data-vehicle-id="{vehicle}"]')
            expect(link_up.first).to_contain_text("agent connected")
        page.screenshot(path=f"/tmp/truths-shots/events-{size}.png")


def test_in_flight_counts_from_the_take_off_across_a_reload(
    browser: Browser, truths_fleet: LocalFleet, api: httpx.Client
) -> None:
    vehicle = VEHICLES[0]
    with checked_page(browser, *SIZES["desktop"]) as page:
        _open(page, truths_fleet, "desktop")
        page.locator(f'tr[data-vehicle-id="{vehicle}"] td[data-field="mode"]').click()
        in_flight = page.locator('[data-field="selected-flight-time"]')
        expect(in_flight).to_have_text("on ground", timeout=30_000)
        _command(api, vehicle, name="set_mode", mode="GUIDED")
        _command(api, vehicle, name="arm")
        _command(api, vehicle, name="takeoff", altitude=10)
        try:
            took_off = poll_until(
                lambda: api.get(f"/api/v1/vehicles/{vehicle}").json()["airborne_since"],
                30,
                f"{vehicle}'s take-off time",
            )
            # Long enough in the air that a clock restarted by the reload would show it.
            expect(in_flight).to_have_text(re.compile(r"^0:(0[6-9]|[1-5]\d)$"), timeout=30_000)
            page.reload()  # the session outlives it: no login form
            _open(page, truths_fleet, "desktop", logged_in=True)
            page.locator(f'tr[data-vehicle-id="{vehicle}"] td[data-field="mode"]').click()
            expect(in_flight).to_have_text(re.compile(r"^\d+:\d\d$"))
            shown = _seconds(in_flight.inner_text())
            assert abs(shown - (time.time() - took_off)) <= 2, (shown, time.time() - took_off)
            page.screenshot(path="/tmp/truths-shots/in-flight-desktop.png")
        finally:
            _command(api, vehicle, name="land")  # the module's fleet ends after this test
