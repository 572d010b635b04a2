"""The mission editor, QGroundControl .plan files and "fly here", in headless Chromium
against a real fleet (hub, simulators, agents) whose base map is an offline MBTiles file
made here. The drawn mission and "fly here" run at a desktop, a tablet and a phone size,
each saving its screenshots under test-output/missions/; with GCS_UPDATE_SCREENSHOTS=1
the desktop run of the flown mission also remakes the README's picture."""

from __future__ import annotations

import json
import os
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import jsonschema_rs
import pytest
from playwright.sync_api import Browser, FloatRect, Page, expect

from common.geodesy import LocalFrame, haversine_m
from gcs.launcher import DEFAULT_HOME, FleetPlan, LocalFleet, free_port
from tests.browser.conftest import SIZES, checked_page, log_in
from tests.conftest import FLEET_SPEEDUP
from tests.map_tiles import farmland_tiles, write_mbtiles
from tests.support.api import access_token, api_client
from tests.support.hubs import TEST_HUB_ENV
from tests.support.maps import (
    PixelMap,
    _assert_on_open_map,
    _box,
)
from tests.support.waiting import poll_until

pytestmark = [pytest.mark.browser, pytest.mark.integration]

DATA = Path(__file__).parent.parent / "data" / "qgc"
ROOT = Path(__file__).resolve().parents[2]
OUTPUT = ROOT / "test-output" / "missions"
README_IMAGE = ROOT / "docs" / "img" / "dashboard-map.png"
MISSION_VEHICLE = "sim_3"
GOTO_VEHICLE = "sim_1"
CHECK_S = 15  # the editor checks 0.4 s after an edit; the hub answers at once
U_WIDTH_M, U_HEIGHT_M = 120, 120  # the fence drawn around the mission vehicle


@pytest.fixture(scope="module")
def mission_fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    """A fleet of its own, with nothing online and a farmland tile set as its base map:
    the README's picture is made here."""
    data_dir = tmp_path_factory.mktemp("mission-fleet")
    (data_dir / "tiles").mkdir(mode=0o700)
    tiles = farmland_tiles(DEFAULT_HOME[:2], range(14, 20), radius_m=450)
    write_mbtiles(data_dir / "tiles" / "farmland.mbtiles", tiles, attribution="Made-up farmland")
    plan = FleetPlan(port=free_port(), data_dir=data_dir, vehicles=3, speedup=FLEET_SPEEDUP)
    with LocalFleet(plan) as fleet:
        fleet.start(hub_env={**TEST_HUB_ENV, "GCS_BASEMAP_URL": ""})
        fleet.wait_until_ready()
        yield fleet


@pytest.fixture(scope="module")
def api(mission_fleet: LocalFleet) -> Iterator[httpx.Client]:
    plan = mission_fleet.plan
    with api_client(plan.hub_http, access_token(plan.hub_http, "admin", plan.admin_password)) as c:
        poll_until(
            lambda: sum(bool(s.get("lat")) for s in _states(c).values()) == plan.vehicles,
            60,
            "every vehicle with a position",
        )
        yield c


def _context_page(browser: Browser, size: str) -> Iterator[Page]:
    # The tablet and the phone have touch screens (a long press opens "fly here") and a
    # mouse as well, which draws the mission as it would on a desktop.
    with checked_page(
        browser, *SIZES[size], accept_downloads=True, has_touch=size != "desktop"
    ) as opened:
        yield opened


@pytest.fixture
def wide_page(browser: Browser) -> Iterator[Page]:
    """1920 by 1080: room for the mission panel beside the drawing."""
    yield from _context_page(browser, "desktop")


@pytest.fixture(params=list(SIZES))
def sized_page(browser: Browser, request: pytest.FixtureRequest) -> Iterator[tuple[Page, str]]:
    yield from ((page, request.param) for page in _context_page(browser, request.param))


def _shot(page: Page, name: str, size: str) -> None:
    OUTPUT.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=OUTPUT / f"{name}-{size}.png")


