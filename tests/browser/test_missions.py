"""The mission editor, QGroundControl .plan files and "fly here", in headless Chromium
against the real fleet (hub, simulators, agents)."""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import jsonschema_rs
import pytest
from playwright.sync_api import Browser, FloatRect, Page, expect

from common.geodesy import LocalFrame, haversine_m
from gcs.launcher import LocalFleet
from tests.browser.conftest import log_in
from tests.helpers import api_client, poll_until

pytestmark = [pytest.mark.browser, pytest.mark.integration]

DATA = Path(__file__).parent.parent / "data" / "qgc"
MISSION_VEHICLE = "sim_3"
GOTO_VEHICLE = "sim_1"
CHECK_S = 15  # the editor checks 0.4 s after an edit; the hub answers at once


@pytest.fixture
def wide_page(browser: Browser) -> Iterator[Page]:
    """1920 by 1080: room for the mission panel beside the drawing."""
    context = browser.new_context(viewport={"width": 1920, "height": 1080}, accept_downloads=True)
    opened = context.new_page()
    errors: list[str] = []
    opened.on("pageerror", lambda error: errors.append(str(error)))
    yield opened
    context.close()
    assert errors == [], f"JavaScript errors on the page: {errors}"


@pytest.fixture
def api(fleet: LocalFleet, fleet_admin_token: str) -> Iterator[httpx.Client]:
    with api_client(fleet.plan.hub_http, fleet_admin_token) as client:
        yield client


def _states(api: httpx.Client) -> dict[str, dict[str, Any]]:
    return {v["id"]: v["state"] or {} for v in api.get("/api/v1/vehicles").json()}


