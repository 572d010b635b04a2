"""Missions through the hub: checked against the rails, uploaded with the MAVLink mission
protocol, read back, refused items reported honestly, and flown in AUTO."""

from __future__ import annotations

from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.launcher import LocalFleet
from tests.support.api import api_client
from tests.support.watcher import FleetWatcher

pytestmark = pytest.mark.integration

VEHICLE = "sim_1"
TAKEOFF = mavlink2.MAV_CMD_NAV_TAKEOFF
WAYPOINT = mavlink2.MAV_CMD_NAV_WAYPOINT
RTL = mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH
DO_SET_SERVO = mavlink2.MAV_CMD_DO_SET_SERVO


def _mission(lat: float, lon: float, alt: float) -> list[dict[str, Any]]:
    return [
        {"command": TAKEOFF, "alt": alt},
        {"command": WAYPOINT, "lat": lat + 30 / 111_320, "lon": lon, "alt": alt},
        {"command": RTL},
    ]


def _ready(vehicles: dict[str, dict[str, Any]]) -> bool:
    state = (vehicles.get(VEHICLE) or {}).get("state") or {}
    return bool(
        vehicles.get(VEHICLE, {}).get("connected")
        and state.get("gps_fix", 0) >= 3
        and state.get("battery_remaining") is not None
        and state.get("home_lat") is not None
        and not state.get("armed")
        and (state.get("alt_rel") or 0) < 0.5
    )


def test_mission_checked_uploaded_read_back_and_flown(
    fleet: LocalFleet,
    fleet_admin_token: str,
    settled_fleet: LocalFleet,  # landed before it flies, and landed again after, pass or fail
) -> None:
    base = fleet.plan.hub_http
    url = f"/api/v1/vehicles/{VEHICLE}/mission"
    with (
        FleetWatcher(base, fleet_admin_token) as watcher,
        api_client(base, fleet_admin_token) as api,
    ):
        watcher.wait_until(_ready, 60, f"{VEHICLE} ready on the ground")
        here = watcher.state(VEHICLE)

        too_high = api.post(url, json={"items": _mission(here["lat"], here["lon"], 150)})
        assert too_high.status_code == 422
        assert {v["rule"] for v in too_high.json()["violations"]} >= {"max_altitude"}

        uploaded = api.post(url, json={"items": _mission(here["lat"], here["lon"], 10)})
        assert uploaded.status_code == 200, uploaded.text
        items = api.get(url).json()["items"]
        assert [item["command"] for item in items[1:]] == [TAKEOFF, WAYPOINT, RTL]
        assert items[2]["lat"] == pytest.approx(here["lat"] + 30 / 111_320, abs=1e-6)

        # An item the vehicle does not support: refused, and the old mission stays.
        unsupported = [*_mission(here["lat"], here["lon"], 10), {"command": DO_SET_SERVO}]
        rejected = api.post(url, json={"items": unsupported})
        assert rejected.status_code == 409
        assert "keeps its previous mission" in rejected.json()["detail"]
        assert len(api.get(url).json()["items"]) == 4

        commands = f"/api/v1/vehicles/{VEHICLE}/commands"
        assert api.post(commands, json={"name": "set_mode", "mode": "GUIDED"}).status_code == 200
        assert api.post(commands, json={"name": "arm"}).json()["outcome"]["status"] == "accepted"
        auto = api.post(commands, json={"name": "set_mode", "mode": "AUTO"})
        assert auto.json()["outcome"]["status"] == "accepted", auto.text

        watcher.wait_until(lambda v: (v[VEHICLE]["state"]["alt_rel"] or 0) > 8, 60, "climb")
        watcher.wait_until(
            lambda v: not v[VEHICLE]["state"]["armed"], 120, "the mission to end in a landing"
        )
        state = watcher.state(VEHICLE)
        assert state["mode"] in ("RTL", "LAND", "AUTO")
        assert (state["alt_rel"] or 0) < 0.5
        assert state["mission_current"] is not None
        # Mission progress reached the flight log as events.
        events = api.get("/api/v1/events", params={"vehicle_id": VEHICLE, "kind": "mission"})
        assert any("reached mission item" in e["text"] for e in events.json()["events"])
