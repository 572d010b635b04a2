"""Shared sensing through the hub: the leader's LIDAR sees the simulator's yard, the hub
relays its scans to the follower's agent, and the follower, whose slot lies against the
building the leader sees, holds short of it and says so. Real processes on loopback (a
two-drone fleet with LIDARs, the simulators at real time: the LIDAR's timing is the
agent's to measure, as in tests/integration/test_scans.py)."""

from __future__ import annotations

import math
import re
import time
from typing import Any

import pytest

from common.geodesy import LocalFrame
from tests.support.api import access_token, api_client
from tests.support.formations import take_off_all
from tests.support.processes import running_fleet
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher

pytestmark = [pytest.mark.integration, pytest.mark.slow]

LEADER, FOLLOWER = "sim_1", "sim_2"
ALTITUDE_M = 3.0
# The yard's building (simulator.world.obstacles.default_scene) stands 7 to 11 m east of the
# leader's home and 1 m south to 5 m north: this slot is just inside its west face.
SLOT = {"x": 2.0, "y": 7.5, "up": 0.0, "frame": "ne"}
CLEARANCE_M = 2.5


def _hold_events(watcher: FleetWatcher) -> list[dict[str, Any]]:
    return [
        e
        for e in watcher.events
        if e.get("vehicle_id") == FOLLOWER
        and e.get("kind") == "formation"
        and e["text"].startswith("hold_obstacle")
    ]


def test_a_follower_holds_short_of_the_obstacle_the_leaders_lidar_found(
    tmp_path_factory: pytest.TempPathFactory,
) -> None:
    with running_fleet(
        tmp_path_factory.mktemp("formation_scans"), vehicles=2, speedup=1.0, lidars=True
    ) as fleet:
        base = fleet.plan.hub_http
        token = access_token(base, "admin", fleet.plan.admin_password)
        with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
            take_off_all(watcher, api, {LEADER: ALTITUDE_M, FOLLOWER: ALTITUDE_M})
            here = watcher.state(LEADER)
            frame = LocalFrame(here["lat"], here["lon"])
            route = [
                {"lat": lat, "lon": lon, "alt_m": ALTITUDE_M}
                for lat, lon in (frame.to_geo(0.0, 0.0), frame.to_geo(0.0, 1.0))
            ]
            answer = api.post(
                "/api/v1/formations",
                json={
                    "leader_id": LEADER,
                    "route": route,
                    "speed_ms": 0.5,
                    "pause_s": 60.0,
                    "followers": [{"vehicle_id": FOLLOWER, "offset": SLOT}],
                    "obstacle_clearance_m": CLEARANCE_M,
                },
            )
            assert answer.status_code == 200, answer.text
            formation_id = answer.json()["id"]
            try:
                watcher.wait_until(
                    lambda v: bool(_hold_events(watcher)), 30, "the follower holding short"
                )
                text = _hold_events(watcher)[0]["text"]
                # the point it holds short of is the building's west face, as the
                # leader's scans placed it on the formation's plane
                found = re.search(r"saw at (-?[\d.]+) m north, (-?[\d.]+) m east", text)
                assert found is not None, text
                north, east = float(found[1]), float(found[2])
                assert math.dist((north, east), (SLOT["x"], SLOT["y"])) <= CLEARANCE_M, text
                assert 6.0 <= east <= 8.0, text
                # and it stays short: never within 1 m of its slot inside the building
                deadline = time.monotonic() + 3.0

                def clear_until_deadline(v: dict[str, Any]) -> bool:
                    state = v[FOLLOWER]["state"]
                    east_m, north_m = frame.to_local(state["lat"], state["lon"])
                    assert math.dist((north_m, east_m), (SLOT["x"], SLOT["y"])) > 1.0
                    return time.monotonic() > deadline

                watcher.wait_until(clear_until_deadline, 10, "three seconds held")
            finally:
                api.post(f"/api/v1/formations/{formation_id}/stop")
            poll_until(
                lambda: api.get(f"/api/v1/formations/{formation_id}").json()["stopped"],
                10,
                "the formation stopped",
            )
