""" "Start mission" in the mission panel, in headless Chromium against the package's fleet
(conftest.py): a mission the vehicle's rails refuse stops at the check with the rule
named, and nothing is sent (each screen size); a mission they pass is checked, armed in
GUIDED, taken off to its take-off item's height, flown in AUTO and ends landed (the
desktop). Screenshots of the step list go to test-output/missions/ (start-mission-*)."""

from __future__ import annotations

from typing import Any

import httpx
from playwright.sync_api import Page, expect

from common.geodesy import LocalFrame
from gcs.launcher import LocalFleet
from tests.browser.conftest import log_in
from tests.support.mission_editor import expand_panel, select, shot, vehicle_states
from tests.support.waiting import poll_until

VEHICLE = "sim_2"
TAKEOFF_M = 12


def _upload_a_mission(api: httpx.Client) -> None:
    """A take-off to 12 m, a waypoint 30 m north at 15 m, and RTL (MAV_CMD 22, 16, 20)."""
    here = vehicle_states(api)[VEHICLE]
    north = LocalFrame(here["lat"], here["lon"], 0.0).to_geo(0, 30)

    def item(command: int, lat: float, lon: float, alt: float) -> dict[str, Any]:
        return {
            "command": command,
            "frame": 3,
            "param1": 0,
            "param2": 0,
            "param3": 0,
            "param4": None,
            "lat": lat,
            "lon": lon,
            "alt": alt,
            "autocontinue": True,
        }

    items = [item(22, here["lat"], here["lon"], TAKEOFF_M), item(16, *north, 15), item(20, 0, 0, 0)]
    answer = api.post(f"/api/v1/vehicles/{VEHICLE}/mission", json={"items": items})
    assert answer.status_code == 200, answer.text


def _open(page: Page, size: str, fleet: LocalFleet) -> None:
    log_in(page, fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
    select(page, size, VEHICLE)
    expand_panel(page)


def test_start_mission_stops_at_the_first_refusal_with_its_reason(
    sized_page: tuple[Page, str], mission_fleet: LocalFleet, api: httpx.Client
) -> None:
    page, size = sized_page
    poll_until(lambda: not vehicle_states(api)[VEHICLE]["armed"], 120, f"{VEHICLE} on the ground")
    _upload_a_mission(api)
    rails = f"/api/v1/vehicles/{VEHICLE}/safety-rails"
    assert api.put(rails, json={"max_altitude_m": 10}).status_code == 200
    try:
        _open(page, size, mission_fleet)
        page.locator('[data-action="mission-start"]').click()
        steps = page.locator('[data-field="start-steps"] li')
        check = page.locator('[data-step="check"]')
        expect(check).to_have_attribute("data-state", "refused", timeout=30_000)
        expect(check).to_contain_text("max_altitude")
        expect(steps).to_have_count(1)  # nothing after the refusal
        text = check.locator(".mission-start-text")
        # The reason is whole on the screen: not cut, not scrolled out of its row.
        assert text.evaluate("(e) => e.scrollWidth <= e.clientWidth + 1")
        check.scroll_into_view_if_needed()
        shot(page, "start-mission-refused", size)
        assert not vehicle_states(api)[VEHICLE]["armed"]
    finally:
        assert api.delete(rails).status_code in (200, 204)


def test_start_mission_checks_arms_takes_off_and_flies_it(
    wide_page: Page, mission_fleet: LocalFleet, api: httpx.Client
) -> None:
    page = wide_page
    poll_until(lambda: vehicle_states(api)[VEHICLE].get("ready_to_fly"), 120, "ready to fly")
    _upload_a_mission(api)
    _open(page, "desktop", mission_fleet)
    page.locator('[data-action="mission-start"]').click()
    mission = page.locator('[data-step="mission"]')
    expect(mission).to_have_attribute("data-state", "ok", timeout=120_000)
    steps = page.locator('[data-field="start-steps"] li')
    assert steps.evaluate_all("(rows) => rows.map((r) => r.dataset.step)") == [
        "check",
        "mode",
        "arm",
        "takeoff",
        "climb",
        "mission",
    ]
    expect(page.locator('[data-field="start-steps"] li[data-state="ok"]')).to_have_count(6)
    expect(page.locator('[data-step="check"]')).to_contain_text(
        f"take-off to {TAKEOFF_M} m (item 1)"
    )
    expect(page.locator('[data-step="climb"]')).to_contain_text("airborne at")
    page.locator('[data-step="mission"]').scroll_into_view_if_needed()
    shot(page, "start-mission-flown", "desktop")
    # AUTO flies the whole mission, its RTL item too: the mode stays until it has landed.
    assert vehicle_states(api)[VEHICLE]["mode"] == "AUTO"
    # The mission runs to its RTL and lands.
    poll_until(lambda: not vehicle_states(api)[VEHICLE]["armed"], 180, "the mission to end landed")
