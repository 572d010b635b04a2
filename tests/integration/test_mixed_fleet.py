"""A mixed fleet through the hub: an ArduPilot Rover and a quadcopter playing PX4 connect,
list their own modes, and do what their autopilots do with the same REST commands."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.launcher import LocalFleet
from tests.support.api import access_token, api_client, send_command
from tests.support.processes import running_fleet
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, ready, speed_of, state_of

pytestmark = pytest.mark.integration

ROVER, PX4 = "sim_1", "sim_2"
NORTH = 1 / 111_320
WAYPOINT = mavlink2.MAV_CMD_NAV_WAYPOINT
RTL = mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalFleet]:
    with running_fleet(
        tmp_path_factory.mktemp("mixed-fleet"),
        vehicles=2,
        speedup=5.0,
        frames=("rover", "quad"),
        autopilots=("ardupilot", "px4"),
    ) as local_fleet:
        yield local_fleet


@pytest.fixture
def clients(fleet: LocalFleet) -> Iterator[tuple[httpx.Client, FleetWatcher]]:
    base = fleet.plan.hub_http
    token = access_token(base, "admin", fleet.plan.admin_password)
    with api_client(base, token) as api, FleetWatcher(base, token) as watcher:
        yield api, watcher


def listed_once_ready(
    clients: tuple[httpx.Client, FleetWatcher], vehicle: str, what: str
) -> dict[str, Any]:
    """The vehicle's summary from the REST API, once the watcher has seen it ready."""
    api, watcher = clients
    watcher.wait_until(ready(vehicle), 60, f"{what} ready")
    summary: dict[str, Any] = api.get(f"/api/v1/vehicles/{vehicle}").json()
    return summary


def survey_north_of(lat: float, lon: float) -> dict[str, Any]:
    """A survey request for the PX4 copter: a field 40 to 120 m north of it."""
    east = NORTH / 0.8  # about a metre east at the simulator's home latitude
    ring = [
        [lon, lat + 40 * NORTH],
        [lon + 120 * east, lat + 40 * NORTH],
        [lon + 120 * east, lat + 120 * NORTH],
        [lon, lat + 120 * NORTH],
        [lon, lat + 40 * NORTH],
    ]
    return {
        "area": {"type": "Polygon", "coordinates": [ring]},
        "camera": "sony_a6000_16mm",
        "altitude_m": 40,
        "angle_deg": 0,
        "vehicle_ids": [PX4],
    }


def test_rover_connects_lists_rover_modes_and_drives_a_mission(
    clients: tuple[httpx.Client, FleetWatcher],
) -> None:
    api, watcher = clients
    rover = listed_once_ready(clients, ROVER, "the rover")
    assert (rover["vehicle_type"], rover["autopilot"]) == ("rover", "ardupilot")
    assert {"MANUAL", "HOLD", "AUTO", "GUIDED", "RTL", "SMART_RTL"} <= set(rover["modes"])
    assert "LAND" not in rover["modes"]
    assert rover["state"]["mode"] == "MANUAL"

    takeoff = send_command(api, ROVER, name="takeoff", altitude=10)
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

    assert send_command(api, ROVER, name="set_mode", mode="AUTO")["status"] == "accepted"
    assert send_command(api, ROVER, name="arm")["status"] == "accepted"  # Rover arms in AUTO
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
    assert send_command(api, ROVER, name="disarm")["status"] == "accepted"


