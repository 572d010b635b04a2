"""An operator's day (issue #33's "Done when"): a four-drone fleet with cameras and LIDAR,
flown from the dashboard through its UI only (clicks, keys, taps; the API is read only to
wait for the fleet's state) at a desktop, a tablet and a phone size. Each step saves a
screenshot, ``<size>-<NN>-<step>.png`` in ``$GCS_DAY_SHOTS`` (else the test's tmp_path),
and measures the page: no element off the viewport, no control under another.

The fleet runs at real time: the formation's follower and the hand-flown stick stream run
on the wall clock (docs/reference.md, "Slow tests"). The selectors live in
tests/support/operators_day.py.

Not yet in `make test`: on the 2-core reference machine the day has passed its first
eleven steps at desktop size and twelve at tablet size, but not yet end to end at any
size (the hand-flying steps: a stick stream paused by a loaded machine is cut by the hub's
input watchdog, as it must be). A test that cannot pass would fail every run, so it runs
only when asked: ``GCS_OPERATORS_DAY=1 pytest tests/browser/test_operators_day.py``.
Issue #33 stays open until it passes in the suite."""

from __future__ import annotations

import os
import re
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from playwright.sync_api import Browser, expect

from common.geodesy import LocalFrame, haversine_m
from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.browser.conftest import SIZES, checked_page, log_in
from tests.support.api import api_client
from tests.support.hubs import TEST_HUB_ENV, seed_database
from tests.support.maps import long_press
from tests.support.operators_day import (
    Day,
    drag,
    drawer,
    flights_button,
    formation_open,
    frame_on_map,
    map_point,
    metres_forward,
    mission_open,
    mission_panel,
    open_space,
    patient_token,
    pilot_panel,
    select_vehicle,
    shots_folder,
    survey_open,
    take_off,
    view_3d_button,
)

pytestmark = [pytest.mark.browser, pytest.mark.integration]

VEHICLES = ["sim_1", "sim_2", "sim_3", "sim_4"]
FLIER, SURVEYORS, FOLLOWER = "sim_1", ["sim_2", "sim_3", "sim_4"], "sim_2"
# The drones' camera (the MicaSense RedEdge-MX's figures: the smallest photos to render);
# the hub offers it as a survey preset of its own, chosen when the drones share it.
CAMERA_MODEL = "4.8,3.6,1280,960,5.4"
FLEET_CAMERA = f"fleet:{CAMERA_MODEL}"
# Places on the ground, metres (east, north) of sim_1's home; the homes run east 15 m apart.
FLY_HERE_M = (0.0, 40.0)
MISSION_M = [(30.0, 40.0), (20.0, 12.0)]  # it ends holding near the follower's home
SURVEY_M = [(-30.0, -80.0), (40.0, -80.0), (40.0, -25.0), (-30.0, -25.0)]
ROUTE_M = [(8.0, 12.0), (-20.0, 12.0)]  # west from where the mission left the leader


@pytest.fixture
def fleet(tmp_path: Path) -> Iterator[LocalFleet]:
    """Four drones, each with a camera and a LIDAR, at real time: a fleet of its own per
    size, so that each size's day starts on the ground."""
    seed_database(tmp_path / "fleet")
    plan = FleetPlan(
        port=free_port(),
        data_dir=tmp_path / "fleet",
        vehicles=len(VEHICLES),
        speedup=1.0,
        lidars=True,
        camera_model=CAMERA_MODEL,
    )
    with LocalFleet(plan) as local:
        local.start(
            hub_env={
                **TEST_HUB_ENV,
                "GCS_BASEMAP_URL": "",
                "GCS_SURVEY_UPDATE_INTERVAL_S": "0.5",
                "GCS_COMMANDS_PER_SECOND": "1000",
            }
        )
        local.wait_until_ready(timeout_s=90)
        yield local


def log_in_step(day: Day, plan: FleetPlan) -> None:
    log_in(day.page, plan.hub_http, "admin", plan.admin_password)
    expect(day.page.locator(".vehicle-marker")).to_have_count(len(VEHICLES), timeout=30_000)
    day.wait(lambda s: all(s[v].get("ready_to_fly") for v in VEHICLES), 90, "all ready to fly")
    day.shot("logged-in")


