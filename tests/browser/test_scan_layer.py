"""The selected vehicle's LIDAR scan on the dashboard's map, the obstacles' outlines, and
the flight's scans in its replay, in headless Chromium against a real hub, simulator (with
its LIDAR) and agent."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from playwright.sync_api import Page, expect

from gcs.launcher import LocalFleet
from tests.browser.conftest import log_in
from tests.support.api import access_token, api_client
from tests.support.processes import running_fleet
from tests.support.waiting import poll_until

pytestmark = [pytest.mark.browser, pytest.mark.integration, pytest.mark.slow]


@pytest.fixture
def lidar_fleet(tmp_path: Path) -> Iterator[LocalFleet]:
    with running_fleet(tmp_path, vehicles=1, speedup=1.0, lidars=True) as fleet:
        yield fleet


def test_the_selected_vehicles_scan_and_the_obstacles_are_drawn(
    page: Page, lidar_fleet: LocalFleet
) -> None:
    vehicle = lidar_fleet.vehicle_id(0)
    log_in(page, lidar_fleet.plan.hub_http, "admin", lidar_fleet.plan.admin_password)
    row = page.locator(f'tr[data-vehicle-id="{vehicle}"]')
    expect(row.locator('[data-field="armed"]')).to_have_text("disarmed · ready", timeout=60_000)
    # Nothing is drawn for a vehicle nobody selected: the hub sends no scan unasked.
    assert page.locator("#map").get_attribute("data-scan-points") is None
    row.locator('input[data-field="takeoff-altitude"]').fill("3")
    row.locator('button[data-action="takeoff"]').click()
    expect(row.locator('[data-field="command-result"]')).to_contain_text("accepted", timeout=30_000)
    row.click()  # selects it: its scans are subscribed to and drawn
    page.wait_for_function(
        "() => Number(document.querySelector('#map').dataset.scanPoints || 0) > 300",
        timeout=30_000,
    )
    # Obstacles come from the hub's point map, above the ground: once it has flown up.
    page.wait_for_function(
        "() => Number(document.querySelector('#map').dataset.obstacles || 0) >= 3",
        timeout=30_000,
    )

    # Land: the flight is stored, and its replay draws the scan of the replayed instant.
    row.locator('button[data-action="land"]').click()
    token = access_token(lidar_fleet.plan.hub_http, "admin", lidar_fleet.plan.admin_password)
    with api_client(lidar_fleet.plan.hub_http, token) as api:

        def closed() -> list[dict[str, Any]]:
            params = {"vehicle_id": vehicle, "limit": 5}
            flights = api.get("/api/v1/flights", params=params).json()["flights"]
            return [f for f in flights if f["end_time"] is not None]

        flight = poll_until(closed, 60, "the flight closed")[0]
    page.locator('button[data-action="show-flights"]').click()
    panel = page.locator("#replay-panel")
    panel.locator(f'tr[data-flight-id="{flight["id"]}"]').click()
    expect(panel.locator('.replay[data-state="ready"]')).to_be_visible(timeout=15_000)
    page.evaluate(
        """() => {
            const scrubber = document.querySelector('input[data-field="replay-scrubber"]');
            scrubber.value = String(parseFloat(scrubber.max) / 2);  // mid-flight, in the air
            scrubber.dispatchEvent(new Event("input"));
        }"""
    )
    page.wait_for_function(
        "() => Number(document.querySelector('#map').dataset.replayScanPoints || 0) > 300",
        timeout=15_000,
    )
    # The flight's world points are among its exports, for CloudCompare or PDAL.
    points = panel.locator('a[data-action="export-ply"]').get_attribute("href") or ""
    assert points.endswith(f"/api/v1/flights/{flight['id']}/points.ply"), points
    ply = page.request.get(points)
    assert ply.status == 200, ply.text()[:500]
    assert ply.body().startswith(b"ply\n")
    page.locator('button[data-action="show-flights"]').click()  # back to the fleet
    page.wait_for_function("() => !('replayScanPoints' in document.querySelector('#map').dataset)")