def test_px4_copter_lists_px4_modes_and_reports_them_decoded(
    clients: tuple[httpx.Client, FleetWatcher],
) -> None:
    """PX4 lists its own modes (AVAILABLE_MODES): the hub offers those, under the names
    the agent gives every PX4 mode (pymavlink's where it has one), and none PX4 lacks
    (RATTITUDE, RTGS) or keeps from the user (Termination, unregistered external modes)."""
    api, watcher = clients
    listed_once_ready(clients, PX4, "the PX4 copter")
    # The list comes after the hello, once the agent has read it off the autopilot.
    watcher.wait_until(
        lambda v: "PRECISION_LANDING" in v[PX4].get("modes", []), 20, "PX4's own mode list"
    )
    copter = api.get(f"/api/v1/vehicles/{PX4}").json()
    assert (copter["vehicle_type"], copter["autopilot"]) == ("multirotor", "px4")
    assert sorted(copter["modes"]) == [
        "ACRO",
        "ALTCTL",
        "FOLLOWME",
        "LAND",
        "LOITER",
        "MANUAL",
        "MISSION",
        "OFFBOARD",
        "ORBIT",
        "POSCTL",
        "PRECISION_LANDING",
        "RTL",
        "STABILIZED",
        "TAKEOFF",
        "VTOL_TAKEOFF",
    ]
    assert copter["state"]["mode"] == "MANUAL"
    refused = api.post(
        f"/api/v1/vehicles/{PX4}/commands", json={"name": "set_mode", "mode": "RATTITUDE"}
    )
    assert refused.status_code == 422, refused.text

    assert send_command(api, PX4, name="set_mode", mode="POSCTL")["status"] == "accepted"
    watcher.wait_until(lambda v: state_of(v, PX4).get("mode") == "POSCTL", 10, "POSCTL")
    assert send_command(api, PX4, name="hold")["status"] == "accepted"  # PX4's Hold: AUTO.LOITER
    watcher.wait_until(lambda v: state_of(v, PX4).get("mode") == "LOITER", 10, "Hold")

    # PX4 accepts OFFBOARD without a setpoint stream and stays in Hold: not a change.
    offboard = send_command(api, PX4, name="set_mode", mode="OFFBOARD")
    assert offboard["status"] == "failed", offboard
    assert offboard["result"] == "MAV_RESULT_ACCEPTED"
    assert offboard["message"] == "OFFBOARD: accepted but the mode stayed LOITER"
    assert state_of(watcher.vehicles, PX4).get("mode") == "LOITER"

    assert send_command(api, PX4, name="takeoff", altitude=8)["status"] == "accepted"
    watcher.wait_until(lambda v: state_of(v, PX4).get("mode") == "TAKEOFF", 10, "Takeoff mode")
    watcher.wait_until(
        lambda v: (
            state_of(v, PX4).get("mode") == "LOITER"
            and abs((state_of(v, PX4).get("alt_rel") or 0) - 8) < 0.3
        ),
        60,
        "at 8 m, holding",
    )
    assert send_command(api, PX4, name="land")["status"] == "accepted"
    watcher.wait_until(lambda v: state_of(v, PX4).get("mode") == "LAND", 10, "Land mode")
    watcher.wait_until(lambda v: not state_of(v, PX4).get("armed"), 120, "landed and disarmed")


def test_px4_missions_start_at_item_zero_on_the_wire_and_number_as_everywhere(
    clients: tuple[httpx.Client, FleetWatcher],
) -> None:
    """PX4 keeps no home item: the agent sends the mission as it is (a placeholder would
    be a waypoint at 0°N 0°E), and the hub still numbers items from 1, home being 0."""
    api, watcher = clients
    state = listed_once_ready(clients, PX4, "the PX4 copter")["state"]
    lat, lon = state["lat"], state["lon"]
    items = [
        {"command": WAYPOINT, "lat": lat + 20 * NORTH, "lon": lon, "alt": 10},
        {"command": WAYPOINT, "lat": lat + 40 * NORTH, "lon": lon, "alt": 10},
        {"command": RTL},
    ]
    url = f"/api/v1/vehicles/{PX4}/mission"
    assert api.post(url, json={"items": items}).status_code == 200
    stored = api.get(url).json()["items"]
    assert len(stored) == 4, "home (from HOME_POSITION) and the three items, nothing else"
    assert stored[0]["lat"] == pytest.approx(state["home_lat"], abs=1e-6)
    assert [item["command"] for item in stored[1:]] == [WAYPOINT, WAYPOINT, RTL]
    assert stored[1]["lat"] == pytest.approx(lat + 20 * NORTH, abs=1e-6)
    current = send_command(api, PX4, name="mission_set_current", seq=2)
    assert current["status"] == "accepted", current
    watcher.wait_until(lambda v: state_of(v, PX4).get("mission_current") == 2, 10, "item 2")