class PixelMap:
    """Map pixels from lat/lon, measured from two vehicles' markers (Web Mercator is
    locally linear: a degree of latitude is sec(lat) times a degree of longitude)."""

    def __init__(self, page: Page, api: httpx.Client, a: str, b: str) -> None:
        def centres() -> dict[str, tuple[float, float]]:
            found = {}
            for vid in (a, b):
                box = page.locator(f'.vehicle-marker[data-vehicle-id="{vid}"]').bounding_box()
                assert box is not None
                found[vid] = (box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
            return found

        # Wait for the map to stop moving (a pan or zoom animates).
        last: list[dict[str, tuple[float, float]]] = [centres()]

        def settled() -> bool:
            now = centres()
            same = now == last[0]
            last[0] = now
            return same

        poll_until(settled, 10, "the map to settle", every_s=0.3)
        states = _states(api)
        (xa, ya), (xb, _) = last[0][a], last[0][b]
        self.lat0, self.lon0 = states[a]["lat"], states[a]["lon"]
        self.x0, self.y0 = xa, ya
        self.per_lon = (xb - xa) / (states[b]["lon"] - self.lon0)
        self.per_lat = -self.per_lon / math.cos(math.radians(self.lat0))

    def pixel(self, lat: float, lon: float) -> tuple[float, float]:
        return (
            self.x0 + (lon - self.lon0) * self.per_lon,
            self.y0 + (lat - self.lat0) * self.per_lat,
        )


def _open_panel(page: Page, vehicle: str) -> None:
    page.locator(f'tr[data-vehicle-id="{vehicle}"]').first.click()
    page.locator('[data-action="mission-toggle"]').click()
    expect(page.locator('[data-field="mission-vehicle"]')).to_contain_text(vehicle)


def test_a_qgc_plan_opens_and_a_saved_plan_is_qgcs_format(
    wide_page: Page, fleet: LocalFleet
) -> None:
    page = wide_page
    log_in(page, fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
    _open_panel(page, MISSION_VEHICLE)

    source = json.loads((DATA / "simple_square.plan").read_text())
    page.locator('[data-field="mission-file"]').set_input_files(DATA / "simple_square.plan")
    rows = page.locator(".mission-row")
    expect(rows).to_have_count(5)
    expect(rows.nth(0)).to_have_attribute("data-command", "22")
    expect(rows.nth(0).locator('[data-field="frame"]')).to_have_text("m above home")
    expect(page.locator(".mission-item")).to_have_count(5)  # the take-off and four waypoints

    with page.expect_download() as download_info:
        page.locator('[data-action="mission-save"]').click()
    saved = json.loads(Path(download_info.value.path()).read_text())
    schema = json.loads((DATA / "plan.schema.json").read_text())
    errors = [e.message for e in jsonschema_rs.validator_for(schema).iter_errors(saved)]
    assert errors == []
    # The same MAVLink items, NaN (null) parameters sent as 0 as MAVLink does.
    for mine, theirs in zip(saved["mission"]["items"], source["mission"]["items"], strict=True):
        assert (mine["command"], mine["frame"], mine["autoContinue"]) == (
            theirs["command"],
            theirs["frame"],
            theirs["autoContinue"],
        )
        assert mine["params"] == pytest.approx([p or 0 for p in theirs["params"]])

    # Uploaded to a group: each vehicle is checked and answers for itself.
    page.locator('[data-field="mission-targets"]').select_option(["sim_2", MISSION_VEHICLE])
    page.locator('[data-action="mission-upload"]').click()
    status = page.locator('[data-field="mission-status"]')
    expect(status).to_contain_text(re.compile(r"^sim_2: .+\nsim_3: .+$"), timeout=30_000)

    # A file that is not a plan is refused with the field named, and the plan stays.
    # Handed over as bytes: a file on disk removed right after set_input_files could be
    # gone before the page reads it (NotFoundError under load).
    bad = b'{"fileType": "Plan", "version": 1, "mission": {"version": 2, "items": 3}}'
    page.locator('[data-field="mission-file"]').set_input_files(
        {"name": "not-a-plan.json", "mimeType": "application/json", "buffer": bad}
    )
    expect(page.locator('[data-field="mission-status"]')).to_contain_text("mission.items")
    expect(rows).to_have_count(5)


def _box(page: Page, selector: str) -> FloatRect:
    box = page.locator(selector).first.bounding_box()
    assert box is not None, f"{selector} is not on the page"
    return box


def _pan_clear_of_panel(page: Page, vehicle: str) -> None:
    """Drag the map so that the vehicle sits midway between the map's left edge and
    the mission panel, low in the map: the panel floats over the map's top right and
    grows downwards as items are added, and the map is only a column of the dashboard,
    so the drawing (some 240 px wide, 160 px above and 80 px below the vehicle at this
    zoom) must lie wholly to the left of the panel."""
    marker_at = f'.vehicle-marker[data-vehicle-id="{vehicle}"]'
    # Leaflet ignores a drag begun while it animates a zoom or pan: wait for it to end.
    last = [_box(page, marker_at)]

    def settled() -> bool:
        now = _box(page, marker_at)
        same = now == last[0]
        last[0] = now
        return same

    poll_until(settled, 10, "the map to settle", every_s=0.3)
    area, panel, marker = _box(page, "#map"), _box(page, ".mission-panel"), last[0]
    here = (marker["x"] + marker["width"] / 2, marker["y"] + marker["height"] / 2)
    there = ((area["x"] + panel["x"]) / 2, area["y"] + area["height"] * 0.65)
    # Grab the map well below the vehicles, where there is nothing but map.
    start = (area["x"] + area["width"] / 2, area["y"] + area["height"] * 0.85)
    page.mouse.move(*start)
    page.mouse.down()
    page.mouse.move(start[0] + there[0] - here[0], start[1] + there[1] - here[1], steps=15)
    page.mouse.up()


def _assert_on_open_map(page: Page, x: float, y: float) -> None:
    """A point to click or drag on the map: on the map, not under a panel or control."""
    hit = page.evaluate(
        """([x, y]) => {
            const element = document.elementFromPoint(x, y);
            if (element === null) return "nothing";
            if (element.closest(".mission-panel, .leaflet-control")) return "a panel";
            return element.closest("#map") ? "map" : element.tagName;
        }""",
        [x, y],
    )
    assert hit == "map", f"({x:.0f}, {y:.0f}) is on {hit}, not the open map"


def _u_fence(frame: LocalFrame) -> list[dict[str, float]]:
    """A U open to the north around the vehicle: a notch 20 m wide from 20 m north."""
    corners = [(-60, -40), (60, -40), (60, 80), (10, 80), (10, 20), (-10, 20), (-10, 80), (-60, 80)]
    return [dict(zip(("lat", "lon"), frame.to_geo(e, n), strict=True)) for e, n in corners]


def test_a_drawn_mission_is_refused_on_its_leg_fixed_by_dragging_and_flown(
    wide_page: Page, fleet: LocalFleet, api: httpx.Client, tmp_path: Path
) -> None:
    page = wide_page
    here = _states(api)[MISSION_VEHICLE]
    frame = LocalFrame(here["lat"], here["lon"], 0.0)
    site_rails = api.get("/api/v1/safety/rails").json()
    fenced = {**site_rails, "geofence": {"polygon": _u_fence(frame)}}
    assert api.put("/api/v1/safety/rails", json=fenced).status_code == 200
    try:
        log_in(page, fleet.plan.hub_http, "admin", fleet.plan.admin_password)
        expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
        _open_panel(page, MISSION_VEHICLE)
        # Zoomed out so that the whole U fits beside the panel.
        zoom_out = page.locator(".leaflet-control-zoom-out")
        zoom_out.click()
        zoom_out.click()
        _pan_clear_of_panel(page, MISSION_VEHICLE)
        pixels = PixelMap(page, api, GOTO_VEHICLE, MISSION_VEHICLE)

        def at(east: float, north: float) -> tuple[float, float]:
            x, y = pixels.pixel(*frame.to_geo(east, north))
            _assert_on_open_map(page, x, y)
            return x, y

        # Draw: a take-off (added by Edit), a waypoint in each arm of the U, then RTL.
        page.locator('[data-action="mission-edit"]').click()
        page.mouse.click(*at(-40, 60))
        page.mouse.click(*at(40, 60))
        page.locator('[data-action="mission-add-20"]').click()
        rows = page.locator(".mission-row")
        expect(rows).to_have_count(4)
        expect(rows.nth(1)).to_have_attribute("data-command", "16")

        # Refused on the leg into item 3, which crosses the notch, with the rule named.
        refused = page.locator('.mission-row[data-seq="3"] [data-field="refusal"]')
        expect(refused).to_contain_text(
            "geofence: the leg from item 2 to item 3 leaves the geofence", timeout=CHECK_S * 1000
        )
        expect(page.locator('.mission-violation[data-rule="geofence"]')).to_have_count(1)
        expect(page.locator('.mission-item.refused[data-seq="3"]')).to_have_count(1)
        expect(page.locator('.mission-leg.refused[data-seq="3"]')).to_have_count(1)
        page.screenshot(path=str(tmp_path / "mission-refused.png"))

        # The go-to check speaks for the same fence: into the notch is refused.
        notch = frame.to_geo(0, 50)
        checked = api.post(
            f"/api/v1/vehicles/{MISSION_VEHICLE}/goto-check",
            json={"lat": notch[0], "lon": notch[1], "altitude": 10},
        ).json()
        assert checked["ok"] is False
        assert [v["rule"] for v in checked["violations"]] == ["geofence"]
        assert checked["distance_m"] == pytest.approx(50, abs=2)

        # Fixed by dragging item 3 into the west arm.
        page.mouse.move(*at(40, 60))
        page.mouse.down()
        page.mouse.move(*at(-45, 5), steps=12)
        page.mouse.up()
        expect(page.locator('[data-field="mission-verdict"]')).to_contain_text(
            "Rails: OK", timeout=CHECK_S * 1000
        )
        expect(page.locator(".mission-row.refused")).to_have_count(0)
        moved = rows.nth(2)
        lat, lon = (
            float(moved.get_attribute("data-lat") or 0),
            float(moved.get_attribute("data-lon") or 0),
        )
        assert haversine_m(lat, lon, *frame.to_geo(-45, 5)) < 5

        page.locator('[data-action="mission-upload"]').click()
        expect(page.locator('[data-field="mission-status"]')).to_contain_text(
            f"{MISSION_VEHICLE}: uploaded (4 items)", timeout=30_000
        )
        on_board = api.get(f"/api/v1/vehicles/{MISSION_VEHICLE}/mission").json()["items"][1:]
        assert [item["command"] for item in on_board] == [22, 16, 16, 20]

        commands = f"/api/v1/vehicles/{MISSION_VEHICLE}/commands"
        assert api.post(commands, json={"name": "set_mode", "mode": "GUIDED"}).status_code == 200
        armed = api.post(commands, json={"name": "arm"}).json()
        assert armed["outcome"]["status"] == "accepted", armed
        auto = api.post(commands, json={"name": "set_mode", "mode": "AUTO"}).json()
        assert auto["outcome"]["status"] == "accepted", auto

        # The active item moves along the path on the map, the flown legs dimmed behind it.
        for seq in (2, 3):
            expect(page.locator(f'.mission-item.active[data-seq="{seq}"]')).to_have_count(
                1, timeout=90_000
            )
        expect(page.locator('.mission-item.flown[data-seq="1"]')).to_have_count(1)
        expect(page.locator('.mission-leg.flown[data-seq="2"]')).to_have_count(1)
        expect(page.locator('.mission-row.active[data-seq="3"]')).to_have_count(1)
        page.screenshot(path=str(tmp_path / "mission-flown.png"))
        poll_until(
            lambda: not _states(api)[MISSION_VEHICLE]["armed"], 120, "the mission to end landed"
        )
    finally:
        assert api.put("/api/v1/safety/rails", json=site_rails).status_code == 200


def test_fly_here_moves_the_vehicle(wide_page: Page, fleet: LocalFleet, api: httpx.Client) -> None:
    page = wide_page
    commands = f"/api/v1/vehicles/{GOTO_VEHICLE}/commands"
    poll_until(lambda: _states(api)[GOTO_VEHICLE].get("ready_to_fly"), 60, "ready to fly")
    assert api.post(commands, json={"name": "set_mode", "mode": "GUIDED"}).status_code == 200
    assert api.post(commands, json={"name": "arm"}).json()["outcome"]["status"] == "accepted"
    takeoff = api.post(commands, json={"name": "takeoff", "altitude": 10}).json()
    assert takeoff["outcome"]["status"] == "accepted", takeoff
    poll_until(lambda: (_states(api)[GOTO_VEHICLE].get("alt_rel") or 0) > 6, 60, "the climb")

    log_in(page, fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
    page.locator(f'tr[data-vehicle-id="{GOTO_VEHICLE}"]').first.click()
    pixels = PixelMap(page, api, GOTO_VEHICLE, MISSION_VEHICLE)
    start = _states(api)[GOTO_VEHICLE]
    target = LocalFrame(start["lat"], start["lon"], 0.0).to_geo(0, 40)

    page.mouse.click(*pixels.pixel(*target), button="right")
    verdict = page.locator('[data-field="go-here-verdict"]')
    expect(verdict).to_contain_text("rails: OK", timeout=CHECK_S * 1000)
    distance = float(verdict.inner_text().split(" m away")[0])
    assert distance == pytest.approx(40, abs=4)
    confirm = page.locator('[data-action="go-here-confirm"]')
    expect(confirm).to_have_text("Fly here at 10 m")
    confirm.click()
    expect(page.locator('[data-field="go-here-result"]')).to_contain_text("accepted")
    poll_until(
        lambda: (
            haversine_m(
                _states(api)[GOTO_VEHICLE]["lat"], _states(api)[GOTO_VEHICLE]["lon"], *target
            )
            < 4
        ),
        90,
        f"{GOTO_VEHICLE} at the clicked point",
    )
    api.post(commands, json={"name": "land"})
