"""A mission drawn on the map and "fly here", in headless Chromium against the package's
fleet (conftest.py), whose base map is an offline MBTiles file made there. Both run at a
desktop, a tablet and a phone size, each saving its screenshots under
test-output/missions/; with GCS_UPDATE_SCREENSHOTS=1 the desktop run of the flown
mission also remakes the README's picture."""

from __future__ import annotations

import os
import re

import httpx
import pytest
from playwright.sync_api import FloatRect, Page, expect

from common.geodesy import LocalFrame, haversine_m
from gcs.launcher import LocalFleet
from tests.browser.conftest import log_in
from tests.support.maps import (
    PixelMap,
    _assert_on_open_map,
    _box,
    long_press,
)
from tests.support.mission_editor import (
    CHECK_S,
    GOTO_VEHICLE,
    MISSION_VEHICLE,
    README_IMAGE,
    collapse_panel,
    expand_panel,
    open_panel,
    select,
    shot,
    small,
    toggle_drawer,
    vehicle_states,
)
from tests.support.waiting import poll_until

pytestmark = [pytest.mark.browser, pytest.mark.integration]

U_WIDTH_M, U_HEIGHT_M = 120, 120  # the fence drawn around the mission vehicle


def _u_fence(frame: LocalFrame) -> list[dict[str, float]]:
    """A U open to the north around the vehicle: a notch 20 m wide from 20 m north."""
    corners = [(-60, -40), (60, -40), (60, 80), (10, 80), (10, 20), (-10, 20), (-10, 80), (-60, 80)]
    return [dict(zip(("lat", "lon"), frame.to_geo(e, n), strict=True)) for e, n in corners]


def _drawing_area(page: Page) -> FloatRect:
    """Where the drawing goes: the map, below the controls along its top and above the
    scale and attribution. An open mission panel stands in the map area's dock beside the
    map (under it on a phone), never over it; where it does lie over the map, the drawing
    goes to the map's part left of it."""
    area, panel = _box(page, "#map"), _box(page, ".mission-panel")
    top = area["y"] + 70  # the zoom buttons, the drawer toggles, the layer switcher
    bottom = area["y"] + area["height"] - 40  # the scale, the attribution
    width = area["width"]
    if _overlaps(area, panel):
        width = panel["x"] - area["x"]
    return {"x": area["x"], "y": top, "width": width, "height": bottom - top}


def _overlaps(one: FloatRect, other: FloatRect) -> bool:
    return (
        one["x"] < other["x"] + other["width"]
        and other["x"] < one["x"] + one["width"]
        and one["y"] < other["y"] + other["height"]
        and other["y"] < one["y"] + one["height"]
    )


def _fold_panel_if_in_the_way(page: Page) -> None:
    """Folding the panel ends its editor (one map tool at a time), so it is folded only
    where it lies over the map and leaves under 400 px of it for the drawing."""
    area, panel = _box(page, "#map"), _box(page, ".mission-panel")
    if _overlaps(area, panel) and panel["x"] - area["x"] < 400:
        collapse_panel(page)


def _frame_the_fence(page: Page, frame: LocalFrame) -> PixelMap:
    """Zoom out until the fence fits the drawing area, then drag the map so that the
    fence sits in the middle of it."""
    _fold_panel_if_in_the_way(page)
    pixels = PixelMap(page)
    space = _drawing_area(page)
    zoom_out = page.locator(".leaflet-control-zoom-out")
    for _ in range(6):
        fits = (
            U_WIDTH_M / pixels.metres_per_px() < space["width"] * 0.8
            and U_HEIGHT_M / pixels.metres_per_px() < space["height"] * 0.8
        )
        if fits:
            break
        zoom_out.click()
        pixels = PixelMap(page)
    centre = pixels.pixel(*frame.to_geo(0, 20))  # the middle of the U
    wanted = (space["x"] + space["width"] / 2, space["y"] + space["height"] / 2)
    # Grab the map at an open point, away from the vehicles and the controls.
    start = pixels.a
    page.mouse.move(*start)
    page.mouse.down()
    page.mouse.move(start[0] + wanted[0] - centre[0], start[1] + wanted[1] - centre[1], steps=15)
    page.mouse.up()
    return PixelMap(page)


def _close_up(page: Page, middle: tuple[float, float]) -> None:
    """One zoom step in about ``middle`` (the wheel zooms about the pointer), then drag
    the map to put it in the middle of the drawing area."""
    pixels = PixelMap(page)
    page.mouse.move(*pixels.pixel(*middle))
    page.mouse.wheel(0, -60)
    pixels = PixelMap(page)
    here, space = pixels.pixel(*middle), _drawing_area(page)
    start = pixels.a
    page.mouse.move(*start)
    page.mouse.down()
    page.mouse.move(
        start[0] + space["x"] + space["width"] / 2 - here[0],
        start[1] + space["y"] + space["height"] / 2 - here[1],
        steps=15,
    )
    page.mouse.up()
    PixelMap(page)  # settled
    page.wait_for_function(
        "() => !document.querySelector('#map img.leaflet-tile:not(.leaflet-tile-loaded)')"
    )


