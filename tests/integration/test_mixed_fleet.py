"""A mixed fleet through the hub: an ArduPilot Rover and a quadcopter playing PX4 connect,
list their own modes, and do what their autopilots do with the same REST commands."""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import httpx
import pytest

from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.helpers import FleetWatcher, access_token, api_client

pytestmark = pytest.mark.integration

ROVER, PX4 = "sim_1", "sim_2"
NORTH = 1 / 111_320
WAYPOINT, RTL = 16, 20


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    plan = FleetPlan(
        vehicles=2,
        port=free_port(),
        data_dir=tmp_path_factory.mktemp("mixed-fleet"),
        speedup=5.0,
        frames=("rover", "quad"),
        autopilots=("ardupilot", "px4"),
    )
    with LocalFleet(plan) as local_fleet:
        local_fleet.start()
        local_fleet.wait_until_ready()
        yield local_fleet


@pytest.fixture
def clients(fleet: LocalFleet) -> Iterator[tuple[httpx.Client, FleetWatcher]]:
    base = fleet.plan.hub_http
    token = access_token(base, "admin", fleet.plan.admin_password)
    with api_client(base, token) as api, FleetWatcher(base, token) as watcher:
        yield api, watcher


def state_of(vehicles: dict[str, dict[str, Any]], vehicle: str) -> dict[str, Any]:
    return (vehicles.get(vehicle) or {}).get("state") or {}


def ready(vehicle: str) -> Any:
    def check(vehicles: dict[str, dict[str, Any]]) -> bool:
        state = state_of(vehicles, vehicle)
        return bool(
            vehicles.get(vehicle, {}).get("connected")
            and state.get("gps_fix", 0) >= 3
            and state.get("home_lat") is not None
            and state.get("battery_remaining") is not None
        )

    return check


def speed_of(state: dict[str, Any]) -> float:
    speed = state.get("groundspeed")
    return math.inf if speed is None else float(speed)


def send(api: httpx.Client, vehicle: str, **command: Any) -> dict[str, Any]:
    response = api.post(f"/api/v1/vehicles/{vehicle}/commands", json=command)
    assert response.status_code == 200, response.text
    outcome: dict[str, Any] = response.json()["outcome"]
    return outcome


def test_rover_connects_lists_rover_modes_and_drives_a_mission(
    clients: tuple[httpx.Client, FleetWatcher],
) -> None:
    api, watcher = clients
    watcher.wait_until(ready(ROVER), 60, "the rover ready")
    rover = api.get(f"/api/v1/vehicles/{ROVER}").json()
    assert rover["vehicle_type"] == "rover"
    assert rover["autopilot"] == "ardupilot"
    assert {"MANUAL", "HOLD", "AUTO", "GUIDED", "RTL", "SMART_RTL"} <= set(rover["modes"])
    assert "LAND" not in rover["modes"]
    assert rover["state"]["mode"] == "MANUAL"

    takeoff = send(api, ROVER, name="takeoff", altitude=10)
    assert takeoff["status"] == "refused"
    assert takeoff["message"] == "takeoff: a rover does not take off"

    here = state_of(watcher.vehicles, ROVER)
    lat, lon = here["lat"], here["lon"]
    items = [
        {"command": WAYPOINT, "lat": lat + 25 * NORTH, "lon": lon},
        {"command": WAYPOINT, "lat": lat + 25 * NORTH, "lon": lon + 25 * NORTH * 1.23},
        {"command": RTL},
    ]
    uploaded = api.post(f"/api/v1/vehicles/{ROVER}/mission", json={"items": items})
    assert uploaded.status_code == 200, uploaded.text
    stored = api.get(f"/api/v1/vehicles/{ROVER}/mission").json()["items"]
    assert [item["command"] for item in stored[1:]] == [WAYPOINT, WAYPOINT, RTL]

    assert send(api, ROVER, name="set_mode", mode="AUTO")["status"] == "accepted"
    assert send(api, ROVER, name="arm")["status"] == "accepted"  # Rover arms in AUTO
    top_alt = 0.0

    def mission_done(vehicles: dict[str, dict[str, Any]]) -> bool:
        nonlocal top_alt
        state = state_of(vehicles, ROVER)
        top_alt = max(top_alt, abs(state.get("alt_rel") or 0.0))
        return bool(
            state.get("mission_current") == 3
            and state.get("mode") == "AUTO"
            and speed_of(state) < 0.05
        )

    watcher.wait_until(lambda v: (state_of(v, ROVER).get("groundspeed") or 0) > 1, 30, "moving")
    watcher.wait_until(mission_done, 120, "the rover to drive the mission and stop")
    assert top_alt < 0.1  # on the ground all the way
    events = api.get("/api/v1/events", params={"vehicle_id": ROVER, "kind": "mission"}).json()
    reached = {e["text"] for e in events["events"]}
    assert {f"reached mission item {n}" for n in (1, 2, 3)} <= reached
    assert send(api, ROVER, name="disarm")["status"] == "accepted"


def test_px4_copter_lists_px4_modes_and_reports_them_decoded(
    clients: tuple[httpx.Client, FleetWatcher],
) -> None:
    api, watcher = clients
    watcher.wait_until(ready(PX4), 60, "the PX4 copter ready")
    copter = api.get(f"/api/v1/vehicles/{PX4}").json()
    assert copter["autopilot"] == "px4"
    assert copter["vehicle_type"] == "multirotor"
    assert {"MANUAL", "POSCTL", "LOITER", "MISSION", "RTL", "LAND", "OFFBOARD"} <= set(
        copter["modes"]
    )
    assert "GUIDED" not in copter["modes"]
    assert copter["state"]["mode"] == "MANUAL"

    assert send(api, PX4, name="set_mode", mode="POSCTL")["status"] == "accepted"
    watcher.wait_until(lambda v: state_of(v, PX4).get("mode") == "POSCTL", 10, "POSCTL")
    assert send(api, PX4, name="hold")["status"] == "accepted"  # PX4's Hold: AUTO.LOITER
    watcher.wait_until(lambda v: state_of(v, PX4).get("mode") == "LOITER", 10, "Hold")

    offboard = send(api, PX4, name="set_mode", mode="OFFBOARD")
    assert offboard["status"] == "refused"
    assert offboard["result"] == "MAV_RESULT_TEMPORARILY_REJECTED"

    assert send(api, PX4, name="takeoff", altitude=8)["status"] == "accepted"
    watcher.wait_until(lambda v: state_of(v, PX4).get("mode") == "TAKEOFF", 10, "Takeoff mode")
    watcher.wait_until(
        lambda v: (
            state_of(v, PX4).get("mode") == "LOITER"
            and abs((state_of(v, PX4).get("alt_rel") or 0) - 8) < 0.3
        ),
        60,
        "at 8 m, holding",
    )
    assert send(api, PX4, name="land")["status"] == "accepted"
    watcher.wait_until(lambda v: state_of(v, PX4).get("mode") == "LAND", 10, "Land mode")
    watcher.wait_until(lambda v: not state_of(v, PX4).get("armed"), 120, "landed and disarmed")