def test_px4s_mission_mode_flies_only_a_checked_mission(
    clients: tuple[httpx.Client, FleetWatcher],
) -> None:
    """PX4's mission mode is MISSION in the modes the agent lists, not AUTO: the hub's
    mission check before AUTO holds for it too (issue 12.12)."""
    api, watcher = clients
    state = listed_once_ready(clients, PX4, "the PX4 copter")["state"]
    url = f"/api/v1/vehicles/{PX4}/mission"
    assert api.delete(url).status_code == 200
    refused = api.post(
        f"/api/v1/vehicles/{PX4}/commands", json={"name": "set_mode", "mode": "MISSION"}
    )
    assert refused.status_code == 422, refused.text
    assert [v["rule"] for v in refused.json()["violations"]] == ["mission_unchecked"]
    assert state_of(watcher.vehicles, PX4).get("mode") != "MISSION"

    lat, lon = state["lat"], state["lon"]
    items = [{"command": WAYPOINT, "lat": lat + 20 * NORTH, "lon": lon, "alt": 10}]
    assert api.post(url, json={"items": items}).status_code == 200
    try:
        assert send_command(api, PX4, name="set_mode", mode="MISSION")["status"] == "accepted"
        watcher.wait_until(lambda v: state_of(v, PX4).get("mode") == "MISSION", 10, "MISSION")
    finally:
        send_command(api, PX4, name="hold")
        api.delete(url)


def test_px4_s_survey_takes_off_where_it_stands_and_a_take_off_at_zero_is_refused(
    clients: tuple[httpx.Client, FleetWatcher],
) -> None:
    """PX4 climbs, then flies to a take-off item's position: a survey's take-off carries
    the drone's own position, and the check refuses a take-off at 0, 0 naming it."""
    api, _ = clients
    state = listed_once_ready(clients, PX4, "the PX4 copter")["state"]
    lat, lon = state["lat"], state["lon"]
    survey = survey_north_of(lat, lon)
    preview = api.post("/api/v1/surveys/preview", json=survey)
    assert preview.status_code == 200, preview.text
    [part] = preview.json()["parts"]
    takeoff = part["mission"]["items"][0]
    assert takeoff["command"] == mavlink2.MAV_CMD_NAV_TAKEOFF
    assert takeoff["lat"] == pytest.approx(lat, abs=2 * NORTH)
    assert takeoff["lon"] == pytest.approx(lon, abs=2 * NORTH)
    assert part["check"]["ok"] is True, part["check"]

    at_zero = [{**takeoff, "lat": 0, "lon": 0}, *part["mission"]["items"][1:]]
    checked = api.post(f"/api/v1/vehicles/{PX4}/mission-check", json={"items": at_zero})
    assert checked.status_code == 200, checked.text
    assert checked.json()["ok"] is False
    rules = {v["rule"]: v for v in checked.json()["violations"]}
    assert rules["mission_item"]["items"] == [1]
    assert rules["mission_item"]["message"].startswith(
        "item 1 (NAV_TAKEOFF): latitude and longitude are 0, 0: PX4 flies to a take-off's position"
    )
    assert rules["max_distance_from_home"]["items"] == [1]


def test_a_px4_survey_starts_as_qgc_starts_a_mission_mission_mode_then_arm(
    clients: tuple[httpx.Client, FleetWatcher],
) -> None:
    """PX4's mission mode is MISSION in its mode list (AUTO.MISSION in PX4's own terms),
    and PX4 does not arm itself in it: the survey's launch sets it, then arms, and the
    copter takes off on the mission's take-off item and flies its lanes."""
    api, watcher = clients
    # On the ground as the survey judges it: disarmed, and landed by the autopilot's word
    # (a landing just ended still reads "landing" for a moment).
    watcher.wait_until(
        lambda v: (
            ready(PX4)(v)
            and not state_of(v, PX4).get("armed")
            and state_of(v, PX4).get("landed_state") == "on_ground"
        ),
        120,
        "on the ground",
    )
    state = listed_once_ready(clients, PX4, "the PX4 copter")["state"]
    created = api.post("/api/v1/surveys", json=survey_north_of(state["lat"], state["lon"]))
    assert created.status_code == 201, created.text
    survey_id = created.json()["survey"]["id"]
    try:
        started = api.post(f"/api/v1/surveys/{survey_id}/start")
        assert started.status_code == 200, started.text
        progress = started.json()["progress"]
        assert progress["state"] == "flying", progress
        assert [d["state"] for d in progress["drones"]] == ["flying"], progress
        watcher.wait_until(
            lambda v: (
                state_of(v, PX4).get("mode") == "MISSION"
                and state_of(v, PX4).get("armed") is True
                and (state_of(v, PX4).get("alt_rel") or 0) > 10
            ),
            60,
            "armed in MISSION, climbing on the take-off item",
        )
    finally:
        api.post(f"/api/v1/surveys/{survey_id}/abort")
    watcher.wait_until(lambda v: state_of(v, PX4).get("mode") == "RTL", 30, "sent home")
    watcher.wait_until(lambda v: not state_of(v, PX4).get("armed"), 180, "home and disarmed")


