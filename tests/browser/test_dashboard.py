"""The dashboard in headless Chromium against the real fleet."""

from __future__ import annotations

import re

import pytest
from playwright.sync_api import Page, expect

from gcs.launcher import LocalFleet
from tests.browser.conftest import log_in

pytestmark = [pytest.mark.browser, pytest.mark.integration]

VEHICLE = "sim_2"


def _altitude(page: Page) -> float:
    text = page.locator(f'tr[data-vehicle-id="{VEHICLE}"] [data-field="alt_rel"]').inner_text()
    match = re.search(r"-?\d+(\.\d+)?", text)
    return float(match.group()) if match else 0.0


def test_dashboard_shows_the_fleet_and_takes_off(page: Page, settled_fleet: LocalFleet) -> None:
    # settled_fleet: the take-off below is landed again after the test, for the tests
    # after it on the shared fleet (a surveys' check refuses a drone still in the air).
    fleet = settled_fleet
    log_in(page, fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
    expect(page.locator("tr[data-vehicle-id]")).to_have_count(3)
    row = page.locator(f'tr[data-vehicle-id="{VEHICLE}"]')
    expect(row.locator('[data-field="mode"]')).not_to_have_text("", timeout=10_000)
    expect(row.locator('[data-field="gps"]')).to_contain_text("3D")
    # a good fix is not enough: the autopilot's readiness (its EKF, its pre-arm checks)
    expect(row.locator('[data-field="armed"]')).to_have_text("disarmed · ready", timeout=30_000)
    # Whether it flies, as the autopilot says (EXTENDED_SYS_STATE), not guessed ("~").
    expect(row.locator('[data-field="landed_state"]')).to_have_text("on ground")
    start_altitude = _altitude(page)
    assert start_altitude < 1.0

    row.locator('input[data-field="takeoff-altitude"]').fill("8")
    row.locator('button[data-action="takeoff"]').click()
    expect(row.locator('[data-field="command-result"]')).to_contain_text("accepted", timeout=30_000)
    # The altitude cell climbs live as telemetry arrives over the WebSocket.
    page.wait_for_function(
        """(id) => {
            const row = document.querySelector(`tr[data-vehicle-id="${id}"]`);
            const cell = row && row.querySelector('[data-field="alt_rel"]');
            return parseFloat(cell ? cell.textContent : "") >= 3;
        }""",
        arg=VEHICLE,
        timeout=60_000,
    )
    assert _altitude(page) >= 3
    expect(row.locator('[data-field="landed_state"]')).to_have_text(
        re.compile("^(taking off|in air)$"), timeout=30_000
    )
    expect(row.locator('[data-field="armed"]')).to_contain_text(re.compile("armed", re.I))