def _states(api: httpx.Client) -> dict[str, dict[str, Any]]:
    return {v["id"]: v["state"] or {} for v in api.get("/api/v1/vehicles").json()}


def _small(size: str) -> bool:
    return size != "desktop"


def _toggle_drawer(page: Page, size: str, drawer: str, open_: bool) -> None:
    """On a tablet or a phone the fleet list and the panels are drawers over the map."""
    if not _small(size):
        return
    button = page.locator(f'button[data-action="drawer-{drawer}"]')
    if (button.get_attribute("aria-expanded") == "true") != open_:
        button.click()
    expect(button).to_have_attribute("aria-expanded", str(open_).lower())


def _select(page: Page, size: str, vehicle: str) -> None:
    _toggle_drawer(page, size, "fleet", True)
    page.locator(f'tr[data-vehicle-id="{vehicle}"] td[data-field="mode"]').click()
    _toggle_drawer(page, size, "fleet", False)
    expect(page.locator('[data-field="mission-vehicle"]')).to_contain_text(vehicle)


def _open_panel(page: Page, size: str, vehicle: str) -> None:
    _select(page, size, vehicle)
    _expand_panel(page)


def _expand_panel(page: Page) -> None:
    toggle = page.locator('[data-action="mission-toggle"]')
    if toggle.get_attribute("aria-expanded") != "true":
        toggle.click()
    expect(page.locator(".mission-body")).to_be_visible()


def _collapse_panel(page: Page) -> None:
    toggle = page.locator('[data-action="mission-toggle"]')
    if toggle.get_attribute("aria-expanded") == "true":
        toggle.click()
    expect(page.locator(".mission-body")).to_be_hidden()