def take_off_and_fly_here(day: Day) -> None:
    take_off(day, FLIER, 10)
    day.wait(lambda s: (s[FLIER].get("alt_rel") or 0) > 8, 60, f"{FLIER} at 10 m")
    day.shot("took-off")
    select_vehicle(day, FLIER)
    pixels = frame_on_map(day, (10.0, 25.0), (60.0, 50.0), open_space(day, ".mission-panel"))
    x, y = map_point(day, pixels, *FLY_HERE_M)
    verdict = '[data-field="go-here-verdict"]'
    if day.small:
        long_press(day.page, x, y, until=verdict)
    else:
        day.page.mouse.click(x, y, button="right")
    expect(day.page.locator(verdict)).to_contain_text("rails: OK", timeout=15_000)
    day.shot("fly-here")
    day.page.locator('[data-action="go-here-confirm"]').click()
    # The answer ("accepted") can take longer than the flight on a loaded machine: the
    # arrival is the test, the answer is in the screenshot.
    expect(day.page.locator('[data-field="go-here-result"]')).to_be_visible()
    target = day.frame.to_geo(*FLY_HERE_M)
    day.wait(lambda s: haversine_m(s[FLIER]["lat"], s[FLIER]["lon"], *target) < 3, 60, "there")
    day.shot("flown-here")


def draw_and_start_mission(day: Day) -> None:
    page = day.page
    select_vehicle(day, FLIER)
    mission_open(page, True)
    page.locator('[data-action="mission-edit"]').click()
    page.locator('[data-action="mission-clear"]').click()
    page.locator('[data-action="mission-add-22"]').click()  # a take-off item first
    # The panel stays open (folding it ends its tool): the map is drawn on beside it.
    pixels = frame_on_map(day, (15.0, 25.0), (60.0, 50.0), open_space(day, ".mission-panel"))
    for east, north in MISSION_M:
        page.mouse.click(*map_point(day, pixels, east, north))
    # Done ends the map's tool (its banner goes) and keeps the plan.
    edit = page.locator('[data-action="mission-edit"]')
    banner = page.locator(".map-tool-banner")
    expect(banner).to_contain_text("Esc or Done")
    expect(edit).to_have_text("Done")
    edit.click()
    expect(edit).to_have_text("Edit")
    expect(banner).to_be_hidden()
    expect(page.locator(".mission-row")).to_have_count(1 + len(MISSION_M))
    verdict = page.locator('[data-field="mission-verdict"]')
    expect(verdict).to_contain_text("Rails: OK", timeout=15_000)
    day.shot("mission-drawn")
    page.locator('[data-action="mission-upload"]').click()
    expect(page.locator('[data-field="mission-status"]')).to_contain_text(
        f"{FLIER}: uploaded", timeout=30_000
    )
    start_mission(day)
    expect(page.locator('.mission-item.active[data-seq="3"]')).to_have_count(1, timeout=90_000)
    end = day.frame.to_geo(*MISSION_M[-1])
    day.wait(lambda s: haversine_m(s[FLIER]["lat"], s[FLIER]["lon"], *end) < 3, 90, "at its end")
    day.shot("mission-flown")
    mission_open(page, False)


def start_mission(day: Day) -> None:
    """The Mission panel's Start mission: the checked sequence, each step's answer listed.
    The vehicle is already up (flown here), so the sequence checks the mission and goes
    straight to the mission mode."""
    panel = mission_panel(day.page)
    panel.get_by_role("button", name="Start mission").click()
    steps = panel.locator("ol.mission-start-steps")
    expect(steps.locator('li[data-step="check"]')).to_have_attribute("data-state", "ok")
    expect(steps.locator('li[data-step="mission"]')).to_have_attribute("data-state", "ok")
    expect(steps.locator('li[data-state="refused"]')).to_have_count(0)
    day.wait(lambda s: s[FLIER].get("mode") == "AUTO", 15, f"{FLIER} in AUTO")
    day.shot("mission-started")


