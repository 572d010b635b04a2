"""What the manual-control flights share (tests/integration/manual_control/): the two
copters' names, a parameter set through the hub, a button pressed on the stick stream,
and a mission taken over by hand and resumed, which ArduPilot and PX4 fly alike but for
their mode names."""

from __future__ import annotations

import math
import threading
from typing import Any

import httpx

from tests.support.api import send_command
from tests.support.pilots import Pilot
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, speed_of

PX4_VEHICLE = "sim_2"
WAYPOINT = 16
OPERATOR_PASSWORD = "stick-and-rudder-42"
NORTH = 1 / 111_320.0  # degrees of latitude in a metre


def set_param(api: httpx.Client, vehicle: str, name: str, value: float) -> None:
    answer = api.put(f"/api/v1/vehicles/{vehicle}/params/{name}", json={"value": value})
    assert answer.status_code == 200, answer.text


def metres_moved(before: dict[str, Any], after: dict[str, Any]) -> tuple[float, float]:
    """North and east metres between two states (flat earth: a few tens of metres)."""
    north = (after["lat"] - before["lat"]) * 111_320.0
    east = (after["lon"] - before["lon"]) * 111_320.0 * math.cos(math.radians(before["lat"]))
    return north, east


def press(pilot: Pilot, bit: int) -> None:
    """Hold a button for a few frames of the stream, as a thumb does."""
    pilot.buttons = bit
    sent = pilot.seq
    poll_until(lambda: pilot.seq >= sent + 5, 5, "five frames with the button", every_s=0.05)
    pilot.buttons = 0


def start_a_mission(
    api: httpx.Client,
    watcher: FleetWatcher,
    vehicle: str,
    *,
    mode: str,
    first_north_m: float,
    alt: float,
) -> None:
    """Out ``first_north_m`` metres, on to 60 m north and back overhead, at ``alt``,
    started in the autopilot's mission ``mode``; back once it flies to item 2."""
    here = watcher.state(vehicle)
    items = [
        {
            "command": WAYPOINT,
            "lat": here["lat"] + north_m * NORTH,
            "lon": here["lon"],
            "alt": alt,
        }
        for north_m in (first_north_m, 60, 0)
    ]
    uploaded = api.post(f"/api/v1/vehicles/{vehicle}/mission", json={"items": items})
    assert uploaded.status_code == 200, uploaded.text
    started = send_command(api, vehicle, name="set_mode", mode=mode)
    assert started["status"] == "accepted", started
    watcher.wait_until(
        lambda v: v[vehicle]["state"].get("mission_current") == 2, 60, "on its way to item 2"
    )


def pause_by_hand_and_resume(
    api: httpx.Client,
    watcher: FleetWatcher,
    pilot: Pilot,
    *,
    mode: str,
    pilot_mode: str,
    paused_event: str | None = None,
) -> None:
    """Take the flying mission by hand: centred sticks pause it in ``pilot_mode`` at
    item 2, the lease and its release offer ``mode`` to resume, and ``mode`` carries on
    from item 2, not from the start. ``paused_event``: what the live feed says on taking."""
    vehicle = pilot.vehicle
    stop = threading.Event()
    streamer = threading.Thread(target=pilot.stream, args=(stop, 0), daemon=True)
    try:
        granted = pilot.take()
        assert granted.get("resume_mode") == mode, granted
        if paused_event is not None:
            assert pilot.events(paused_event)
        streamer.start()  # centred sticks: the vehicle stops and stays
        paused = watcher.wait_until(
            lambda v: (
                v[vehicle]["state"]["mode"] == pilot_mode and speed_of(v[vehicle]["state"]) < 0.3
            ),
            20,
            f"the mission paused in {pilot_mode}",
        )[vehicle]["state"]
        assert paused["mission_current"] == 2
        stop.set()
        streamer.join(5)
        pilot.control("release")
        released = poll_until(lambda: pilot.leases(None, "released"), 5, "the release")
        assert released[-1]["resume_mode"] == mode  # the dashboard offers to resume

        resumed = send_command(api, vehicle, name="set_mode", mode=mode)
        assert resumed["status"] == "accepted", resumed
        watcher.wait_until(
            lambda v: v[vehicle]["state"]["mode"] == mode and speed_of(v[vehicle]["state"]) > 1.0,
            20,
            "the mission resumed",
        )
        assert watcher.state(vehicle)["mission_current"] >= 2
        watcher.wait_until(
            lambda v: v[vehicle]["state"].get("mission_current") == 3, 60, "item 3 next"
        )
        assert send_command(api, vehicle, name="hold")["status"] == "accepted"
    finally:
        stop.set()
        if streamer.is_alive():
            streamer.join(5)
        pilot.close()