def test_a_qgc_plan_opens_and_a_saved_plan_is_qgcs_format(
    wide_page: Page, mission_fleet: LocalFleet
) -> None:
    page = wide_page
    log_in(page, mission_fleet.plan.hub_http, "admin", mission_fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
    _open_panel(page, "desktop", MISSION_VEHICLE)

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
    # The same MAVLink items, NaN (null, "unset": QGC's yaws) kept as null.
    for mine, theirs in zip(saved["mission"]["items"], source["mission"]["items"], strict=True):
        assert (mine["command"], mine["frame"], mine["autoContinue"]) == (
            theirs["command"],
            theirs["frame"],
            theirs["autoContinue"],
        )
        assert [p is None for p in mine["params"]] == [p is None for p in theirs["params"]]
        assert [p for p in mine["params"] if p is not None] == pytest.approx(
            [p for p in theirs["params"] if p is not None]
        )

    # Uploaded to a group (another vehicle ticked on purpose): each vehicle is checked and
    # answers for itself, the plan's own vehicle first.
    page.locator('[data-field="mission-targets"] input[value="sim_2"]').check()
    page.locator('[data-action="mission-upload"]').click()
    status = page.locator('[data-field="mission-status"]')
    expect(status).to_contain_text(re.compile(r"^sim_3: .+\nsim_2: .+$"), timeout=30_000)

    # A file that is not a plan is refused with the field named, and the plan stays.
    # Handed over as bytes: a file on disk removed right after set_input_files could be
    # gone before the page reads it (NotFoundError under load).
    bad = b'{"fileType": "Plan", "version": 1, "mission": {"version": 2, "items": 3}}'
    page.locator('[data-field="mission-file"]').set_input_files(
        {"name": "not-a-plan.json", "mimeType": "application/json", "buffer": bad}
    )
    expect(page.locator('[data-field="mission-status"]')).to_contain_text("mission.items")
    expect(rows).to_have_count(5)


def _on_board(api: httpx.Client, vehicle: str) -> list[dict[str, Any]]:
    """The vehicle's mission as it reads back from the vehicle, home (item 0) left out."""
    answer = api.get(f"/api/v1/vehicles/{vehicle}/mission")
    assert answer.status_code == 200, answer.text
    items: list[dict[str, Any]] = answer.json()["items"][1:]
    return items


def test_a_plan_goes_to_the_vehicle_it_was_edited_for(
    wide_page: Page, mission_fleet: LocalFleet, api: httpx.Client
) -> None:
    """Select sim_1, then sim_2, edit and upload: the plan is sim_2's and only sim_2 gets
    it (the upload list once kept the first vehicle selected on the page). Another
    vehicle ticked on purpose is checked against its own rails first and, refused, is
    not uploaded, with the reason."""
    page, first, edited, other = wide_page, "sim_1", "sim_2", "sim_3"
    first_before, other_before = _on_board(api, first), _on_board(api, other)
    log_in(page, mission_fleet.plan.hub_http, "admin", mission_fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
    _open_panel(page, "desktop", first)
    _select(page, "desktop", edited)  # the map pans to it
    page.locator('[data-action="mission-edit"]').click()
    expect(page.locator('[data-field="mission-vehicle"]')).to_have_text(
        f"Editing a plan for {edited}"
    )
    page.locator('[data-action="mission-clear"]').click()
    page.locator('[data-action="mission-add-22"]').click()
    here = _states(api)[edited]
    frame = LocalFrame(here["lat"], here["lon"], 0.0)
    pixels = PixelMap(page)
    for east, north in ((-8, 25), (8, 25), (8, -25), (-8, -25)):
        x, y = pixels.pixel(*frame.to_geo(east, north))
        _assert_on_open_map(page, x, y)
        page.mouse.click(x, y)
    page.locator('[data-action="mission-add-20"]').click()
    expect(page.locator(".mission-row")).to_have_count(6)

    page.locator('[data-action="mission-upload"]').click()
    status = page.locator('[data-field="mission-status"]')
    expect(status).to_have_text(f"{edited}: uploaded (6 items)", timeout=30_000)
    on_board = _on_board(api, edited)
    assert [item["command"] for item in on_board] == [22, 16, 16, 16, 16, 20]
    # A drawn take-off and waypoints leave the yaw unset (keep the heading), as QGC does.
    assert [item["param4"] for item in on_board[:5]] == [None] * 5
    # The take-off stands where the vehicle launches (home), as QGC writes it: PX4 flies
    # to a take-off's position, and at 0, 0 it flew towards 0°N 0°E.
    takeoff = on_board[0]
    home = (here["home_lat"], here["home_lon"])
    assert (takeoff["lat"], takeoff["lon"]) == pytest.approx(home, abs=1e-7)
    assert _on_board(api, first) == first_before  # nothing went to the first vehicle

    # The list says where an upload goes: the edited vehicle, ticked; the others not.
    targets = page.locator('[data-field="mission-targets"]')
    expect(targets.locator("input:checked")).to_have_count(1)
    expect(targets.locator(f'input[value="{edited}"]')).to_be_checked()
    expect(targets.locator(".mission-target.edited")).to_have_text(f"{edited} (this plan's)")
    _shot(page, "mission-targets", "desktop")

    # Another vehicle ticked on purpose is checked against its own rails: with a 10 m
    # ceiling of its own it refuses the 20 m plan, and is not sent it.
    rails = f"/api/v1/vehicles/{other}/safety-rails"
    assert api.put(rails, json={"max_altitude_m": 10}).status_code == 200
    try:
        page.locator('[data-action="mission-edit"]').click()
        targets.locator(f'input[value="{other}"]').check()
        page.locator('[data-action="mission-upload"]').click()
        expect(status).to_contain_text(
            re.compile(
                rf"^{edited}: uploaded \(6 items\)\n{other}: not uploaded — refused by its "
                r"rails: max_altitude: .+$"
            ),
            timeout=30_000,
        )
        assert _on_board(api, other) == other_before
    finally:
        assert api.delete(rails).status_code in (200, 204)


def test_a_qgc_null_stays_unset_or_is_refused_never_zero(
    wide_page: Page, mission_fleet: LocalFleet, api: httpx.Client
) -> None:
    """QGroundControl writes null for what it leaves unset. A null yaw (param4) stays
    unset: sent as MAVLink's NaN ("keep the heading"), read back as null, not 0 (north on
    PX4). A null altitude has no "unset" on the wire: the file is refused naming the item
    and the field (it used to become 0 m above sea level), and the plan open stays."""
    page, vehicle = wide_page, "sim_2"
    log_in(page, mission_fleet.plan.hub_http, "admin", mission_fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
    _open_panel(page, "desktop", vehicle)
    status = page.locator('[data-field="mission-status"]')
    rows = page.locator(".mission-row")

    page.locator('[data-field="mission-file"]').set_input_files(DATA / "unset_yaw.plan")
    expect(status).to_have_text("unset_yaw.plan: 5 items opened.")
    expect(rows).to_have_count(5)
    expect(page.locator('[data-field="mission-verdict"]')).to_contain_text(
        "Rails: OK", timeout=CHECK_S * 1000
    )
    page.locator('[data-action="mission-upload"]').click()
    expect(status).to_have_text(f"{vehicle}: uploaded (5 items)", timeout=30_000)
    on_board = _on_board(api, vehicle)
    assert [item["command"] for item in on_board] == [22, 16, 16, 16, 20]
    assert [item["param4"] for item in on_board[:4]] == [None] * 4
    assert on_board[2]["alt"] == 20

    page.locator('[data-action="mission-edit"]').click()
    page.locator('[data-field="mission-file"]').set_input_files(DATA / "null_altitude.plan")
    expect(status).to_have_text(
        "null_altitude.plan could not be opened: item 3: altitude is empty (null) in the "
        ".plan (mission.items[2].params[6])"
    )
    expect(rows).to_have_count(5)
    expect(rows.nth(2).locator('[data-field="alt"]')).to_have_value("20")
    assert _on_board(api, vehicle) == on_board


def _u_fence(frame: LocalFrame) -> list[dict[str, float]]:
    """A U open to the north around the vehicle: a notch 20 m wide from 20 m north."""
    corners = [(-60, -40), (60, -40), (60, 80), (10, 80), (10, 20), (-10, 20), (-10, 80), (-60, 80)]
    return [dict(zip(("lat", "lon"), frame.to_geo(e, n), strict=True)) for e, n in corners]


def _drawing_area(page: Page) -> FloatRect:
    """Where the drawing goes: the map beside the mission panel when the panel leaves
    room for it (a desktop, a tablet), else the whole map with the panel folded away (a
    phone), below the controls along the map's top."""
    area, panel = _box(page, "#map"), _box(page, ".mission-panel")
    top = area["y"] + 70  # the zoom buttons, the drawer toggles, the layer switcher
    bottom = area["y"] + area["height"] - 40  # the scale, the attribution
    if panel["x"] - area["x"] >= 400:
        return {"x": area["x"], "y": top, "width": panel["x"] - area["x"], "height": bottom - top}
    return {"x": area["x"], "y": top, "width": area["width"], "height": bottom - top}


def _fold_panel_if_in_the_way(page: Page) -> None:
    area, panel = _box(page, "#map"), _box(page, ".mission-panel")
    if panel["x"] - area["x"] < 400:
        _collapse_panel(page)


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
    poll_until(lambda: not _states(api)[MISSION_VEHICLE]["armed"], 120, "the vehicle landed")
    here = _states(api)[MISSION_VEHICLE]
    frame = LocalFrame(here["lat"], here["lon"], 0.0)
    site_rails = api.get("/api/v1/safety/rails").json()
    fenced = {**site_rails, "geofence": {"polygon": _u_fence(frame)}}
    assert api.put("/api/v1/safety/rails", json=fenced).status_code == 200
    try:
        log_in(page, mission_fleet.plan.hub_http, "admin", mission_fleet.plan.admin_password)
        expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
        expect(page.locator("#map")).to_have_attribute("data-basemap", "farmland")
        _open_panel(page, size, MISSION_VEHICLE)
        # A fresh plan: the vehicle's mission (an earlier run's) is where editing starts.
        page.locator('[data-action="mission-edit"]').click()
        page.locator('[data-action="mission-clear"]').click()
        page.locator('[data-action="mission-add-22"]').click()
        expect(page.locator(".mission-row")).to_have_count(1)
        if _small(size):  # touch targets of at least 44 px
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
        _expand_panel(page)
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
        _shot(page, "mission-refused", size)

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
        if _small(size):
            _shot(page, "mission-refused-map", size)  # the red leg, the panel folded
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
        _expand_panel(page)
        _shot(page, "mission-dragged", size)
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
        _shot(page, "mission-flown", size)
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
            lambda: not _states(api)[MISSION_VEHICLE]["armed"], 120, "the mission to end landed"
        )
    finally:
        assert api.put("/api/v1/safety/rails", json=site_rails).status_code == 200


def _long_press(page: Page, x: float, y: float, until: str) -> None:
    """A finger held on the screen (CDP touch events, as a touch screen sends them)
    until ``until`` shows, then lifted: no fixed wait for the long-press timer."""
    cdp = page.context.new_cdp_session(page)
    point = [{"x": x, "y": y}]
    cdp.send("Input.dispatchTouchEvent", {"type": "touchStart", "touchPoints": point})
    try:
        expect(page.locator(until)).to_be_visible(timeout=10_000)
    finally:
        cdp.send("Input.dispatchTouchEvent", {"type": "touchEnd", "touchPoints": []})
        cdp.detach()


def test_fly_here_moves_the_vehicle(
    sized_page: tuple[Page, str], mission_fleet: LocalFleet, api: httpx.Client
) -> None:
    page, size = sized_page
    commands = f"/api/v1/vehicles/{GOTO_VEHICLE}/commands"
    poll_until(lambda: _states(api)[GOTO_VEHICLE].get("ready_to_fly"), 60, "ready to fly")
    assert api.post(commands, json={"name": "set_mode", "mode": "GUIDED"}).status_code == 200
    assert api.post(commands, json={"name": "arm"}).json()["outcome"]["status"] == "accepted"
    takeoff = api.post(commands, json={"name": "takeoff", "altitude": 10}).json()
    assert takeoff["outcome"]["status"] == "accepted", takeoff
    poll_until(lambda: (_states(api)[GOTO_VEHICLE].get("alt_rel") or 0) > 6, 60, "the climb")

    log_in(page, mission_fleet.plan.hub_http, "admin", mission_fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
    _select(page, size, GOTO_VEHICLE)  # the map pans to it
    states = _states(api)
    start = states[GOTO_VEHICLE]
    # Towards the others: each run flies back over the ground the last one left.
    north = 40 if start["lat"] <= states[MISSION_VEHICLE]["lat"] else -40
    target = LocalFrame(start["lat"], start["lon"], 0.0).to_geo(0, north)
    pixels = PixelMap(page)
    x, y = pixels.pixel(*target)
    _assert_on_open_map(page, x, y)

    verdict = page.locator('[data-field="go-here-verdict"]')
    if _small(size):
        _long_press(page, x, y, until='[data-field="go-here-verdict"]')
    else:
        page.mouse.click(x, y, button="right")
    expect(verdict).to_contain_text("rails: OK", timeout=CHECK_S * 1000)
    distance = float(verdict.inner_text().split(" m away")[0])
    assert distance == pytest.approx(40, abs=4)
    confirm = page.locator('[data-action="go-here-confirm"]')
    expect(confirm).to_have_text("Fly here at 10 m")
    if _small(size):
        box = confirm.bounding_box()
        assert box is not None
        assert box["height"] >= 44, box  # a touch target
    _shot(page, "fly-here", size)
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
    # The selected vehicle's panel follows it: up at 10 m, 40 m from where it armed
    # (its home), in flight, its attitude drawn.
    _toggle_drawer(page, size, "ops", True)
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
    _shot(page, "fly-here-arrived", size)
    assert api.post(commands, json={"name": "land"}).status_code == 200
    poll_until(lambda: not _states(api)[GOTO_VEHICLE]["armed"], 120, f"{GOTO_VEHICLE} landed")