def survey_with_three_drones(day: Day) -> None:
    page = day.page
    survey_open(page, True)
    for name, value in (("height", "30"), ("side", "60"), ("front", "70"), ("speed", "5")):
        page.locator(f'[data-field="survey-{name}"]').fill(value)
    for vehicle in SURVEYORS:
        page.locator(f'.survey-drone[data-vehicle-id="{vehicle}"] input').check()
    # The drones share one camera: the hub's preset of it is chosen for them.
    expect(page.locator('[data-field="survey-camera"]')).to_have_value(FLEET_CAMERA)
    page.locator('[data-action="survey-draw"]').click()
    # As the mission's, the area is drawn beside (on a phone, above) the docked panel.
    pixels = frame_on_map(day, (5.0, -52.0), (70.0, 55.0), open_space(day, ".survey-panel"))
    for corner in SURVEY_M:
        page.mouse.click(*map_point(day, pixels, *corner))
    survey_open(page, True)
    page.locator('[data-action="survey-close"]').click()
    summary = page.locator('[data-field="survey-summary"]')
    expect(summary).to_have_attribute("data-state", "ok", timeout=20_000)
    rows = page.locator('[data-field="survey-parts"] tr:not(.survey-refusal)')
    expect(rows).to_have_count(len(SURVEYORS))
    day.shot("survey-planned")
    page.locator('[data-action="survey-launch"]').click()
    expect(page.locator('[data-field="survey-progress"]')).to_be_visible(timeout=30_000)
    loaded = page.locator(".survey-mosaic img.leaflet-tile-loaded")
    expect(loaded.first).to_be_attached(timeout=240_000)
    day.shot("survey-mosaic")


def formation_of_airborne_drones(day: Day) -> None:
    # The survey's drones fly it to its end and land: the follower is one of them.
    day.wait(lambda s: not any(s[v].get("armed") for v in SURVEYORS), 400, "the survey landed")
    take_off(day, FOLLOWER, 5)
    day.wait(lambda s: (s[FOLLOWER].get("alt_rel") or 0) > 4.5, 60, f"{FOLLOWER} up")
    page = day.page
    panel = formation_open(page)
    panel.locator('[data-field="formation-leader"]').select_option(FLIER)
    row = panel.locator(f'.formation-follower[data-vehicle-id="{FOLLOWER}"]')
    row.locator("input[type=checkbox]").check()
    row.locator("input[type=number]").fill("-5")
    panel.locator('[data-field="formation-shape"]').select_option("column")
    panel.locator('[data-field="formation-altitude"]').fill("10")
    panel.locator('[data-field="formation-spacing"]').fill("8")
    panel.locator('[data-action="formation-draw"]').click()
    pixels = frame_on_map(day, (0.0, 10.0), (50.0, 30.0), open_space(day, ".formation-panel"))
    for east, north in ROUTE_M:
        page.mouse.click(*map_point(day, pixels, east, north))
    panel.locator('[data-action="formation-finish"]').click()
    day.shot("formation-planned")
    panel.locator('[data-action="formation-start"]').click()
    progress = panel.locator('[data-field="formation-progress"]')
    # Formed: the follower joined its slot and the leader flies the route (or, a short
    # route, has flown it and the formation holds at its end).
    expect(progress).to_have_attribute(
        "data-state", re.compile(r"^(flying|route_done)$"), timeout=90_000
    )
    expect(progress).to_contain_text(re.compile(rf"{FOLLOWER}: [0-2]\.\d m from its slot"))
    day.shot("formation-formed")
    panel.locator('[data-action="formation-stop"]').click()
    expect(progress).to_have_attribute("data-state", "stopped")
    page.locator('[data-action="formation-toggle"]').click()


def fly_by_hand(day: Day, source: str) -> None:
    """Take the lease with ``source`` ("touch": the on-screen sticks; "keyboard"), fly
    5 m forward (pitch: along the heading it has, west after the formation), release."""
    page = day.page
    select_vehicle(day, FLIER)
    pilot = pilot_panel(day)
    pilot.locator('select[data-field="pilot-source"]').select_option(source)
    pilot.locator('button[data-action="take-control"]').click()
    expect(pilot.locator('[data-field="lease-holder"]')).to_have_text(
        "Flown by hand by admin", timeout=30_000
    )
    start = day.states()[FLIER]
    forward = lambda s: metres_forward(start, s[FLIER]) > 5  # noqa: E731
    if source == "touch":
        release = drag(page, pilot.locator('[data-stick="right"]'), 0, -60)
        try:
            day.wait(forward, 30, f"{FLIER} 5 m forward by the stick")
            day.shot("sticks")
        finally:
            release()
    else:
        page.keyboard.down("w")  # pitch forward
        try:
            day.wait(forward, 30, f"{FLIER} 5 m forward by the keyboard")
            day.shot("keyboard")
        finally:
            page.keyboard.up("w")
    pilot.locator('button[data-action="release-control"]').click()
    expect(pilot.locator('[data-field="lease-holder"]')).to_contain_text("released", timeout=10_000)
    drawer(day, "ops", False)


