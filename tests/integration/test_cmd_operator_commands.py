"""The operator's command set through the hub's REST API, against simulated copters:
hold, change speed, set home (and the geofence on it), reboot, and the forced disarm.

A fleet of its own (hub, three simulators, three agents as processes on loopback), one
vehicle per story so that the stories do not disturb each other.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from gcs.launcher import FleetPlan, LocalFleet
from tests.support.api import access_token, api_client, send_command
from tests.support.processes import running_fleet
from tests.support.watcher import FleetWatcher, ready, speed_of, state_of

pytestmark = pytest.mark.integration

SPEEDUP = 5.0
NORTH = 1 / 111_320  # degrees of latitude per metre, near enough


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    data_dir = tmp_path_factory.mktemp("operator-commands")
    with running_fleet(data_dir, vehicles=3, speedup=SPEEDUP) as local_fleet:
        yield local_fleet


@pytest.fixture(scope="module")
def token(fleet: LocalFleet) -> str:
    return access_token(fleet.plan.hub_http, "admin", fleet.plan.admin_password)


@pytest.fixture
def watcher(fleet: LocalFleet, token: str) -> Iterator[FleetWatcher]:
    with FleetWatcher(fleet.plan.hub_http, token) as fleet_watcher:
        yield fleet_watcher


@pytest.fixture
def api(fleet: LocalFleet, token: str) -> Iterator[httpx.Client]:
    with api_client(fleet.plan.hub_http, token) as client:
        yield client


def metres(a: dict[str, Any], lat: float, lon: float) -> float:
    north = (a["lat"] - lat) / NORTH
    east = (a["lon"] - lon) / NORTH * math.cos(math.radians(lat))
    return math.hypot(north, east)


def airborne(api: httpx.Client, watcher: FleetWatcher, vehicle: str) -> dict[str, Any]:
    """Up at 10 m in GUIDED; returns the state there."""
    watcher.wait_until(ready(vehicle), 60, f"{vehicle} ready")
    assert send_command(api, vehicle, name="takeoff", altitude=10)["status"] == "accepted"
    watcher.wait_until(
        lambda v: (state_of(v, vehicle).get("alt_rel") or 0) > 9.5, 60, f"{vehicle} at 10 m"
    )
    return state_of(watcher.vehicles, vehicle)


def cruising(api: httpx.Client, watcher: FleetWatcher, vehicle: str) -> dict[str, Any]:
    """On its way to a point 400 m north, at WPNAV_SPEED."""
    here = airborne(api, watcher, vehicle)
    goto = send_command(
        api, vehicle, name="goto", lat=here["lat"] + 400 * NORTH, lon=here["lon"], altitude=10
    )
    assert goto["status"] == "accepted", goto
    watcher.wait_until(lambda v: (state_of(v, vehicle).get("groundspeed") or 0) > 4.5, 30, "5 m/s")
    return state_of(watcher.vehicles, vehicle)


def test_hold_brakes_and_holds_and_change_speed_paces_the_goto(
    api: httpx.Client, watcher: FleetWatcher
) -> None:
    vehicle = "sim_1"
    cruising(api, watcher, vehicle)

    slower = send_command(api, vehicle, name="change_speed", speed=2, speed_type="ground")
    assert slower["status"] == "accepted", slower
    assert slower["result"] == "MAV_RESULT_ACCEPTED"
    watcher.wait_until(
        lambda v: abs((state_of(v, vehicle).get("groundspeed") or 0) - 2.0) < 0.2,
        30,
        "the copter cruising at 2 m/s",
    )

    before = state_of(watcher.vehicles, vehicle)
    hold = send_command(api, vehicle, name="hold")
    assert hold["status"] == "accepted", hold
    stopped = watcher.wait_until(
        lambda v: (
            state_of(v, vehicle).get("mode") == "BRAKE" and speed_of(state_of(v, vehicle)) < 0.05
        ),
        30,
        "the copter stopped in BRAKE",
    )
    stop = state_of(stopped, vehicle)
    assert metres(stop, before["lat"], before["lon"]) < 5  # braked, not coasted
    stopped_at = stopped[vehicle]["last_seen"]
    later = watcher.wait_until(
        lambda v: v[vehicle]["last_seen"] > stopped_at + 1.0, 10, "a second more of telemetry"
    )
    assert metres(state_of(later, vehicle), stop["lat"], stop["lon"]) < 0.5
    assert abs((state_of(later, vehicle).get("alt_rel") or 0) - 10) < 0.5
    assert send_command(api, vehicle, name="land")["status"] == "accepted"


def test_set_home_moves_home_and_rtl_goes_there(api: httpx.Client, watcher: FleetWatcher) -> None:
    vehicle = "sim_2"
    here = airborne(api, watcher, vehicle)
    home_alt = here["home_alt_msl"]
    lat, lon = here["home_lat"] + 30 * NORTH, here["home_lon"]
    outcome = send_command(
        api, vehicle, name="set_home", use_current=False, lat=lat, lon=lon, alt_msl=home_alt
    )
    assert outcome["status"] == "accepted", outcome
    moved = watcher.wait_until(
        lambda v: abs((state_of(v, vehicle).get("home_lat") or 0) - lat) < 1e-6,
        10,
        "HOME_POSITION to show the new home",
    )
    assert state_of(moved, vehicle)["home_lon"] == pytest.approx(lon, abs=1e-6)

    assert send_command(api, vehicle, name="rtl")["status"] == "accepted"
    landed = watcher.wait_until(
        lambda v: not state_of(v, vehicle).get("armed"), 120, "the RTL to land and disarm"
    )
    assert metres(state_of(landed, vehicle), lat, lon) < 2.0

    # with a geofence around where it stands, a home outside it is refused before sending
    fence = [
        {"lat": lat + d_lat * NORTH, "lon": lon + d_lon * NORTH}
        for d_lat, d_lon in ((-100, -100), (-100, 100), (100, 100), (100, -100))
    ]
    rails = api.put(
        f"/api/v1/vehicles/{vehicle}/safety-rails", json={"geofence": {"polygon": fence}}
    )
    assert rails.status_code == 200, rails.text
    far = api.post(
        f"/api/v1/vehicles/{vehicle}/commands",
        json={
            "name": "set_home",
            "use_current": False,
            "lat": lat + 300 * NORTH,
            "lon": lon,
            "alt_msl": home_alt,
        },
    )
    assert far.status_code == 422, far.text
    [violation] = far.json()["violations"]
    assert violation["rule"] == "geofence"
    assert "RTL would fly there" in violation["message"]
    assert send_command(api, vehicle, name="set_home")["status"] == "accepted"  # here: inside


def test_disarm_and_reboot_refused_in_flight_then_forced_disarm_and_reboot(
    api: httpx.Client, watcher: FleetWatcher
) -> None:
    vehicle = "sim_3"
    airborne(api, watcher, vehicle)

    reboot = send_command(api, vehicle, name="reboot")
    assert reboot["status"] == "refused"
    assert reboot["result"] == "MAV_RESULT_FAILED"
    assert "the vehicle is armed" in reboot["message"]

    plain = send_command(api, vehicle, name="disarm")
    assert plain["status"] == "refused"
    assert "in the air" in plain["message"]
    assert state_of(watcher.vehicles, vehicle)["armed"]

    forced = send_command(api, vehicle, name="disarm", force=True)
    assert forced["status"] == "accepted", forced
    watcher.wait_until(
        lambda v: (
            not state_of(v, vehicle).get("armed")
            and (state_of(v, vehicle).get("alt_rel") or 0) < 0.2
        ),
        30,
        "the motors stopped and the copter down",
    )
    assert state_of(watcher.vehicles, vehicle)["mode"] == "GUIDED"

    accepted = send_command(api, vehicle, name="reboot")
    assert accepted["status"] == "accepted", accepted
    # The autopilot is quiet from here, before the agent can see its link down: a command
    # now is answered at once, not after every retry's wait (a 504 that the fuzz run met).
    meanwhile = api.post(
        f"/api/v1/vehicles/{vehicle}/commands", json={"name": "set_mode", "mode": "GUIDED"}
    )
    assert meanwhile.status_code == 200, meanwhile.text
    assert meanwhile.json()["outcome"]["status"] == "failed", meanwhile.text
    assert "the flight controller is rebooting" in meanwhile.json()["outcome"]["message"]
    watcher.wait_until(
        lambda v: not state_of(v, vehicle).get("fcu_connected", True),
        15,
        "the flight controller to go quiet while it reboots",
    )
    back = watcher.wait_until(
        lambda v: (
            state_of(v, vehicle).get("fcu_connected")
            and state_of(v, vehicle).get("mode") == "STABILIZE"
        ),
        30,
        "the flight controller back, freshly booted",
    )
    assert back[vehicle]["connected"]
    assert send_command(api, vehicle, name="set_mode", mode="GUIDED")["status"] == "accepted"


def test_a_bad_mission_item_is_refused_with_its_index(
    api: httpx.Client, watcher: FleetWatcher
) -> None:
    vehicle = "sim_1"
    watcher.wait_until(lambda v: state_of(v, vehicle).get("lat") is not None, 60, "a position")
    here = state_of(watcher.vehicles, vehicle)
    good = {"command": 16, "lat": here["lat"] + 20 * NORTH, "lon": here["lon"], "alt": 10}
    before = api.get(f"/api/v1/vehicles/{vehicle}/mission").json()["items"]
    response = api.post(
        f"/api/v1/vehicles/{vehicle}/mission",
        json={"items": [{"command": 22, "alt": 10}, good, {**good, "param1": -4, "command": 19}]},
    )
    # checked by the hub, before anything reaches the agent or the vehicle
    assert response.status_code == 422, response.text
    assert response.json()["violations"] == [
        {
            "rule": "mission_item",
            "message": "item 3 (NAV_LOITER_TIME): loiter time -4 s is negative",
            "limit": None,
            "value": None,
            "items": [3],
        }
    ]
    assert api.get(f"/api/v1/vehicles/{vehicle}/mission").json()["items"] == before


def test_the_fleet_plan_can_name_frames(tmp_path: Path) -> None:
    plan = FleetPlan(data_dir=tmp_path, frames=("quad", "rover"), autopilots=("px4",))
    # Each vehicle is set up for the agent as a user would set up a real one: PX4's
    # deadman hold exempt from its manual-control-loss failsafe, ArduPilot's GCS id.
    assert plan.vehicle_sim_args(0) == [
        *("--frame", "quad", "--autopilot", "px4"),
        *("--param", "COM_RCL_EXCEPT=2"),
    ]
    assert plan.vehicle_sim_args(1) == ["--frame", "rover", "--param", "SYSID_MYGCS=254"]
    assert plan.vehicle_sim_args(2) == ["--param", "SYSID_MYGCS=254"]
