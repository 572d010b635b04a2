"""A formation of the fleet's three copters: who flies where, and getting them all up."""

from __future__ import annotations

from typing import Any

import httpx

from common.geodesy import LocalFrame
from tests.support.api import send_command
from tests.support.watcher import FleetWatcher, ready

LEADER, RIGHT, LEFT = "sim_1", "sim_3", "sim_2"  # the right slot is on the sim_3 side


ALTITUDES = {LEADER: 8.0, RIGHT: 2.0, LEFT: 3.0}


SIDE_M, SPEED_MS, PAUSE_S = 20.0, 1.5, 2.0


MIN_SEPARATION_M = 2.0


def take_off_all(watcher: FleetWatcher, api: httpx.Client, altitudes: dict[str, float]) -> None:
    """Each vehicle ready, in GUIDED, armed and climbing to its altitude; back once all
    are there."""
    for vehicle, altitude in altitudes.items():
        watcher.wait_until(ready(vehicle), 60, f"{vehicle} ready")
        assert send_command(api, vehicle, name="set_mode", mode="GUIDED")["status"] == "accepted"
        assert send_command(api, vehicle, name="arm")["status"] == "accepted"
        outcome = send_command(api, vehicle, name="takeoff", altitude=altitude)
        assert outcome["status"] == "accepted"
    for vehicle, altitude in altitudes.items():
        watcher.wait_until(
            lambda v, n=vehicle, a=altitude: (v[n]["state"]["alt_rel"] or 0) >= a - 0.3,
            60,
            f"{vehicle} at {altitude} m",
        )


def _square(frame: LocalFrame) -> list[dict[str, float]]:
    out = []
    for north, east in [(0, 0), (SIDE_M, 0), (SIDE_M, SIDE_M), (0, SIDE_M), (0, 0)]:
        lat, lon = frame.to_geo(east, north)
        out.append({"lat": lat, "lon": lon, "alt_m": ALTITUDES[LEADER]})
    return out


def _request(frame: LocalFrame, **overrides: Any) -> dict[str, Any]:
    body: dict[str, Any] = {
        "leader_id": LEADER,
        "route": _square(frame),
        "speed_ms": SPEED_MS,
        "pause_s": PAUSE_S,
        "followers": [
            {"vehicle_id": RIGHT, "up": ALTITUDES[RIGHT] - ALTITUDES[LEADER]},
            {"vehicle_id": LEFT, "up": ALTITUDES[LEFT] - ALTITUDES[LEADER]},
        ],
        "shape": "triangle",
        "spacing_m": 3.0,
        "min_separation_m": MIN_SEPARATION_M,
    }
    body.update(overrides)
    return body