def the_3d_view(day: Day) -> None:
    """The drones, the survey's lanes, its mosaic and the LIDAR's points: each layer is
    listed in the viewer's panel once its first data is drawn (backend/viz3d/scene.py)."""
    page = day.page
    view_3d_button(page).click()
    # Beside the map, full height, where the map area has room for two (a desktop); on a
    # phone instead of it; a tablet's area beside a docked panel may have room or not.
    split = page.locator(".viz3d-split")
    mode = {"desktop": "^beside$", "phone": "^instead$"}.get(day.size, "^(beside|instead)$")
    expect(split).to_have_attribute("data-mode", re.compile(mode))
    viewer = page.frame_locator(".viz3d-pane iframe")
    expect(viewer.locator("canvas").first).to_be_visible(timeout=30_000)
    for layer in ("Vehicles", "Survey lanes", "Mosaic", "LIDAR scans"):
        expect(viewer.get_by_text(layer, exact=True).first).to_be_attached(timeout=30_000)
    for vehicle in VEHICLES:
        expect(viewer.get_by_text(vehicle).first).to_be_attached()
    day.shot("view-3d")
    close = page.locator('[data-action="viz3d-close"]')
    beside = split.get_attribute("data-mode") == "beside"
    expect(close).to_have_text("Close 3D view" if beside else "Back to map")
    close.click()
    expect(split).to_be_hidden()
    expect(page.locator("#map")).to_be_visible()


def replay_and_export(day: Day) -> None:
    page, flown = day.page, SURVEYORS[1]
    flights_button(page).click()
    panel = page.locator("#replay-panel")
    vehicle_filter = panel.locator('input[data-field="flight-vehicle"]')
    vehicle_filter.fill(flown)
    vehicle_filter.press("Enter")
    panel.locator("tr[data-flight-id]").first.click()
    expect(panel.locator('.replay[data-state="ready"]')).to_be_visible(timeout=15_000)
    play = panel.locator('button[data-action="replay-play"]')
    panel.locator('select[data-field="replay-speed"]').select_option("30")
    play.click()
    expect(panel.locator('[data-field="replay-time"]')).not_to_have_text(re.compile(r"^00:00:00 /"))
    day.shot("replay")
    with page.expect_download() as downloading:
        panel.locator('a[data-action="export-csv"]').click()
    saved = day.shots / f"{day.size}-{downloading.value.suggested_filename}"
    downloading.value.save_as(saved)
    assert saved.read_text().count("\n") > 10
    day.shot("exported")


@pytest.mark.slow
@pytest.mark.skipif(
    not os.environ.get("GCS_OPERATORS_DAY"),
    reason="the operator's day runs only with GCS_OPERATORS_DAY=1 until it passes end to end "
    "(issue #33; see the module's docstring)",
)
@pytest.mark.timeout(1800)  # a size's day: minutes of real-time flight on a loaded machine
@pytest.mark.parametrize("size", list(SIZES))
def test_an_operators_day(browser: Browser, fleet: LocalFleet, size: str, tmp_path: Path) -> None:
    plan, began = fleet.plan, time.monotonic()
    token = patient_token(plan.hub_http, plan.admin_password)
    with (
        api_client(plan.hub_http, token) as api,
        checked_page(
            browser, *SIZES[size], accept_downloads=True, has_touch=size != "desktop"
        ) as page,
    ):
        # A loaded machine: four drones' feeds, their photos and scans, at real time.
        page.set_default_timeout(30_000)
        page.set_default_navigation_timeout(90_000)
        day = Day(page, size, api, shots_folder(tmp_path), LocalFrame(*plan.vehicle_home(0)[:2]))
        try:
            log_in_step(day, plan)
            take_off_and_fly_here(day)
            draw_and_start_mission(day)
            survey_with_three_drones(day)
            formation_of_airborne_drones(day)
            fly_by_hand(day, "touch")
            fly_by_hand(day, "keyboard")
            the_3d_view(day)
            replay_and_export(day)
        except BaseException:
            page.screenshot(path=day.shots / f"{size}-failed.png")  # where the day stopped
            raise
        finally:
            print(f"{size}: {time.monotonic() - began:.0f} s, layout faults: {day.faults}")
    assert day.faults == {}, "\n".join(
        f"{step}: {fault}" for step, faults in day.faults.items() for fault in faults
    )
