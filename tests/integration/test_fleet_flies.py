"""The walking skeleton end to end: real hub, simulator and agent processes on loopback."""

from __future__ import annotations

import sqlite3
import time
from typing import Any

import httpx
import pytest

from gcs.launcher import LocalFleet
from tests.support.api import api_client
from tests.support.mavutil_state import mavutil_in_mavlink2
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher

pytestmark = pytest.mark.integration

TAKEOFF_ALTITUDE_M = 10.0


def wait_for_closed_flight(api: httpx.Client, vehicle: str, since: float) -> dict[str, Any]:
    """The live feed shows the disarm before the writer has stored it; poll the store."""

    def closed() -> list[dict[str, Any]]:
        flights = api.get("/api/v1/flights", params={"vehicle_id": vehicle}).json()["flights"]
        return [f for f in flights if f["start_time"] >= since and f["end_time"] is not None]

    # the batching writer flushes every 0.25 s
    return dict(poll_until(closed, 10, f"a closed flight of {vehicle}", every_s=0.1)[0])


def watch_for_tlog(api: httpx.Client, vehicle: str) -> dict[str, Any]:
    """The agent uploads after landing; poll the hub's list until it arrives."""
    tlogs = poll_until(
        lambda: api.get(f"/api/v1/vehicles/{vehicle}/tlogs").json(), 30, "the onboard .tlog"
    )
    return dict(tlogs[-1])


def _ready(vehicles: dict[str, dict[str, Any]], count: int) -> bool:
    """Connected, with a 3D fix reported (GPS_RAW_INT may trail the first snapshot)."""
    return (
        sum(
            1
            for v in vehicles.values()
            if v["connected"] and (v["state"] or {}).get("gps_fix", 0) >= 3
        )
        >= count
    )