def test_a_px4_flying_its_mission_runs_a_do_item_made_current_at_once_and_moves_on(
    clients: tuple[httpx.Client, FleetWatcher],
) -> None:
    """PX4 (as ArduPilot) runs a DO_ item made current at once and goes on to the next NAV
    item: MISSION_CURRENT never names the DO_ item, and the request is still accepted."""
    api, watcher = clients
    watcher.wait_until(
        lambda v: ready(PX4)(v) and not state_of(v, PX4).get("armed"), 120, "on the ground"
    )
    state = listed_once_ready(clients, PX4, "the PX4 copter")["state"]
    lat, lon = state["lat"], state["lon"]
    items = [
        {"command": mavlink2.MAV_CMD_NAV_TAKEOFF, "lat": lat, "lon": lon, "alt": 10},
        {"command": WAYPOINT, "lat": lat + 30 * NORTH, "lon": lon, "alt": 10},
        {"command": mavlink2.MAV_CMD_DO_CHANGE_SPEED, "param1": 1, "param2": 4, "param3": -1},
        {"command": WAYPOINT, "lat": lat + 60 * NORTH, "lon": lon, "alt": 10},
        {"command": RTL},
    ]
    url = f"/api/v1/vehicles/{PX4}/mission"
    assert api.post(url, json={"items": items}).status_code == 200
    try:
        assert send_command(api, PX4, name="set_mode", mode="MISSION")["status"] == "accepted"
        assert send_command(api, PX4, name="arm")["status"] == "accepted"
        watcher.wait_until(
            lambda v: (state_of(v, PX4).get("alt_rel") or 0) > 2, 30, "climbing on item 1"
        )
        current = api.put(f"{url}/current", json={"seq": 3})
        assert current.status_code == 200, current.text
        assert current.json()["outcome"]["message"] == "item 3 ran at once; current item is 4"
        watcher.wait_until(lambda v: state_of(v, PX4).get("mission_current") == 4, 10, "item 4")
    finally:
        send_command(api, PX4, name="rtl")
        watcher.wait_until(lambda v: not state_of(v, PX4).get("armed"), 180, "home, disarmed")
        api.delete(url)


def test_px4s_parameter_metadata_refuses_a_value_outside_it_and_explains_each(
    clients: tuple[httpx.Client, FleetWatcher],
) -> None:
    """PX4 stores whatever PARAM_SET says (it checks no range): the agent reads PX4's own
    parameter metadata (COMPONENT_METADATA, then its xz files over MAVLink FTP) and refuses
    a value outside it before it is sent. The answers say what a parameter means."""
    api, _watcher = clients
    listed_once_ready(clients, PX4, "the PX4 copter")
    url = f"/api/v1/vehicles/{PX4}/params/COM_RC_IN_MODE"
    read = poll_until(
        lambda: (answer := api.get(url).json()).get("metadata") and answer,
        30,
        "the metadata read off the autopilot",
    )
    assert read["values"] == {"COM_RC_IN_MODE": 3.0}
    meta = read["metadata"]
    assert meta["source"] == "autopilot"
    assert meta["description"] == "Manual control input source configuration"
    assert [v["value"] for v in meta["values"]] == [0, 1, 2, 3, 4]
    assert meta["values"][4]["description"] == "Disable manual control"

    refused = api.put(url, json={"value": 9})
    assert refused.status_code == 409, refused.text
    assert (
        "COM_RC_IN_MODE: 9 is not one of the values it takes (0 RC Transmitter only, "
        "1 MAVLink only, 2 RC and MAVLink with fallback, 3 RC or MAVLink keep first, "
        "4 Disable manual control)" in refused.json()["detail"]
    )
    assert api.get(url).json()["values"] == {"COM_RC_IN_MODE": 3.0}  # never sent

    too_high = api.put(f"/api/v1/vehicles/{PX4}/params/MIS_TAKEOFF_ALT", json={"value": 100})
    assert too_high.status_code == 409, too_high.text
    assert "MIS_TAKEOFF_ALT: 100 is outside its range 0..80 m" in too_high.json()["detail"]

    written = api.put(f"/api/v1/vehicles/{PX4}/params/MIS_TAKEOFF_ALT", json={"value": 3})
    assert written.status_code == 200, written.text
    assert written.json()["range_checked"] is True
    assert written.json()["metadata"]["units"] == "m"
    assert api.put(f"/api/v1/vehicles/{PX4}/params/MIS_TAKEOFF_ALT", json={"value": 2.5}).is_success
