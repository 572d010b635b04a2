"""The Flights replay in headless Chromium: a real flight of sim_3 is flown through the
REST API, stored by the hub, then picked in the dashboard and replayed."""

from __future__ import annotations

import re
import time
from typing import Any

import pytest
from playwright.sync_api import Page, expect

from gcs.launcher import LocalFleet
from tests.browser.conftest import log_in
from tests.support.api import api_client
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher

pytestmark = [pytest.mark.browser, pytest.mark.integration]

# Only this test flies sim_3; the other browser tests use sim_1 and sim_2.
VEHICLE = "sim_3"
TAKEOFF_ALTITUDE = 6.0
# About 20 m north-east of where it took off, so the replay marker really moves.
HOP_DEGREES = 0.00015

MARKER_POSITION = """() => {
    const marker = document.querySelector('.replay-marker');
    return marker ? `${marker.dataset.lat},${marker.dataset.lon}` : null;
}"""


def _state(vehicles: dict[str, dict[str, Any]]) -> dict[str, Any]:
    return vehicles.get(VEHICLE, {}).get("state") or {}


def _command(api: Any, payload: dict[str, Any]) -> None:
    response = api.post(f"/api/v1/vehicles/{VEHICLE}/commands", json=payload)
    assert response.status_code == 200, response.text
    outcome = response.json()["outcome"]
    assert outcome["status"] == "accepted", outcome


@pytest.fixture(scope="module")
def stored_flight(fleet: LocalFleet, fleet_admin_token: str) -> dict[str, Any]:
    """Takes sim_3 off, hops it a few metres, lands it; returns the hub's closed flight."""
    base = fleet.plan.hub_http
    with api_client(base, fleet_admin_token) as api, FleetWatcher(base, fleet_admin_token) as watch:
        watch.wait_until(
            lambda v: (
                _state(v).get("gps_fix", 0) >= 3
                and _state(v).get("lat") is not None
                and not _state(v).get("armed")
            ),
            60,
            f"{VEHICLE} on the ground with a GPS fix",
        )
        home = _state(watch.vehicles)
        flown_from = time.time()
        _command(api, {"name": "takeoff", "altitude": TAKEOFF_ALTITUDE})
        watch.wait_until(
            lambda v: (_state(v).get("alt_rel") or 0) >= TAKEOFF_ALTITUDE - 1.0,
            90,
            f"{VEHICLE} to climb to {TAKEOFF_ALTITUDE} m",
        )
        target = (home["lat"] + HOP_DEGREES, home["lon"] + HOP_DEGREES)
        _command(
            api,
            {"name": "goto", "lat": target[0], "lon": target[1], "altitude": TAKEOFF_ALTITUDE},
        )
        watch.wait_until(
            lambda v: (
                abs(_state(v).get("lat", 0) - target[0]) < HOP_DEGREES / 4
                and abs(_state(v).get("lon", 0) - target[1]) < HOP_DEGREES / 4
            ),
            90,
            f"{VEHICLE} to reach the hop's target",
        )
        _command(api, {"name": "land"})
        watch.wait_until(
            lambda v: _state(v).get("armed") is False, 120, f"{VEHICLE} to land and disarm"
        )

        # The hub's writer closes the flight when it stores the disarmed sample.
        def closed() -> list[dict[str, Any]]:
            response = api.get("/api/v1/flights", params={"vehicle_id": VEHICLE, "limit": 5})
            assert response.status_code == 200, response.text
            return [
                flight
                for flight in response.json()["flights"]
                if flight["end_time"] is not None and flight["start_time"] >= flown_from - 5
            ]

        return poll_until(closed, 30, f"a closed flight of {VEHICLE}", every_s=0.25)[0]


