"""The mission through the hub's REST API, against the session fleet: one mission body for
check and upload, every problem a 422 naming the item and the rule, a current item that
is not in the mission refused at once, and AUTO refused for a mission nobody checked."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.launcher import LocalFleet
from tests.support.api import api_client
from tests.support.simulators import mavlink_client, wait_for
from tests.support.watcher import FleetWatcher, ready, state_of

pytestmark = pytest.mark.integration

TAKEOFF = mavlink2.MAV_CMD_NAV_TAKEOFF
WAYPOINT = mavlink2.MAV_CMD_NAV_WAYPOINT
RTL = mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH
NORTH = 1 / 111_320
RELATIVE_INT = mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT


@pytest.fixture
def api(fleet: LocalFleet, fleet_admin_token: str) -> Iterator[httpx.Client]:
    with api_client(fleet.plan.hub_http, fleet_admin_token) as client:
        yield client


@pytest.fixture
def watcher(fleet: LocalFleet, fleet_admin_token: str) -> Iterator[FleetWatcher]:
    with FleetWatcher(fleet.plan.hub_http, fleet_admin_token) as watching:
        yield watching


def _mission(state: dict[str, Any], alt: float = 10) -> list[dict[str, Any]]:
    lat, lon = state["lat"], state["lon"]
    return [
        {"command": TAKEOFF, "alt": 10},
        {"command": WAYPOINT, "lat": lat + 20 * NORTH, "lon": lon, "alt": alt},
        {"command": RTL},
    ]


def test_one_mission_body_for_check_upload_and_download(
    api: httpx.Client, watcher: FleetWatcher
) -> None:
    vehicle = "sim_2"
    watcher.wait_until(ready(vehicle), 60, f"{vehicle} ready")
    mission = {"items": _mission(watcher.state(vehicle))}
    checked = api.post(f"/api/v1/vehicles/{vehicle}/mission-check", json=mission)
    assert checked.status_code == 200, checked.text
    assert checked.json()["ok"] is True
    assert api.post(f"/api/v1/vehicles/{vehicle}/mission", json=mission).status_code == 200
    downloaded = api.get(f"/api/v1/vehicles/{vehicle}/mission").json()["items"][1:]
    # what came back is a valid body for the check and the upload, unchanged
    again = api.post(f"/api/v1/vehicles/{vehicle}/mission-check", json={"items": downloaded})
    assert again.status_code == 200, again.text
    assert again.json()["ok"] is True


@pytest.mark.parametrize(
    ("items", "rule", "message"),
    [
        ([{"command": 0}], "mission_item", "item 1 (MAV_CMD 0): unknown MAV_CMD 0"),
        (
            [{"command": TAKEOFF, "alt": 10}, {"command": WAYPOINT, "alt": 10}],
            "mission_item",
            "item 2 (NAV_WAYPOINT): latitude and longitude are 0, 0",
        ),
    ],
)
def test_every_failed_check_is_a_422_naming_the_item_and_the_rule(
    api: httpx.Client, watcher: FleetWatcher, items: list[dict[str, Any]], rule: str, message: str
) -> None:
    vehicle = "sim_2"
    watcher.wait_until(ready(vehicle), 60, f"{vehicle} ready")
    refused = api.post(f"/api/v1/vehicles/{vehicle}/mission", json={"items": items})
    assert refused.status_code == 422, refused.text
    assert len(refused.json()["violations"]) == 1, refused.text
    [violation] = refused.json()["violations"]
    assert violation["rule"] == rule
    assert violation["message"].startswith(message)
    checked = api.post(f"/api/v1/vehicles/{vehicle}/mission-check", json={"items": items})
    assert checked.status_code == 200, checked.text
    assert [v["rule"] for v in checked.json()["violations"]] == [rule]


def test_a_rail_names_the_mission_item_not_the_nth_place(
    api: httpx.Client, watcher: FleetWatcher
) -> None:
    vehicle = "sim_2"
    watcher.wait_until(ready(vehicle), 60, f"{vehicle} ready")
    too_high = _mission(watcher.state(vehicle), alt=150)
    refused = api.post(f"/api/v1/vehicles/{vehicle}/mission", json={"items": too_high})
    assert refused.status_code == 422, refused.text
    [violation] = [v for v in refused.json()["violations"] if v["rule"] == "max_altitude"]
    assert "item 2 altitude" in violation["message"]


def test_the_default_rails_refuse_waypoints_below_home(
    api: httpx.Client, watcher: FleetWatcher
) -> None:
    """A relative altitude typed negative, and a sea-level altitude of 0 written for a
    home at 584 m, each fly into the ground: the default rails' minimum height above home
    refuses both in the check and the upload, naming the item and the rule."""
    vehicle = "sim_2"
    watcher.wait_until(ready(vehicle), 60, f"{vehicle} ready")
    rails = api.get(f"/api/v1/vehicles/{vehicle}/safety-rails").json()
    assert rails["min_height_above_home_m"] == 2.0
    state = watcher.state(vehicle)
    lat, lon, home_msl = state["lat"], state["lon"], state["home_alt_msl"]
    assert home_msl == pytest.approx(584.0, abs=1.0)
    need = "the rails need at least 2.0 m above home (min_height_above_home_m)"
    for frame, alt, said in (
        (mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT, -50.0, "item 2: 50.0 m below home (-50.0 m)"),
        (
            mavlink2.MAV_FRAME_GLOBAL,
            0.0,
            f"item 2: {home_msl:.1f} m below home (0.0 m above sea level; home is at "
            f"{home_msl:.1f} m)",
        ),
    ):
        items = [
            {"command": TAKEOFF, "alt": 10},
            {"command": WAYPOINT, "frame": frame, "lat": lat + 20 * NORTH, "lon": lon, "alt": alt},
            {"command": RTL},
        ]
        checked = api.post(f"/api/v1/vehicles/{vehicle}/mission-check", json={"items": items})
        assert checked.status_code == 200, checked.text
        assert checked.json()["ok"] is False
        [violation] = checked.json()["violations"]
        assert violation["rule"] == "min_height_above_home"
        assert violation["message"] == f"{said}; {need}"
        assert violation["items"] == [2]
        refused = api.post(f"/api/v1/vehicles/{vehicle}/mission", json={"items": items})
        assert refused.status_code == 422, refused.text
        assert [v["rule"] for v in refused.json()["violations"]] == ["min_height_above_home"]


def test_a_mission_without_a_place_is_checked_not_a_crash(
    api: httpx.Client, watcher: FleetWatcher
) -> None:
    vehicle = "sim_2"
    watcher.wait_until(ready(vehicle), 60, f"{vehicle} ready")
    checked = api.post(
        f"/api/v1/vehicles/{vehicle}/mission-check", json={"items": [{"command": RTL}]}
    )
    assert checked.status_code == 200, checked.text
    assert checked.json() == {"ok": True, "violations": [], "estimate": None}


def test_a_current_item_beyond_the_mission_is_refused_at_once(
    api: httpx.Client, watcher: FleetWatcher
) -> None:
    vehicle = "sim_2"
    watcher.wait_until(ready(vehicle), 60, f"{vehicle} ready")
    mission = {"items": _mission(watcher.state(vehicle))}
    assert api.post(f"/api/v1/vehicles/{vehicle}/mission", json=mission).status_code == 200
    started = time.monotonic()
    refused = api.put(f"/api/v1/vehicles/{vehicle}/mission/current", json={"seq": 88})
    took = time.monotonic() - started
    assert refused.status_code == 422, refused.text
    [error] = refused.json()["detail"]
    assert error["loc"] == ["body", "seq"]
    assert error["msg"] == "item 88 is not in the mission: it has 3 items (1..3)"
    assert took < 3, f"refused after {took:.1f} s: it waited for the vehicle"
    as_command = api.post(
        f"/api/v1/vehicles/{vehicle}/commands", json={"name": "mission_set_current", "seq": 4}
    )
    assert as_command.status_code == 422, as_command.text
    assert "it has 3 items" in as_command.text
    moved = api.put(f"/api/v1/vehicles/{vehicle}/mission/current", json={"seq": 3})
    assert moved.status_code == 200, moved.text
    watcher.wait_until(lambda v: state_of(v, vehicle).get("mission_current") == 3, 10, "item 3")


def _next(gcs: Any, system_id: int, types: list[str]) -> Any:
    what = f"{types} from system {system_id}"
    return wait_for(gcs, types, lambda _: True, 10, what, system_id=system_id)


def _load_as_another_gcs(port: int, system_id: int, items: list[Any]) -> None:
    """Upload a mission straight to the flight controller, as a second GCS would."""
    with mavlink_client(f"tcp:127.0.0.1:{port}") as gcs:
        _next(gcs, system_id, ["HEARTBEAT"])
        gcs.mav.mission_count_send(system_id, 1, len(items), 0)
        while True:
            answer = _next(gcs, system_id, ["MISSION_REQUEST_INT", "MISSION_ACK"])
            if answer.get_type() == "MISSION_ACK":
                assert answer.type == 0, answer
                return
            gcs.mav.send(items[answer.seq])


def _wire_item(system_id: int, seq: int, command: int, lat: float, lon: float, alt: float) -> Any:
    # The MAVLink 2 message (with mission_type) whatever dialect mavutil holds right now:
    # it switches to MAVLink 2 only when a connection first hears a MAVLink 2 frame.
    return mavlink2.MAVLink_mission_item_int_message(
        system_id, 1, seq, RELATIVE_INT, command, 0, 1, 0, 0, 0, 0,
        round(lat * 1e7), round(lon * 1e7), alt, 0,
    )  # fmt: skip


def test_auto_flies_only_a_checked_mission(
    fleet: LocalFleet, api: httpx.Client, watcher: FleetWatcher
) -> None:
    vehicle, index = "sim_3", 2
    watcher.wait_until(ready(vehicle), 60, f"{vehicle} ready")
    here = watcher.state(vehicle)
    lat, lon = here["lat"], here["lon"]
    # Another GCS loads a mission that climbs to 150 m: above the site's ceiling.
    _load_as_another_gcs(
        fleet.sim_ports[index],
        index + 1,
        [
            _wire_item(index + 1, 0, WAYPOINT, 0, 0, 0),  # home, replaced by the vehicle's
            _wire_item(index + 1, 1, TAKEOFF, 0, 0, 10),
            _wire_item(index + 1, 2, WAYPOINT, lat + 20 * NORTH, lon, 150),
            _wire_item(index + 1, 3, RTL, 0, 0, 0),
        ],
    )
    commands = f"/api/v1/vehicles/{vehicle}/commands"
    auto = {"name": "set_mode", "mode": "AUTO"}
    try:
        refused = api.post(commands, json=auto)
        assert refused.status_code == 422, refused.text
        assert len(refused.json()["violations"]) == 1, refused.text
        [violation] = refused.json()["violations"]
        assert violation["rule"] == "max_altitude"
        assert "item 2 altitude" in violation["message"]

        group = api.post("/api/v1/fleet/commands", json={"vehicle_ids": [vehicle], "command": auto})
        assert group.status_code == 200, group.text
        [result] = group.json()["results"]
        assert result["status_code"] == 422, result
        assert watcher.state(vehicle)["mode"] != "AUTO"

        # An admin may override, with a reason that the audit log keeps.
        reason = "checked by hand with the site lead"
        overridden = api.post(commands, params={"override_reason": reason}, json=auto)
        assert overridden.status_code == 200, overridden.text
        assert overridden.json()["outcome"]["status"] == "accepted"
        audit = api.get("/api/v1/audit", params={"action": "command", "target": vehicle})
        [entry] = [
            e for e in audit.json()["entries"] if e["detail"].get("override", {}).get("reason")
        ]
        assert entry["detail"]["override"]["violations"] == ["max_altitude"]
        assert entry["detail"]["mission_checked"] == {"items": 3, "ok": False}
    finally:
        api.post(commands, json={"name": "set_mode", "mode": "GUIDED"})
        api.delete(f"/api/v1/vehicles/{vehicle}/mission")

    # With no mission on board there is nothing checked to fly.
    empty = api.post(commands, json=auto)
    assert empty.status_code == 422, empty.text
    assert [v["rule"] for v in empty.json()["violations"]] == ["mission_unchecked"]

    # A mission that passes the check flies as before.
    assert (
        api.post(f"/api/v1/vehicles/{vehicle}/mission", json={"items": _mission(here)}).status_code
        == 200
    )
    try:
        accepted = api.post(commands, json=auto)
        assert accepted.status_code == 200, accepted.text
        assert accepted.json()["outcome"]["status"] == "accepted"
    finally:
        api.post(commands, json={"name": "set_mode", "mode": "GUIDED"})
        api.delete(f"/api/v1/vehicles/{vehicle}/mission")