@pytest.mark.slow
def test_a_drawn_mission_is_refused_on_its_leg_fixed_by_dragging_and_flown(
    sized_page: tuple[Page, str], mission_fleet: LocalFleet, api: httpx.Client
) -> None:
    page, size = sized_page
    poll_until(lambda: not vehicle_states(api)[MISSION_VEHICLE]["armed"], 120, "the vehicle landed")
    here = vehicle_states(api)[MISSION_VEHICLE]
    frame = LocalFrame(here["lat"], here["lon"], 0.0)
    site_rails = api.get("/api/v1/safety/rails").json()
    fenced = {**site_rails, "geofence": {"polygon": _u_fence(frame)}}
    assert api.put("/api/v1/safety/rails", json=fenced).status_code == 200
    try:
        log_in(page, mission_fleet.plan.hub_http, "admin", mission_fleet.plan.admin_password)
        expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
        expect(page.locator("#map")).to_have_attribute("data-basemap", "farmland")
        open_panel(page, size, MISSION_VEHICLE)
        # A fresh plan: the vehicle's mission (an earlier run's) is where editing starts.
        page.locator('[data-action="mission-edit"]').click()
        page.locator('[data-action="mission-clear"]').click()
        page.locator('[data-action="mission-add-22"]').click()
        expect(page.locator(".mission-row")).to_have_count(1)
        if small(size):  # touch targets of at least 44 px
            # Measured in one go in the page: the panel re-renders its buttons as vehicle
            # updates arrive, so a handle taken a moment earlier may be gone.
            shown = page.evaluate(
                """() => [...document.querySelectorAll('.mission-panel button')]
                    .map((b) => [b.innerText, b.getBoundingClientRect(), getComputedStyle(b)])
                    .filter(([, r, style]) => r.width > 0 && r.height > 0
                        && style.visibility !== 'hidden')
                    .map(([text, r]) => [text, r.width, r.height])"""
            )
            assert shown
            for text, width, height in shown:
                assert min(width, height) >= 44, (text, width, height)
        pixels = _frame_the_fence(page, frame)

        def at(east: float, north: float) -> tuple[float, float]:
            x, y = pixels.pixel(*frame.to_geo(east, north))
            _assert_on_open_map(page, x, y)
            return x, y

        # Draw: after the take-off, a waypoint in each arm of the U, then RTL.
        page.mouse.click(*at(-40, 60))
        page.mouse.click(*at(40, 60))
        expand_panel(page)
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
        shot(page, "mission-refused", size)

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
        _fold_panel_if_in_the_way(page)
        if small(size):
            shot(page, "mission-refused-map", size)  # the red leg, the panel folded
        grab = pixels.pixel(*frame.to_geo(40, 60))
        on_item = page.evaluate(
            "([x, y]) => document.elementFromPoint(x, y)?.closest('.mission-item')?.dataset.seq",
            list(grab),
        )
        assert on_item == "3", f"item 3 is not under the pointer at {grab}"
        page.mouse.move(*grab)
        page.mouse.down()
        page.mouse.move(*at(-45, 5), steps=12)
        page.mouse.up()
        expand_panel(page)
        shot(page, "mission-dragged", size)
        try:
            expect(page.locator('[data-field="mission-verdict"]')).to_contain_text(
                "Rails: OK", timeout=CHECK_S * 1000
            )
        except AssertionError as error:  # say which rule still refuses it
            raise AssertionError(page.locator(".mission-body").inner_text()) from error
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

        readme = size == "desktop" and bool(os.environ.get("GCS_UPDATE_SCREENSHOTS"))
        if readme:
            _close_up(page, frame.to_geo(-22, 30))  # the README's picture: the path, larger

        commands = f"/api/v1/vehicles/{MISSION_VEHICLE}/commands"
        assert api.post(commands, json={"name": "set_mode", "mode": "GUIDED"}).status_code == 200
        armed = api.post(commands, json={"name": "arm"}).json()
        assert armed["outcome"]["status"] == "accepted", armed
        auto = api.post(commands, json={"name": "set_mode", "mode": "AUTO"}).json()
        assert auto["outcome"]["status"] == "accepted", auto
        _fold_panel_if_in_the_way(page)  # on a phone: the map, to watch the flight

        # The active item moves along the path on the map, the flown legs dimmed behind it.
        for seq in (2, 3):
            expect(page.locator(f'.mission-item.active[data-seq="{seq}"]')).to_have_count(
                1, timeout=90_000
            )
        expect(page.locator('.mission-item.flown[data-seq="1"]')).to_have_count(1)
        expect(page.locator('.mission-leg.flown[data-seq="2"]')).to_have_count(1)
        expect(page.locator('.mission-row.active[data-seq="3"]')).to_have_count(1)
        shot(page, "mission-flown", size)
        if readme:
            # The base map, the trail behind the flying vehicle, its mission with the
            # active item and the flown legs, and the event feed.
            README_IMAGE.parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=README_IMAGE)
        # On to the return: the RTL item, drawn at home, is the active one.
        expect(page.locator('.mission-item.active[data-kind="rtl"][data-seq="4"]')).to_have_count(
            1, timeout=90_000
        )
        expect(page.locator('.mission-item.flown[data-seq="3"]')).to_have_count(1)
        poll_until(
            lambda: not vehicle_states(api)[MISSION_VEHICLE]["armed"],
            120,
            "the mission to end landed",
        )
    finally:
        assert api.put("/api/v1/safety/rails", json=site_rails).status_code == 200


