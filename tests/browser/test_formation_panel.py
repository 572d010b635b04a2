"""The dashboard's formation panel in headless Chromium against a real fleet (hub, three
simulators, three agents) in real time, as formations fly (the leader's states are
stamped and predicted on the wall clock): an operator picks the leader and the
followers, draws the leader's route with the mouse, is refused with the hub's reason,
starts it, watches it form, changes its spacing in flight and stops it. The screenshot
goes to test-output/formation/."""

from __future__ import annotations

import math
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from playwright.sync_api import Browser, Page, expect

from common.geodesy import LocalFrame
from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.browser.conftest import log_in
from tests.support.api import access_token, api_client
from tests.support.formations import take_off_all
from tests.support.hubs import TEST_HUB_ENV
from tests.support.maps import PixelMap, _assert_on_open_map
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher

pytestmark = [pytest.mark.browser, pytest.mark.integration, pytest.mark.slow]

ROOT = Path(__file__).resolve().parents[2]
OUTPUT = ROOT / "test-output" / "formation"
# Formed: the leader flies the route, or has flown it and the formation holds.
FORMED = re.compile(r"^(flying|route_done)$")
LEADER, FOLLOWERS = "sim_1", ["sim_2", "sim_3"]
# The followers below the leader, as in tests/integration/test_formation.py.
ALTITUDES = {LEADER: 8.0, "sim_2": 3.0, "sim_3": 2.0}
# The route heads west from just west of the leader (its marker would take the click);
# the column's slots are then east of the leader, towards the followers' homes (15 m
# apart, east of the leader's), so they join in a few metres.
ROUTE_M = [(-6.0, 0.0), (-26.0, 0.0)]  # east, north of the leader's home
SPACING_M = 8.0


@pytest.fixture(scope="module")
def airborne(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[LocalFleet, str]]:
    """The fleet in real time, every vehicle in GUIDED and at its altitude."""
    plan = FleetPlan(
        port=free_port(),
        data_dir=tmp_path_factory.mktemp("formation-ui"),
        vehicles=len(ALTITUDES),
        speedup=1.0,
    )
    with LocalFleet(plan) as fleet:
        fleet.start(
            hub_env={**TEST_HUB_ENV, "GCS_BASEMAP_URL": "", "GCS_COMMANDS_PER_SECOND": "1000"}
        )
        fleet.wait_until_ready()
        token = access_token(plan.hub_http, "admin", plan.admin_password)
        with FleetWatcher(plan.hub_http, token) as watcher, api_client(plan.hub_http, token) as api:
            take_off_all(watcher, api, ALTITUDES)
        yield fleet, token


def _stored(api: httpx.Client, formation_id: str) -> dict[str, Any]:
    stored = api.get("/api/v1/formations").json()["formations"]
    return next(f for f in stored if f["id"] == formation_id)


def _a_viewer_follows_it_read_only(
    browser: Browser, plan: FleetPlan, api: httpx.Client, formation_id: str
) -> None:
    """A dashboard opened while it flies follows it; a viewer's has no controls."""
    user = {"username": "vera", "password": "correct horse battery", "role": "viewer"}
    assert api.post("/api/v1/users", json=user).status_code in (200, 201)
    context = browser.new_context(viewport={"width": 1600, "height": 1000})
    try:
        page = context.new_page()
        log_in(page, plan.hub_http, user["username"], user["password"])
        page.locator('[data-action="formation-toggle"]').click()
        panel = page.locator(".formation-panel")
        progress = panel.locator('[data-field="formation-progress"]')
        expect(progress).to_have_attribute("data-formation-id", formation_id)
        expect(progress).to_have_attribute("data-state", FORMED)
        for action in ("formation-start", "formation-change", "formation-stop"):
            expect(panel.locator(f'[data-action="{action}"]')).to_be_hidden()
    finally:
        context.close()


# Each drawn slot's centre on the page, read at once: they move with every telemetry update.
SLOTS_JS = """() => Object.fromEntries([...document.querySelectorAll("path.formation-slot")]
    .map((path) => {
        const box = path.getBoundingClientRect();
        return [path.dataset.vehicleId, [box.x + box.width / 2, box.y + box.height / 2]];
    }))"""


def _assert_slots_on_followers(page: Page, pixels: PixelMap, api: httpx.Client) -> None:
    """Formed, each follower is within FORM_UP_M (0.5 m) of its slot: so the slot the
    panel draws round the leader (its position and heading) lies on the follower. A wrong
    frame or heading would put it metres away (the slots are 8 m apart behind the leader)."""
    slots: dict[str, list[float]] = page.evaluate(SLOTS_JS)
    states = {v["id"]: v["state"] for v in api.get("/api/v1/vehicles").json()}
    assert set(slots) == set(FOLLOWERS)
    tolerance_px = 2.0 / pixels.metres_per_px()  # they move on between the two looks
    for follower, (x, y) in slots.items():
        at = pixels.pixel(states[follower]["lat"], states[follower]["lon"])
        off_m = math.dist((x, y), at) * pixels.metres_per_px()
        assert math.dist((x, y), at) < tolerance_px, f"{follower}'s slot drawn {off_m:.1f} m off"


