"""The dashboard's survey panel in headless Chromium against a real fleet (hub, two
simulators, two agents) at ten times real speed: an area drawn with the mouse, the hub's
preview (lanes per drone on the map, photos, time, area, battery), the launch, and the
progress the live feed's `survey` messages bring. Screenshots go to test-output/survey/."""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from pathlib import Path

import httpx
import pytest
from playwright.sync_api import Page, expect

from common.geodesy import LocalFrame
from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.browser.conftest import log_in
from tests.support.api import access_token, api_client
from tests.support.hubs import TEST_HUB_ENV
from tests.support.maps import PixelMap, _assert_on_open_map, _box
from tests.support.waiting import poll_until

pytestmark = [pytest.mark.browser, pytest.mark.integration, pytest.mark.slow]

ROOT = Path(__file__).resolve().parents[2]
QGC_SURVEY = ROOT / "tests" / "data" / "qgc" / "survey.plan"
OUTPUT = ROOT / "test-output" / "survey"
VEHICLES = ["sim_1", "sim_2"]
SPEEDUP = 10.0
# A small area north of the homes, so the flight is short: 80 m by 60 m.
WEST_M, SOUTH_M, WIDE_M, DEEP_M = -40.0, 40.0, 80.0, 60.0
FLIGHT_S = 240  # the take-off, the first lane and its photos, at ten times speed, under load


@pytest.fixture(scope="module")
def survey_fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    plan = FleetPlan(
        port=free_port(),
        data_dir=tmp_path_factory.mktemp("survey-ui"),
        vehicles=len(VEHICLES),
        speedup=SPEEDUP,
    )
    with LocalFleet(plan) as fleet:
        fleet.start(
            hub_env={
                **TEST_HUB_ENV,
                "GCS_BASEMAP_URL": "",
                "GCS_SURVEY_UPDATE_INTERVAL_S": "0.2",
                "GCS_COMMANDS_PER_SECOND": "1000",
            }
        )
        fleet.wait_until_ready()
        yield fleet


def _ready_on_ground(api: httpx.Client) -> bool:
    states = {v["id"]: v["state"] or {} for v in api.get("/api/v1/vehicles").json()}
    return all(
        states.get(vid, {}).get("home_lat") is not None and not states[vid].get("armed")
        for vid in VEHICLES
    )


def _space(page: Page) -> dict[str, float]:
    """The open map left of the panels, below the controls along its top."""
    area, panel = _box(page, "#map"), _box(page, ".survey-panel")
    top, bottom = area["y"] + 70, area["y"] + area["height"] - 40
    return {"x": area["x"], "y": top, "width": panel["x"] - area["x"] - 20, "height": bottom - top}


def _frame_area(page: Page, frame: LocalFrame) -> PixelMap:
    """Zoom until the area fills a good part of the open map, then drag it to its middle."""
    pixels = PixelMap(page)
    space = _space(page)
    for _ in range(8):
        width_px = WIDE_M / pixels.metres_per_px()
        deep_px = DEEP_M / pixels.metres_per_px()
        if width_px > space["width"] * 0.8 or deep_px > space["height"] * 0.7:
            page.locator(".leaflet-control-zoom-out").click()
        elif width_px < space["width"] * 0.25:
            page.locator(".leaflet-control-zoom-in").click()
        else:
            break
        pixels = PixelMap(page)
    centre = pixels.pixel(*frame.to_geo(WEST_M + WIDE_M / 2, SOUTH_M + DEEP_M / 2))
    wanted = (space["x"] + space["width"] / 2, space["y"] + space["height"] / 2)
    start = pixels.a
    page.mouse.move(*start)
    page.mouse.down()
    page.mouse.move(start[0] + wanted[0] - centre[0], start[1] + wanted[1] - centre[1], steps=15)
    page.mouse.up()
    return PixelMap(page)


def _draw_ring(
    page: Page,
    at: Callable[[float, float], tuple[float, float]],
    corners: list[tuple[float, float]],
) -> None:
    for corner in corners:
        page.mouse.click(*at(*corner))
    expect(page.locator("path.survey-vertex")).to_have_count(len(corners))


def _area_m2(page: Page) -> float:
    text = page.locator('[data-field="survey-area"]').inner_text()
    return float(re.sub(r"[^0-9.]", "", text)) * (10_000 if text.endswith("ha") else 1)