def test_a_stored_flight_replays_on_the_map(
    page: Page, fleet: LocalFleet, stored_flight: dict[str, Any]
) -> None:
    flight_id = stored_flight["id"]
    log_in(page, fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)

    # Flights mode: the panel replaces the fleet table, live markers stay but fade.
    page.locator('button[data-action="show-flights"]').click()
    panel = page.locator("#replay-panel")
    expect(panel).to_be_visible()
    expect(page.locator("#map")).to_have_class(re.compile(r"\breplaying\b"))
    expect(page.locator(".vehicle-marker")).to_have_count(3)

    # Only sim_3's flights once filtered; ours is among them.
    vehicle_filter = panel.locator('input[data-field="flight-vehicle"]')
    vehicle_filter.fill(VEHICLE)
    vehicle_filter.press("Enter")
    row = panel.locator(f'tr[data-flight-id="{flight_id}"]')
    expect(row).to_be_visible(timeout=10_000)
    expect(row.locator('[data-field="vehicle"]')).to_have_text(VEHICLE)
    expect(row.locator('[data-field="duration"]')).to_have_text(re.compile(r"^\d\d:\d\d:\d\d$"))
    for cell in panel.locator('tr[data-flight-id] [data-field="vehicle"]').all():
        expect(cell).to_have_text(VEHICLE)

    row.click()
    expect(row).to_have_class(re.compile(r"\bselected\b"))
    expect(panel.locator('.replay[data-state="ready"]')).to_be_visible(timeout=15_000)
    expect(panel).to_have_attribute("data-flight-id", str(flight_id))

    # The track, the event markers (armed, mode, disarmed), the replay marker, the charts.
    expect(page.locator("#map path.replay-track")).to_have_count(1)
    expect(page.locator("#map .event-marker").first).to_be_attached()
    expect(page.locator("#map .replay-marker")).to_have_count(1)
    expect(panel.locator(".replay-chart .uplot")).to_have_count(3)
    expect(panel.locator(".replay-chart canvas")).to_have_count(3)
    expect(panel.locator('[data-field="replay-time"]')).to_have_text(
        re.compile(r"^00:00:00 / \d\d:\d\d:\d\d$")
    )
    expect(panel.locator('[data-field="replay-alt"]')).to_have_text(re.compile(r"m$"))

    # The export links point at this flight, and the session cookie is enough to fetch one.
    csv_link = panel.locator('a[data-action="export-csv"]')
    href = csv_link.get_attribute("href") or ""
    assert href.endswith(f"/api/v1/flights/{flight_id}/export.csv"), href
    for kind in ("geojson", "tlog"):
        other = panel.locator(f'a[data-action="export-{kind}"]').get_attribute("href") or ""
        assert other.endswith(f"/api/v1/flights/{flight_id}/export.{kind}"), other
    download = page.request.get(href)
    assert download.status == 200, download.text()[:500]
    assert download.text().count("\n") > 2

    scrubber = panel.locator('input[data-field="replay-scrubber"]')
    play = panel.locator('button[data-action="replay-play"]')
    start_position = page.evaluate(MARKER_POSITION)
    assert start_position
    assert "undefined" not in start_position
    assert float(scrubber.input_value()) == 0
    duration = float(scrubber.get_attribute("max") or 0)
    assert duration > 1, f"the flight lasted {duration} s"

    # Play at 1x: the button reads Pause, the scrubber advances; pause stops it.
    expect(play).to_have_text("Play")
    play.click()
    expect(play).to_have_text("Pause")
    page.wait_for_function(
        """() => {
            const scrubber = document.querySelector('input[data-field="replay-scrubber"]');
            return parseFloat(scrubber.value) > 0.2;
        }""",
        timeout=10_000,
    )
    play.click()
    expect(play).to_have_text("Play")

    # Then at 30x to the end: the marker has moved along the track to where it landed.
    panel.locator('select[data-field="replay-speed"]').select_option("30")
    play.click()
    page.wait_for_function(
        """([start, duration]) => {
            const marker = document.querySelector('.replay-marker');
            const scrubber = document.querySelector('input[data-field="replay-scrubber"]');
            const position = marker ? `${marker.dataset.lat},${marker.dataset.lon}` : null;
            return position !== null && position !== start
                && parseFloat(scrubber.value) >= duration - 0.5;
        }""",
        arg=[start_position, duration],
        timeout=int(duration / 30 * 1000) + 15_000,
    )
    expect(play).to_have_text("Play")  # stopped at the end
    assert page.evaluate(MARKER_POSITION) != start_position
    expect(panel.locator('[data-field="replay-time"]')).not_to_have_text(re.compile(r"^00:00:00 /"))
    # The live feed's view plays back with it: at the end, the whole flight's events,
    # the landing's disarm among them.
    feed = panel.locator('[data-feed="replay"]')
    expect(feed.locator('li[data-kind="disarmed"]')).to_have_count(1)
    expect(feed.locator('li[data-kind="armed"]')).to_have_count(1)
    at_end = feed.locator("li").count()

    # Scrubbing back to the start puts the marker back where it took off.
    # (Playwright cannot fill a range input: set it as a drag would, with an input event.)
    scrubber.evaluate(
        """(input) => {
            input.value = '0';
            input.dispatchEvent(new Event('input', { bubbles: true }));
        }"""
    )
    expect(panel.locator('[data-field="replay-time"]')).to_have_text(re.compile(r"^00:00:00 /"))
    assert page.evaluate(MARKER_POSITION) == start_position
    # Back at the start, what had not happened yet is gone from the feed: the disarm.
    expect(feed.locator('li[data-kind="disarmed"]')).to_have_count(0)
    assert feed.locator("li").count() < at_end

    # Leaving the replay restores the live view.
    page.locator('button[data-action="close-flights"]').click()
    expect(panel).to_be_hidden()
    expect(page.locator("#map")).not_to_have_class(re.compile(r"\breplaying\b"))
    expect(page.locator("#map .replay-marker")).to_have_count(0)
    expect(page.locator("#map path.replay-track")).to_have_count(0)
    expect(page.locator("tr[data-vehicle-id]")).to_have_count(3)
    expect(page.locator(f'tr[data-vehicle-id="{VEHICLE}"]')).to_be_visible()
