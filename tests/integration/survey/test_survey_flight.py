"""A 3-drone survey flown end to end on real processes (hub, three simulators, three
agents) at ten times real speed: plan, split, upload, fly with the camera triggering on
distance, land. The photos the autopilots report (CAMERA_FEEDBACK) must cover the area,
counted from their footprints. A second run cuts one drone's link mid-survey: the hand-over
is offered and accepted, the other two finish, and all the photos still cover the area."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import httpx
import pytest
import shapely
from pymavlink.dialects.v20 import ardupilotmega as mavlink2
from shapely import affinity
from shapely.geometry import Polygon, box

from common.geodesy import LocalFrame
from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.support.api import access_token, api_client
from tests.support.hubs import TEST_HUB_ENV
from tests.support.survey_shapes import geojson_area
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, on_the_ground

pytestmark = [pytest.mark.integration, pytest.mark.slow]

VEHICLES = ["sim_1", "sim_2", "sim_3"]
SPEEDUP = 10.0
LINK_TIMEOUT_S = 2.0
NORTH_M, EAST_M, WIDE_M, DEEP_M = 30.0, -60.0, 160.0, 110.0


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    plan = FleetPlan(
        port=free_port(), data_dir=tmp_path_factory.mktemp("survey"), vehicles=3, speedup=SPEEDUP
    )
    with LocalFleet(plan) as local:
        local.start(
            hub_env={
                **TEST_HUB_ENV,
                "GCS_SURVEY_LINK_TIMEOUT_S": str(LINK_TIMEOUT_S),
                "GCS_SURVEY_UPDATE_INTERVAL_S": "0.2",
                "GCS_COMMANDS_PER_SECOND": "1000",
            }
        )
        local.wait_until_ready()
        yield local


@pytest.fixture(scope="module")
def token(fleet: LocalFleet) -> str:
    token = access_token(fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    with api_client(fleet.plan.hub_http, token) as api:
        for vid in VEHICLES:
            # Four surveys at ten times speed would drain a real pack below the launch
            # rail; a tenth of the rate keeps the battery moving.
            poll_until(
                lambda vid=vid: (
                    api.put(
                        f"/api/v1/vehicles/{vid}/params/SIM_BATT_DRAIN", json={"value": 0.1}
                    ).status_code
                    == 200
                ),
                60,
                f"{vid} drawing a tenth",
            )
    return token


@pytest.fixture
def api(fleet: LocalFleet, token: str) -> Iterator[httpx.Client]:
    with api_client(fleet.plan.hub_http, token) as client:
        yield client


@pytest.fixture
def watcher(fleet: LocalFleet, token: str) -> Iterator[FleetWatcher]:
    with FleetWatcher(fleet.plan.hub_http, token) as watching:
        yield watching


def _on_ground_and_ready(vehicles: dict[str, Any]) -> bool:
    # On the ground as the hub's busy check sees it: the autopilot's landed state, which
    # trails the disarm by up to a second, not only the disarm.
    return all(on_the_ground(vid)(vehicles) for vid in VEHICLES)


def _area(fleet: LocalFleet) -> tuple[dict[str, Any], LocalFrame]:
    lat, lon, _ = fleet.plan.vehicle_home(0)
    frame = LocalFrame(lat, lon)
    corners = [
        (EAST_M, NORTH_M),
        (EAST_M + WIDE_M, NORTH_M + 10),
        (EAST_M + WIDE_M, NORTH_M + DEEP_M),
        (EAST_M, NORTH_M + DEEP_M - 10),
    ]
    return geojson_area(frame, corners), frame


def _request(fleet: LocalFleet) -> dict[str, Any]:
    area, _ = _area(fleet)
    return {
        "area": area,
        "camera": "sony_a6000_16mm",
        "altitude_m": 30,
        "side_overlap_pct": 60,
        "front_overlap_pct": 70,
        "angle_deg": 0,
        "speed_ms": 8,
        "vehicle_ids": VEHICLES,
    }


def _photo_coverage(fleet: LocalFleet, survey: dict[str, Any]) -> float:
    """The area's share the recorded photos' footprints cover, computed here from the
    photos' places, independently of the hub's own figure."""
    area, frame = _area(fleet)
    polygon = Polygon([frame.to_local(lat, lon) for lon, lat in area["coordinates"][0]])
    side, frontal = survey["footprint_side_m"], survey["footprint_frontal_m"]
    shapes = []
    for drone in survey["drones"]:
        for lat, lon in drone["photos"]:
            x, y = frame.to_local(lat, lon)
            rect = box(x - frontal / 2, y - side / 2, x + frontal / 2, y + side / 2)
            shapes.append(affinity.rotate(rect, survey["angle_deg"], origin=(x, y)))
    assert shapes, "no photo was recorded"
    return float(polygon.intersection(shapely.union_all(shapes)).area / polygon.area)


def _progress(api: httpx.Client, survey_id: str) -> dict[str, Any]:
    response = api.get(f"/api/v1/surveys/{survey_id}/progress")
    assert response.status_code == 200, response.text
    return dict(response.json())


def _create_and_start(api: httpx.Client, fleet: LocalFleet) -> str:
    created = api.post("/api/v1/surveys", json=_request(fleet))
    assert created.status_code == 201, created.text
    survey_id = str(created.json()["survey"]["id"])
    assert created.json()["progress"]["state"] == "planned"
    started = api.post(f"/api/v1/surveys/{survey_id}/start")
    assert started.status_code == 200, started.text
    assert started.json()["progress"]["state"] == "flying", started.text
    return survey_id


def test_bad_survey_requests_are_refused_saying_what_to_change(
    api: httpx.Client, watcher: FleetWatcher, fleet: LocalFleet
) -> None:
    watcher.wait_until(_on_ground_and_ready, 60, "three drones ready on the ground")
    body = _request(fleet)
    for changes, message in [
        ({"camera": "gopro", "vehicle_ids": ["sim_1"]}, "unknown camera preset 'gopro'"),
        ({"vehicle_ids": ["sim_9"]}, "unknown vehicles: sim_9"),
        ({"altitude_m": 400, "vehicle_ids": ["sim_1"]}, "max_altitude"),
        ({"vehicle_ids": ["sim_1", "sim_1"]}, "each vehicle may be chosen once"),
    ]:
        response = api.post("/api/v1/surveys", json={**body, **changes})
        assert response.status_code == 422, response.text
        assert message in response.text
    assert api.post("/api/v1/surveys/abcdef/start").status_code == 404
    assert api.get("/api/v1/surveys").json()["surveys"] == []


def test_three_drones_fly_the_survey_and_their_photos_cover_the_area(
    api: httpx.Client, watcher: FleetWatcher, fleet: LocalFleet
) -> None:
    watcher.wait_until(_on_ground_and_ready, 60, "three drones ready on the ground")
    survey_id = _create_and_start(api, fleet)
    # A drone already in a survey cannot join another one.
    again = api.post("/api/v1/surveys", json=_request(fleet))
    assert again.status_code == 422
    assert "busy" in again.text

    done = poll_until(
        lambda: (p := _progress(api, survey_id))["state"] in ("done", "failed") and p,
        150,
        "the survey to end",
    )
    assert done["state"] == "done", done
    assert [d["state"] for d in done["drones"]] == ["done"] * 3, done
    assert done["lanes_done"] == done["lanes_total"] > 3
    assert all(d["photos"] > 0 for d in done["drones"])
    assert done["covered_pct"] == 100.0

    survey = api.get(f"/api/v1/surveys/{survey_id}").json()["survey"]
    assert _photo_coverage(fleet, survey) == pytest.approx(1.0, abs=1e-6)
    # The live feed carried the progress too.
    watcher.wait_until(
        lambda _: watcher.surveys.get(survey_id, {}).get("state") == "done",
        30,
        "the survey's progress on the live feed",
    )
    live = watcher.surveys[survey_id]
    assert live["lanes_done"] == live["lanes_total"] == done["lanes_total"]
    assert live["photos"] >= done["photos"] > 0
    for drone in survey["drones"]:
        commands = [item["command"] for item in drone["items"]]
        assert commands[0] == mavlink2.MAV_CMD_NAV_TAKEOFF
        assert commands.count(mavlink2.MAV_CMD_DO_SET_CAM_TRIGG_DIST) == 2 * len(drone["lanes"])
    watcher.wait_until(
        lambda v: all(not v[vid]["state"]["armed"] for vid in VEHICLES), 30, "all landed"
    )
    # The photos reached the flight log as events too.
    events = api.get("/api/v1/events", params={"vehicle_id": "sim_1", "kind": "camera"}).json()
    assert any(e["text"].startswith("photo ") for e in events["events"])


def test_a_survey_carries_on_across_a_hub_restart(
    api: httpx.Client, fleet: LocalFleet, token: str
) -> None:
    with FleetWatcher(fleet.plan.hub_http, token) as watcher:
        watcher.wait_until(_on_ground_and_ready, 60, "three drones ready on the ground")
    survey_id = _create_and_start(api, fleet)
    poll_until(
        lambda: _progress(api, survey_id)["lanes_done"] >= 2, 90, "two lanes flown", every_s=0.05
    )
    fleet.kill("hub")
    fleet.start_hub(
        {
            **TEST_HUB_ENV,
            "GCS_SURVEY_LINK_TIMEOUT_S": str(LINK_TIMEOUT_S),
            "GCS_COMMANDS_PER_SECOND": "1000",
        }
    )
    # Generous: the new hub opens the store while three simulators run at ten times speed
    # on a shared machine.
    fleet.wait_until_ready(timeout_s=120)
    with api_client(fleet.plan.hub_http, token) as again:
        resumed = _progress(again, survey_id)
        assert resumed["state"] == "flying"
        assert [d["state"] for d in resumed["drones"]] == ["flying"] * 3
        # Progress stored up to the last save, and the rest from the autopilots' own
        # MISSION_CURRENT once the agents are back.
        poll_until(lambda: _progress(again, survey_id)["lanes_done"] >= 2, 30, "progress")
        done = poll_until(
            lambda: (p := _progress(again, survey_id))["state"] in ("done", "failed") and p,
            150,
            "the survey to end after the restart",
        )
        assert done["state"] == "done", done
        assert done["lanes_done"] == done["lanes_total"]
        # The photos taken while the hub was down come in with the agents' replay, perhaps
        # after the drones were seen landed.
        poll_until(
            lambda: (
                _photo_coverage(fleet, again.get(f"/api/v1/surveys/{survey_id}").json()["survey"])
                > 1 - 1e-6
            ),
            30,
            "the replayed photos to cover the area",
        )
        assert _progress(again, survey_id)["covered_pct"] == 100.0


def test_a_lost_drone_s_lanes_are_handed_over_and_the_area_still_covered(
    api: httpx.Client, watcher: FleetWatcher, fleet: LocalFleet
) -> None:
    watcher.wait_until(_on_ground_and_ready, 60, "three drones ready on the ground")
    survey_id = _create_and_start(api, fleet)

    def sim_2_surveying() -> bool:
        drone = _progress(api, survey_id)["drones"][1]
        return bool(drone["lanes_done"] >= 1 and drone["lanes_done"] < drone["lanes_total"])

    poll_until(sim_2_surveying, 90, "sim_2 part way through its lanes", every_s=0.05)
    fleet.kill("agent_2")  # its link to the hub is gone; the drone flies on unseen

    offered = poll_until(
        lambda: (p := _progress(api, survey_id))["state"] == "handover_offered" and p,
        30,
        "the hand-over offer",
    )
    assert offered["handover_lanes"] >= 1
    assert offered["drones"][1]["state"] == "dropped"
    assert "link lost" in offered["drones"][1]["reason"]
    offer = api.get(f"/api/v1/surveys/{survey_id}/handover").json()
    assert offer["lost"] == ["sim_2"]
    assert sorted(offer["missions"]) == ["sim_1", "sim_3"]

    accepted = api.post(f"/api/v1/surveys/{survey_id}/handover/accept")
    assert accepted.status_code == 200, accepted.text
    survey = accepted.json()["survey"]
    for vid in ("sim_1", "sim_3"):
        items = next(d for d in survey["drones"] if d["vehicle_id"] == vid)["items"]
        # Resumed in the air from where it is (tests/unit/survey/flight/test_run.py checks the
        # first waypoint is its position when it is part way along a lane): no take-off.
        assert items[0]["command"] == mavlink2.MAV_CMD_NAV_WAYPOINT or (
            items[0]["command"] == mavlink2.MAV_CMD_DO_CHANGE_SPEED
        )
        assert all(item["command"] != mavlink2.MAV_CMD_NAV_TAKEOFF for item in items)

    done = poll_until(
        lambda: (p := _progress(api, survey_id))["state"] in ("done", "failed") and p,
        150,
        "the survey to end",
    )
    assert done["state"] == "done", done
    assert [d["state"] for d in done["drones"]] == ["done", "dropped", "done"], done
    assert done["lanes_done"] == done["lanes_total"]
    survey = api.get(f"/api/v1/surveys/{survey_id}").json()["survey"]
    assert _photo_coverage(fleet, survey) == pytest.approx(1.0, abs=1e-6)
    assert done["covered_pct"] == 100.0


def test_a_drone_sent_home_mid_survey_drops_out_and_an_abort_sends_all_home(
    api: httpx.Client, watcher: FleetWatcher, fleet: LocalFleet
) -> None:
    # Runs last: sim_2's agent is gone after the hand-over test; sim_1 and sim_3 fly.
    watcher.wait_until(
        lambda v: all(on_the_ground(vid)(v) for vid in ("sim_1", "sim_3")),
        90,
        "sim_1 and sim_3 ready on the ground",
    )
    created = api.post(
        "/api/v1/surveys", json={**_request(fleet), "vehicle_ids": ["sim_1", "sim_3"]}
    )
    assert created.status_code == 201, created.text
    survey_id = created.json()["survey"]["id"]
    assert api.post(f"/api/v1/surveys/{survey_id}/start").status_code == 200
    poll_until(lambda: _progress(api, survey_id)["photos"] >= 4, 60, "photos", every_s=0.05)
    # As a failsafe or the RC pilot would: the drone leaves its mission for RTL.
    rtl = api.post("/api/v1/vehicles/sim_3/commands", json={"name": "rtl"})
    assert rtl.json()["outcome"]["status"] == "accepted", rtl.text
    offered = poll_until(
        lambda: (p := _progress(api, survey_id))["state"] == "handover_offered" and p,
        30,
        "the hand-over offer",
    )
    assert offered["drones"][1]["state"] == "dropped"
    assert "left its mission: RTL" in offered["drones"][1]["reason"]
    assert api.get(f"/api/v1/surveys/{survey_id}/handover").json()["lost"] == ["sim_3"]
    aborted = api.post(f"/api/v1/surveys/{survey_id}/abort")
    assert aborted.status_code == 200, aborted.text
    assert aborted.json()["progress"]["state"] == "aborted"
    watcher.wait_until(
        lambda v: v["sim_1"]["state"]["mode"] == "RTL", 30, "sim_1 sent home by the abort"
    )
    assert api.post(f"/api/v1/surveys/{survey_id}/abort").status_code == 409