def test_a_hole_drawn_in_the_area_and_a_qgc_survey_opened(
    wide_page: Page, survey_fleet: LocalFleet
) -> None:
    page, plan = wide_page, survey_fleet.plan
    lat, lon, _ = plan.vehicle_home(0)
    frame = LocalFrame(lat, lon)
    log_in(page, plan.hub_http, "admin", plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(len(VEHICLES), timeout=30_000)
    page.locator('[data-action="survey-toggle"]').click()
    pixels = _frame_area(page, frame)

    def at(east: float, north: float) -> tuple[float, float]:
        x, y = pixels.pixel(*frame.to_geo(east, north))
        _assert_on_open_map(page, x, y)
        return x, y

    page.locator('[data-action="survey-draw"]').click()
    _draw_ring(page, at, _rectangle(WEST_M, SOUTH_M, WIDE_M, DEEP_M))
    page.locator('[data-action="survey-close"]').click()
    page.locator(f'.survey-drone[data-vehicle-id="{VEHICLES[0]}"] input').check()
    summary = page.locator('[data-field="survey-summary"]')
    expect(summary).to_have_attribute("data-state", "ok", timeout=20_000)
    whole = _area_m2(page)

    # A 30 m by 20 m no-fly hole in the middle, closed by a click on its first corner.
    page.locator('[data-action="survey-hole"]').click()
    hole = _rectangle(WEST_M + 25, SOUTH_M + 20, 30, 20)
    _draw_ring(page, at, hole)
    page.mouse.click(*at(*hole[0]))
    expect(page.locator("path.survey-hole")).to_have_count(1)
    expect(page.locator("path.survey-vertex")).to_have_count(0)
    expect(summary).to_have_attribute("data-state", "ok", timeout=20_000)
    poll_until(lambda: _area_m2(page) < whole - 400, 20, "the preview without the hole")
    assert _area_m2(page) == pytest.approx(whole - 600, rel=0.1)
    page.screenshot(path=OUTPUT / "survey-hole.png")

    # A QGC plan's Survey item opens with its polygon and camera; the area is in Zurich,
    # far from these drones, and the hub's refusal says so.
    page.locator('[data-field="survey-file"]').set_input_files(QGC_SURVEY)
    status = page.locator('[data-field="survey-status"]')
    expect(status).to_contain_text("km from the area", timeout=20_000)
    expect(page.locator("path.survey-hole")).to_have_count(0)
    expect(page.locator("path.survey-area")).to_have_count(1)
    expect(page.locator('[data-field="survey-camera"]')).to_have_value("file")
    expect(page.locator('[data-action="survey-launch"]')).to_be_disabled()


def _rectangle(west: float, south: float, wide: float, deep: float) -> list[tuple[float, float]]:
    return [(west, south), (west + wide, south), (west + wide, south + deep), (west, south + deep)]


def test_a_drawn_area_is_previewed_launched_and_its_progress_shown(
    wide_page: Page, survey_fleet: LocalFleet
) -> None:
    page, plan = wide_page, survey_fleet.plan
    token = access_token(plan.hub_http, "admin", plan.admin_password)
    with api_client(plan.hub_http, token) as api:
        poll_until(lambda: _ready_on_ground(api), 60, "both drones ready with a home")
        lat, lon, _ = plan.vehicle_home(0)
        frame = LocalFrame(lat, lon)

        log_in(page, plan.hub_http, "admin", plan.admin_password)
        expect(page.locator(".vehicle-marker")).to_have_count(len(VEHICLES), timeout=30_000)
        page.locator('[data-action="survey-toggle"]').click()
        expect(page.locator(".survey-body")).to_be_visible()
        pixels = _frame_area(page, frame)

        def at(east: float, north: float) -> tuple[float, float]:
            x, y = pixels.pixel(*frame.to_geo(east, north))
            _assert_on_open_map(page, x, y)
            return x, y

        # Draw the outline with the mouse: four corners, then close the ring.
        page.locator('[data-action="survey-draw"]').click()
        corners = [
            (WEST_M, SOUTH_M),
            (WEST_M + WIDE_M, SOUTH_M),
            (WEST_M + WIDE_M, SOUTH_M + DEEP_M),
            (WEST_M, SOUTH_M + DEEP_M),
        ]
        for corner in corners:
            page.mouse.click(*at(*corner))
        expect(page.locator("path.survey-vertex")).to_have_count(4)
        page.locator('[data-action="survey-close"]').click()
        expect(page.locator("path.survey-area")).to_have_count(1)

        # The camera and the flight, then the drones: the preview follows.
        for vid in VEHICLES:
            page.locator(f'.survey-drone[data-vehicle-id="{vid}"] input').check()
        # Bad input is refused by the hub with the field named, and nothing can launch.
        page.locator('[data-field="survey-front"]').fill("100")
        status = page.locator('[data-field="survey-status"]')
        expect(status).to_contain_text("front_overlap_pct", timeout=20_000)
        expect(page.locator('[data-action="survey-launch"]')).to_be_disabled()
        # Slow lanes (2 m/s: 5 s a lane at ten times speed) leave time to take a drone out
        # mid-survey below.
        for field, value in (
            ("survey-height", "30"),
            ("survey-side", "60"),
            ("survey-front", "70"),
            ("survey-angle", "0"),
            ("survey-speed", "2"),
        ):
            page.locator(f'[data-field="{field}"]').fill(value)

        summary = page.locator('[data-field="survey-summary"]')
        expect(summary).to_have_attribute("data-state", "ok", timeout=20_000)
        rows = page.locator('[data-field="survey-parts"] tr:not(.survey-refusal)')
        expect(rows).to_have_count(len(VEHICLES))
        photos = int(page.locator('[data-field="survey-photos"]').inner_text())
        lanes = int(page.locator('[data-field="survey-lanes"]').inner_text())
        assert photos > 0
        assert lanes >= 2
        # Every lane of the preview is on the map, in one colour per drone.
        expect(page.locator("path.survey-lane")).to_have_count(lanes)
        strokes = {line.get_attribute("stroke") for line in page.locator("path.survey-lane").all()}
        assert len(strokes) == len(VEHICLES), strokes
        # The mouse drew the area asked for (80 m by 60 m), to within a few pixels' worth.
        area_text = page.locator('[data-field="survey-area"]').inner_text()
        area_m2 = float(re.sub(r"[^0-9.]", "", area_text))
        assert area_m2 == pytest.approx(WIDE_M * DEEP_M, rel=0.1)
        for row in rows.all():
            assert re.search(r"\d+ %", row.inner_text()), "no battery estimate"
            assert re.search(r"\d+:\d\d", row.inner_text()), "no time"
        OUTPUT.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=OUTPUT / "survey-preview.png")

        # Launch: the survey is created and started, and its progress rises.
        page.locator('[data-action="survey-launch"]').click()
        progress = page.locator('[data-field="survey-progress"]')
        expect(progress).to_have_attribute("data-state", "flying", timeout=60_000)
        overall = page.locator('[data-field="survey-overall"]')
        survey_id = page.locator('[data-field="survey-state"]').inner_text().split()[1].rstrip(":")
        poll_until(
            lambda: (
                int(overall.get_attribute("data-lanes-done") or 0) >= 1
                and int(overall.get_attribute("data-photos") or 0) >= 1
            ),
            FLIGHT_S,
            "a lane flown and photos taken",
            every_s=0.5,
        )
        # The panel says what the hub says; the flown lanes fade and the photos show.
        hub = api.get(f"/api/v1/surveys/{survey_id}/progress").json()
        assert hub["lanes_done"] >= 1
        assert hub["photos"] >= 1
        expect(page.locator("path.survey-lane-done").first).to_be_attached(timeout=10_000)
        expect(page.locator("path.survey-photo").first).to_be_attached(timeout=10_000)
        expect(page.locator(".survey-drone-progress li")).to_have_count(len(VEHICLES))
        page.screenshot(path=OUTPUT / "survey-progress.png")

        # A drone taken out mid-survey: the hand-over is offered, accepted with one click,
        # and the drone still flying takes its unflown lanes.
        def flying_with_lanes_left() -> str | None:
            drones = api.get(f"/api/v1/surveys/{survey_id}/progress").json()["drones"]
            left = {
                d["vehicle_id"]: d["lanes_total"] - d["lanes_done"]
                for d in drones
                if d["state"] == "flying"
            }
            best = max(left, key=lambda vid: left[vid], default=None)
            return best if best is not None and left[best] >= 2 else None

        lost = poll_until(flying_with_lanes_left, 60, "a drone flying with lanes left")
        keeper = next(vid for vid in VEHICLES if vid != lost)
        before = api.get(f"/api/v1/surveys/{survey_id}/progress").json()
        keeper_total = next(d for d in before["drones"] if d["vehicle_id"] == keeper)["lanes_total"]
        dropped = api.post(f"/api/v1/surveys/{survey_id}/vehicles/{lost}/abort")
        assert dropped.status_code == 200, dropped.text
        offer = page.locator('[data-field="survey-handover"]')
        expect(offer).to_contain_text(f"{lost} dropped out", timeout=30_000)
        page.screenshot(path=OUTPUT / "survey-handover.png")
        offer.locator('[data-action="survey-accept"]').click()
        expect(offer).to_have_count(0, timeout=30_000)
        expect(progress).to_have_attribute("data-state", "flying", timeout=30_000)
        after = api.get(f"/api/v1/surveys/{survey_id}/progress").json()
        assert after["state"] == "flying"
        assert next(d for d in after["drones"] if d["vehicle_id"] == keeper)["lanes_total"] > (
            keeper_total
        ), after
        lost_row = page.locator(f'.survey-drone-progress li[data-vehicle-id="{lost}"]')
        expect(lost_row).to_have_attribute("data-state", "dropped")

        # Abort brings everyone home (and leaves the fleet idle for whatever runs next).
        page.locator('[data-action="survey-abort"]').click()
        expect(progress).to_have_attribute("data-state", "aborted", timeout=30_000)
