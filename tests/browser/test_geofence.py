"""The geofence on the map, in headless Chromium: the selected vehicle's fence is drawn
where its rails put it, and the site's (none here) when nothing is selected."""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import Any

import pytest
from playwright.sync_api import Page, expect

from gcs.launcher import LocalFleet
from tests.browser.conftest import log_in
from tests.support.api import api_client
from tests.support.watcher import FleetWatcher

pytestmark = [pytest.mark.browser, pytest.mark.integration]

VEHICLE = "sim_2"
# A fence about 40 m across around the vehicle: inside the view when the map fits the
# fleet, so Leaflet does not clip it (a clipped outline gains the view's corners).
HALF_SIDE_DEG = 0.0002


@pytest.fixture
def fenced(fleet: LocalFleet, fleet_admin_token: str) -> Iterator[list[dict[str, float]]]:
    """A fence of the vehicle's own around where it stands, taken off again afterwards
    (the suite's other tests fly this vehicle under the site's rails)."""
    base = fleet.plan.hub_http
    with FleetWatcher(base, fleet_admin_token) as watcher:
        watcher.wait_until(
            lambda v: (v.get(VEHICLE, {}).get("state") or {}).get("lat") is not None,
            60,
            f"{VEHICLE}'s position",
        )
        state: dict[str, Any] = watcher.state(VEHICLE)
    lat, lon = state["lat"], state["lon"]
    polygon = [
        {"lat": lat - HALF_SIDE_DEG, "lon": lon - HALF_SIDE_DEG},
        {"lat": lat - HALF_SIDE_DEG, "lon": lon + HALF_SIDE_DEG},
        {"lat": lat + HALF_SIDE_DEG, "lon": lon + HALF_SIDE_DEG},
        {"lat": lat + HALF_SIDE_DEG, "lon": lon - HALF_SIDE_DEG},
    ]
    rails = {"geofence": {"polygon": polygon, "max_altitude_m": 60}}
    with api_client(base, fleet_admin_token) as api:
        answer = api.put(f"/api/v1/vehicles/{VEHICLE}/safety-rails", json=rails)
        assert answer.status_code == 200, answer.text
        try:
            yield polygon
        finally:
            cleared = api.delete(f"/api/v1/vehicles/{VEHICLE}/safety-rails")
            assert cleared.status_code in (200, 204), cleared.text


def test_the_selected_vehicles_geofence_is_drawn(
    page: Page, fleet: LocalFleet, fenced: list[dict[str, float]]
) -> None:
    log_in(page, fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    expect(page.locator("tr[data-vehicle-id]")).to_have_count(3, timeout=30_000)
    fence = page.locator("#map path.geofence")
    expect(fence).to_have_count(0)  # the site has no fence
    page.locator(f'tr[data-vehicle-id="{VEHICLE}"]').click()
    expect(fence).to_have_count(1, timeout=10_000)
    expect(page.locator(".geofence-label")).to_have_text(
        f"Geofence of {VEHICLE}, ceiling 60 m", timeout=10_000
    )
    # The outline has the rails' four corners (Leaflet writes "M x y L x y L x y L x y z").
    outline = fence.get_attribute("d") or ""
    assert len(re.findall(r"[ML]", outline)) == len(fenced), outline