def test_fly_here_moves_the_vehicle(
    sized_page: tuple[Page, str], mission_fleet: LocalFleet, api: httpx.Client
) -> None:
    page, size = sized_page
    commands = f"/api/v1/vehicles/{GOTO_VEHICLE}/commands"
    poll_until(lambda: vehicle_states(api)[GOTO_VEHICLE].get("ready_to_fly"), 60, "ready to fly")
    assert api.post(commands, json={"name": "set_mode", "mode": "GUIDED"}).status_code == 200
    assert api.post(commands, json={"name": "arm"}).json()["outcome"]["status"] == "accepted"
    takeoff = api.post(commands, json={"name": "takeoff", "altitude": 10}).json()
    assert takeoff["outcome"]["status"] == "accepted", takeoff
    poll_until(lambda: (vehicle_states(api)[GOTO_VEHICLE].get("alt_rel") or 0) > 6, 60, "the climb")

    log_in(page, mission_fleet.plan.hub_http, "admin", mission_fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
    select(page, size, GOTO_VEHICLE)  # the map pans to it
    states = vehicle_states(api)
    start = states[GOTO_VEHICLE]
    # Towards the others: each run flies back over the ground the last one left.
    north = 40 if start["lat"] <= states[MISSION_VEHICLE]["lat"] else -40
    target = LocalFrame(start["lat"], start["lon"], 0.0).to_geo(0, north)
    pixels = PixelMap(page)
    x, y = pixels.pixel(*target)
    _assert_on_open_map(page, x, y)

    verdict = page.locator('[data-field="go-here-verdict"]')
    if small(size):
        long_press(page, x, y, until='[data-field="go-here-verdict"]')
    else:
        page.mouse.click(x, y, button="right")
    expect(verdict).to_contain_text("rails: OK", timeout=CHECK_S * 1000)
    distance = float(verdict.inner_text().split(" m away")[0])
    assert distance == pytest.approx(40, abs=4)
    confirm = page.locator('[data-action="go-here-confirm"]')
    expect(confirm).to_have_text("Fly here at 10 m")
    if small(size):
        box = confirm.bounding_box()
        assert box is not None
        assert box["height"] >= 44, box  # a touch target
    shot(page, "fly-here", size)
    confirm.click()
    expect(page.locator('[data-field="go-here-result"]')).to_contain_text("accepted")
    poll_until(
        lambda: (
            haversine_m(
                vehicle_states(api)[GOTO_VEHICLE]["lat"],
                vehicle_states(api)[GOTO_VEHICLE]["lon"],
                *target,
            )
            < 4
        ),
        90,
        f"{GOTO_VEHICLE} at the clicked point",
    )
    # The selected vehicle's panel follows it: up at 10 m, 40 m from where it armed
    # (its home), in flight, its attitude drawn.
    toggle_drawer(page, size, "ops", True)
    panel = page.locator('[data-panel="selected-vehicle"]')
    expect(panel.locator('[data-field="selected-alt"]')).to_have_text(
        re.compile(r"^(9|10|11)\.\d m$")
    )
    expect(panel.locator('[data-field="selected-home"]')).to_have_text(
        re.compile(r"^(3[6-9]|4[0-4]) m$")
    )
    expect(panel.locator('[data-field="selected-flight-time"]')).to_have_text(
        re.compile(r"^(\d+:)?\d+:\d\d$")
    )
    expect(panel.locator('[data-field="attitude"]')).to_have_attribute(
        "aria-label", re.compile(r"^Roll -?\d+°, pitch -?\d+°, heading \d{3}°$")
    )
    shot(page, "fly-here-arrived", size)
    assert api.post(commands, json={"name": "land"}).status_code == 200
    poll_until(
        lambda: not vehicle_states(api)[GOTO_VEHICLE]["armed"], 120, f"{GOTO_VEHICLE} landed"
    )