def test_arm_takeoff_land_through_rest(
    fleet: LocalFleet,
    fleet_admin_token: str,
    monkeypatch: pytest.MonkeyPatch,
    settled_fleet: LocalFleet,  # landed before it flies, and landed again after, pass or fail
) -> None:
    base = fleet.plan.hub_http
    vehicle = fleet.vehicle_id(0)
    with (
        FleetWatcher(base, fleet_admin_token) as watcher,
        api_client(base, fleet_admin_token) as api,
    ):
        watcher.wait_until(lambda v: _ready(v, 3), 30, "three connected vehicles with GPS")
        listed = api.get("/api/v1/vehicles").json()
        assert sorted(v["id"] for v in listed) == ["sim_1", "sim_2", "sim_3"]
        assert all(v["state"]["lat"] is not None for v in listed)

        grounded = [
            other
            for other in ("sim_2", "sim_3")
            if not watcher.state(other)["armed"] and (watcher.state(other)["alt_rel"] or 0) < 1
        ]
        mode = api.post(
            f"/api/v1/vehicles/{vehicle}/commands", json={"name": "set_mode", "mode": "GUIDED"}
        )
        assert mode.json()["outcome"]["status"] == "accepted", mode.text
        armed = api.post(f"/api/v1/vehicles/{vehicle}/commands", json={"name": "arm"})
        assert armed.status_code == 200, armed.text
        # Whether it flies: the autopilot's own answer (EXTENDED_SYS_STATE), not a guess.
        on_pad = watcher.wait_until(lambda v: v[vehicle]["state"]["armed"], 10, f"{vehicle} armed")[
            vehicle
        ]["state"]
        assert (on_pad["landed_state"], on_pad["landed_state_source"]) == ("on_ground", "autopilot")
        assert armed.json()["outcome"]["status"] == "accepted"
        assert armed.json()["outcome"]["result"] == "MAV_RESULT_ACCEPTED"

        takeoff = api.post(
            f"/api/v1/vehicles/{vehicle}/commands",
            json={"name": "takeoff", "altitude": TAKEOFF_ALTITUDE_M},
        )
        assert takeoff.json()["outcome"]["status"] == "accepted", takeoff.text
        started_at = time.time()

        watcher.wait_until(
            lambda v: (v[vehicle]["state"]["alt_rel"] or 0) >= TAKEOFF_ALTITUDE_M - 1,
            60,
            f"{vehicle} to climb to {TAKEOFF_ALTITUDE_M} m",
        )
        # It holds at the target rather than overshooting.
        watcher.wait_until(
            lambda v: (
                abs(v[vehicle]["state"]["climb_rate"] or 0) < 0.2
                and abs((v[vehicle]["state"]["alt_rel"] or 0) - TAKEOFF_ALTITUDE_M) <= 1
            ),
            30,
            f"{vehicle} to hold {TAKEOFF_ALTITUDE_M} m ± 1 m",
        )
        assert watcher.state(vehicle)["armed"] is True
        # EXTENDED_SYS_STATE comes at 1 Hz: the take-off ends within a second of the hold.
        watcher.wait_until(
            lambda v: v[vehicle]["state"]["landed_state"] == "in_air", 5, f"{vehicle} in air"
        )
        assert watcher.state(vehicle)["landed_state_source"] == "autopilot"
        # Its take-off time is the hub's, the same for a page opened now (a reload).
        took_off = api.get(f"/api/v1/vehicles/{vehicle}").json()["airborne_since"]
        assert took_off is not None
        assert started_at - 5 <= took_off <= started_at + 10
        with FleetWatcher(base, fleet_admin_token) as reloaded:
            snapshot = reloaded.wait_until(lambda v: vehicle in v, 10, f"{vehicle} listed")
            assert snapshot[vehicle]["airborne_since"] == took_off
        # The other vehicles stayed on the ground.
        # The vehicles that were on the ground stayed there (the fleet is shared with
        # the browser test, which may have flown another one).
        assert all((watcher.state(other)["alt_rel"] or 0) < 1 for other in grounded)

        land = api.post(f"/api/v1/vehicles/{vehicle}/commands", json={"name": "land"})
        assert land.json()["outcome"]["status"] == "accepted", land.text
        watcher.wait_until(
            lambda v: v[vehicle]["state"]["mode"] == "LAND", 10, f"{vehicle} in LAND mode"
        )
        watcher.wait_until(
            lambda v: not v[vehicle]["state"]["armed"], 90, f"{vehicle} to land and disarm"
        )
        assert (watcher.state(vehicle)["alt_rel"] or 0) < 0.5
        watcher.wait_until(
            lambda v: v[vehicle]["state"]["landed_state"] == "on_ground", 5, f"{vehicle} landed"
        )
        assert api.get(f"/api/v1/vehicles/{vehicle}").json()["airborne_since"] is None

        # The climb is in the stored history.
        history = api.get(
            f"/api/v1/vehicles/{vehicle}/telemetry",
            params={"start": started_at - 5, "end": time.time() + 1, "limit": 10000},
        ).json()
        altitudes = [s["alt_rel"] for s in history["samples"] if s["alt_rel"] is not None]
        assert max(altitudes) >= TAKEOFF_ALTITUDE_M - 1
        seqs = [sample["seq"] for sample in history["samples"]]
        assert seqs == sorted(seqs)
        assert len(seqs) == len(set(seqs))

        # The hub found the flight, with its summary and events, and the agent uploaded
        # the .tlog it recorded on board once it had landed.
        flight = wait_for_closed_flight(api, vehicle, since=started_at - 30)
        assert flight["max_alt_m"] >= TAKEOFF_ALTITUDE_M - 1
        kinds = {
            event["kind"]
            for event in api.get(
                "/api/v1/events",
                params={"vehicle_id": vehicle, "start": flight["start_time"] - 5},
            ).json()["events"]
        }
        assert {"armed", "disarmed", "mode"} <= kinds
        commands = api.get("/api/v1/commands", params={"vehicle_id": vehicle}).json()["commands"]
        assert {"arm", "takeoff", "land"} <= {command["name"] for command in commands}
        tlog = watch_for_tlog(api, vehicle)
        onboard = fleet.plan.data_dir / "onboard.tlog"
        onboard.write_bytes(api.get(f"/api/v1/tlogs/{tlog['id']}").content)
        log = mavutil_in_mavlink2(monkeypatch).mavlink_connection(str(onboard))
        assert log.recv_match(type="GLOBAL_POSITION_INT") is not None
        log.close()

    # And the rows are really in the database file, for every vehicle.
    database = fleet.plan.data_dir / "gcs.sqlite3"
    with sqlite3.connect(database) as connection:
        counts = dict(
            connection.execute("SELECT vehicle_id, count(*) FROM telemetry GROUP BY vehicle_id")
        )
    assert set(counts) == {"sim_1", "sim_2", "sim_3"}
    assert all(count > 10 for count in counts.values())
