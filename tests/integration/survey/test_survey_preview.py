"""The survey preview over the real hub and three simulated drones: one mission per drone,
each passing the same mission check as an upload, the photos covering the area; bad input
gets a 422 saying what to change, and nothing is uploaded."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.survey.files.qgc_plan import read_qgc_plan_items
from backend.survey.planning.camera import PRESETS
from gcs.launcher import LocalFleet
from tests.support.api import api_client
from tests.support.surveys import read_wpl
from tests.support.watcher import FleetWatcher, ready

pytestmark = pytest.mark.integration

NORTH = 1 / 111_320
VEHICLES = ["sim_1", "sim_2", "sim_3"]


@pytest.fixture
def api(fleet: LocalFleet, fleet_admin_token: str) -> Iterator[httpx.Client]:
    with api_client(fleet.plan.hub_http, fleet_admin_token) as client:
        yield client


@pytest.fixture
def watcher(fleet: LocalFleet, fleet_admin_token: str) -> Iterator[FleetWatcher]:
    with FleetWatcher(fleet.plan.hub_http, fleet_admin_token) as watching:
        yield watching


def _request(state: dict[str, Any], **changes: Any) -> dict[str, Any]:
    lat, lon = state["lat"] + 40 * NORTH, state["lon"]
    east = NORTH / 0.7  # about a metre east at these latitudes, near enough
    ring = [
        [lon, lat],
        [lon + 200 * east, lat],
        [lon + 200 * east, lat + 150 * NORTH],
        [lon, lat + 150 * NORTH],
        [lon, lat],
    ]
    body: dict[str, Any] = {
        "area": {"type": "Polygon", "coordinates": [ring]},
        "camera": "sony_a6000_16mm",
        "altitude_m": 40,
        "side_overlap_pct": 70,
        "front_overlap_pct": 80,
        "angle_deg": 0,
        "vehicle_ids": VEHICLES,
    }
    body.update(changes)
    return body


def test_preview_gives_each_drone_a_checked_mission(
    settled_fleet: LocalFleet, api: httpx.Client, watcher: FleetWatcher
) -> None:
    # settled_fleet: on the ground with a pack to fly on, whatever flew before, so that
    # every part passes the mission check.
    for vehicle in VEHICLES:
        watcher.wait_until(ready(vehicle), 60, f"{vehicle} ready")
    response = api.post("/api/v1/surveys/preview", json=_request(watcher.state("sim_1")))
    assert response.status_code == 200, response.text
    preview = response.json()
    assert preview["coverage_pct"] == 100.0
    assert preview["coverage_at_overlaps_pct"] == 100.0
    assert preview["lane_spacing_m"] == pytest.approx(17.625)  # 146.875 * 0.4 * 0.3
    assert [p["vehicle_id"] for p in preview["parts"]] == VEHICLES
    for part in preview["parts"]:
        assert part["check"]["ok"] is True, part["check"]
        commands = [item["command"] for item in part["mission"]["items"]]
        assert commands[0] == mavlink2.MAV_CMD_NAV_TAKEOFF
        # the take-off carries where the drone stands (never 0, 0)
        takeoff, here = part["mission"]["items"][0], watcher.state(part["vehicle_id"])
        assert takeoff["lat"] == pytest.approx(here["lat"], abs=2 * NORTH)
        assert takeoff["lon"] == pytest.approx(here["lon"], abs=2 * NORTH)
        assert commands[-1] == mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH
        assert mavlink2.MAV_CMD_DO_SET_CAM_TRIGG_DIST in commands
    assert preview["ok"] is True
    assert preview["photo_count"] == sum(p["photo_count"] for p in preview["parts"])


@pytest.mark.parametrize(
    ("changes", "field", "message"),
    [
        ({"camera": "gopro"}, "camera", "unknown camera preset 'gopro'"),
        ({"side_overlap_pct": 100}, "side_overlap_pct", "less than 100"),
        ({"vehicle_ids": ["sim_1", "sim_1"]}, "vehicle_ids", "each vehicle may be chosen once"),
        ({"altitude_m": None}, "", "give exactly one of altitude_m and gsd_cm"),
    ],
)
def test_bad_input_is_refused_saying_what_to_change(
    api: httpx.Client, watcher: FleetWatcher, changes: dict[str, Any], field: str, message: str
) -> None:
    watcher.wait_until(ready("sim_1"), 60, "sim_1 ready")
    response = api.post("/api/v1/surveys/preview", json=_request(watcher.state("sim_1"), **changes))
    assert response.status_code == 422, response.text
    assert message in response.text
    assert field in response.text


def test_a_self_intersecting_area_is_refused_saying_where(
    api: httpx.Client, watcher: FleetWatcher
) -> None:
    watcher.wait_until(ready("sim_1"), 60, "sim_1 ready")
    body = _request(watcher.state("sim_1"))
    ring = body["area"]["coordinates"][0]
    ring[1], ring[2] = ring[2], ring[1]  # a bow tie
    response = api.post("/api/v1/surveys/preview", json=body)
    assert response.status_code == 422, response.text
    assert "Self-intersection" in response.text


def test_files_import_and_a_planned_survey_exports_each_drone_s_mission(
    settled_fleet: LocalFleet, api: httpx.Client, watcher: FleetWatcher
) -> None:
    # settled_fleet: a survey takes only drones on the ground and in no other survey.
    plan_text = (Path(__file__).resolve().parents[2] / "data" / "qgc" / "survey.plan").read_text()
    imported = api.post("/api/v1/surveys/import", json={"format": "plan", "content": plan_text})
    assert imported.status_code == 200, imported.text
    assert imported.json()["altitude_m"] == 80
    assert imported.json()["area"]["type"] == "Polygon"
    bad = api.post("/api/v1/surveys/import", json={"format": "kml", "content": "<kml/>"})
    assert bad.status_code == 422
    assert "holds no Polygon" in bad.text

    for vehicle in VEHICLES:
        watcher.wait_until(ready(vehicle), 60, f"{vehicle} ready")
    created = api.post("/api/v1/surveys", json=_request(watcher.state("sim_1")))
    assert created.status_code == 201, created.text
    survey = created.json()["survey"]
    try:
        drone = survey["drones"][0]
        url = f"/api/v1/surveys/{survey['id']}/vehicles/{drone['vehicle_id']}/mission"
        exported = api.get(url, params={"format": "plan"})
        assert exported.status_code == 200, exported.text
        items = read_qgc_plan_items(exported.text)
        assert [i.command for i in items] == [i["command"] for i in drone["items"]]
        wpl = api.get(url, params={"format": "wpl"})
        assert wpl.text.startswith("QGC WPL 110")
        assert len(read_wpl(wpl.text)[1]) == len(drone["items"])
    finally:
        # A planned survey holds its drones: free them for the rest of the suite.
        assert api.post(f"/api/v1/surveys/{survey['id']}/abort").status_code == 200


def test_the_camera_presets_are_the_hubs_with_their_figures(
    fleet: LocalFleet, fleet_admin_token: str
) -> None:
    with api_client(fleet.plan.hub_http, fleet_admin_token) as api:
        answer = api.get("/api/v1/surveys/cameras")
    assert answer.status_code == 200, answer.text
    listed = {camera["id"]: camera for camera in answer.json()}
    assert set(listed) == set(PRESETS)
    for key, camera in PRESETS.items():
        shown = listed[key]
        assert (shown["name"], shown["focal_length_mm"]) == (camera.name, camera.focal_length_mm)
        assert (shown["image_width_px"], shown["distance_trigger"]) == (
            camera.image_width_px,
            camera.distance_trigger,
        )