def test_an_operator_flies_a_formation_from_the_panel(
    browser: Browser, wide_page: Page, airborne: tuple[LocalFleet, str]
) -> None:
    page, (fleet, token) = wide_page, airborne
    plan = fleet.plan
    frame = LocalFrame(*plan.vehicle_home(0)[:2])
    log_in(page, plan.hub_http, "admin", plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(len(ALTITUDES), timeout=30_000)
    page.locator('[data-action="formation-toggle"]').click()

    # -- the members and the shape
    panel = page.locator(".formation-panel")
    panel.locator('[data-field="formation-leader"]').select_option(LEADER)
    for follower, up in zip(FOLLOWERS, (-5, -6), strict=True):
        row = panel.locator(f'.formation-follower[data-vehicle-id="{follower}"]')
        row.locator("input[type=checkbox]").check()
        row.locator("input[type=number]").fill(str(up))
    panel.locator('[data-field="formation-shape"]').select_option("column")
    panel.locator('[data-field="formation-altitude"]').fill(str(ALTITUDES[LEADER]))

    # -- the route, drawn with the mouse
    pixels = PixelMap(page)
    panel.locator('[data-action="formation-draw"]').click()
    for east, north in ROUTE_M:
        x, y = pixels.pixel(*frame.to_geo(east, north))
        _assert_on_open_map(page, x, y)
        page.mouse.click(x, y)
    expect(panel).to_have_attribute("data-route-points", str(len(ROUTE_M)))
    panel.locator('[data-action="formation-finish"]').click()
    expect(page.locator("path.formation-route-point")).to_have_count(len(ROUTE_M))

    # -- refused: slots closer than the minimum separation, in the hub's words
    status = panel.locator('[data-field="formation-status"]')
    panel.locator('[data-field="formation-spacing"]').fill("1")
    panel.locator('[data-action="formation-start"]').click()
    expect(status).to_contain_text("minimum separation is 2 m")
    expect(status).to_have_class("mission-status error")

    # -- started, then formed
    panel.locator('[data-field="formation-spacing"]').fill(str(SPACING_M))
    panel.locator('[data-action="formation-start"]').click()
    progress = panel.locator('[data-field="formation-progress"]')
    expect(progress).to_have_attribute("data-formation-id", re.compile("^formation-"))
    formation_id = progress.get_attribute("data-formation-id")
    assert formation_id
    with api_client(plan.hub_http, token) as api:
        stored = _stored(api, formation_id)
        assert stored["stopped"] is None
        assert stored["leader_id"] == LEADER
        assert [f["vehicle_id"] for f in stored["request"]["followers"]] == FOLLOWERS
        assert stored["request"]["shape"] == "column"
        assert stored["request"]["spacing_m"] == SPACING_M
        live = api.get(f"/api/v1/formations/{formation_id}").json()
        assert live["stopped"] is None
        assert set(live["slots"]) == set(FOLLOWERS)

        expect(progress).to_have_attribute("data-state", FORMED, timeout=40_000)
        # when the route ends, from the hub: no sum of formed_at and the route's length
        expect(progress.locator('[data-field="formation-route-end"]')).to_have_text(
            re.compile(r"^Route (ends|done) at \d\d:\d\d:\d\d$")
        )
        for follower in FOLLOWERS:
            expect(progress.locator(f'li[data-vehicle-id="{follower}"]')).to_contain_text(
                "m from its slot"
            )
        expect(page.locator("path.formation-slot")).to_have_count(len(FOLLOWERS))
        _assert_slots_on_followers(page, pixels, api)
        # closer, around the formation, for the screenshot (the view waits for the zoom)
        page.mouse.move(*pixels.pixel(*frame.to_geo(0.0, 0.0)))
        page.mouse.wheel(0, -120)
        PixelMap(page)
        OUTPUT.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(OUTPUT / "formed.png"))
        _a_viewer_follows_it_read_only(browser, plan, api, formation_id)

        # -- a new spacing in flight
        panel.locator('[data-field="formation-live-spacing"]').fill("6")
        panel.locator('[data-action="formation-change"]').click()
        expect(status).to_contain_text("New slots")
        poll_until(
            lambda: _stored(api, formation_id)["request"]["spacing_m"] == 6.0,
            10,
            "the new spacing stored",
        )

        # -- stopped
        panel.locator('[data-action="formation-stop"]').click()
        expect(progress).to_have_attribute("data-state", "stopped")
        expect(status).to_contain_text("stopped")
        poll_until(lambda: _stored(api, formation_id)["stopped"] is not None, 10, "the stop stored")
        stored = _stored(api, formation_id)
        assert stored["stop_reason"] == "stopped by the operator"
        assert stored["stopped_by"] == "admin"
    # the panel plans again once it stopped
    expect(panel.locator('[data-action="formation-start"]')).to_be_visible()
