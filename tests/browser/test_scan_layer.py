"""The selected vehicle's LIDAR scan on the dashboard's map, and the obstacles' outlines,
in headless Chromium against a real hub, simulator (with its LIDAR) and agent."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from playwright.sync_api import Page, expect

from gcs.launcher import LocalFleet
from tests.browser.conftest import log_in
from tests.helpers import running_fleet

pytestmark = [pytest.mark.browser, pytest.mark.integration]


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
