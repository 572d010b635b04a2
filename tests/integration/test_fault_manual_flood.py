"""A manual-control stream that floods: a client sends stick frames at 1000 a second for
2 s at a flying copter. Real hub, agent and simulator; a tap
between the agent and the flight controller counts the MANUAL_CONTROL that arrive.

Guaranteed: at most 100 frames a second reach the flight controller, the newest frame
among them (a flood collapses, it is not queued), and the lease and the vehicle carry on.
The deadman on a frozen or stopped stream is tests/integration/manual_control/'s.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from gcs.launcher import FleetPlan, LocalFleet, free_port
from tests.support.api import access_token, api_client
from tests.support.fcu import FcuTap
from tests.support.hubs import TEST_HUB_ENV
from tests.support.pilots import Pilot
from tests.support.settling import take_off
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, ready

pytestmark = [pytest.mark.integration, pytest.mark.slow]

VEHICLE = "sim_1"
FLOOD_S = 2.0
FLOOD_HZ = 1000  # paced, so the hub takes the frames one by one, not as one read
MAX_RATE_HZ = 100  # the hub's relay cap (ManualRelay's max_rate_hz)


@pytest.fixture
def tapped(tmp_path: Path) -> Iterator[tuple[LocalFleet, FcuTap]]:
    plan = FleetPlan(vehicles=1, port=free_port(), data_dir=tmp_path, speedup=1.0)
    with LocalFleet(plan) as fleet:
        fleet.start(TEST_HUB_ENV)
        fleet.wait_until_ready()
        # The agent again, now through the tap.
        fleet.kill("agent_1")
        with FcuTap(fleet.sim_ports[0]) as tap:
            fleet.start_agent(0, tap.port)
            yield fleet, tap


def _manual_controls(tap: FcuTap) -> list[Any]:
    with tap._changed:
        return [m for m in tap._from_agent if m.get_type() == "MANUAL_CONTROL"]


def test_a_flood_of_stick_frames_reaches_the_vehicle_at_100_hz_newest_first(
    tapped: tuple[LocalFleet, FcuTap],
) -> None:
    fleet, tap = tapped
    base = fleet.plan.hub_http
    token = access_token(base, "admin", fleet.plan.admin_password)
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(ready(VEHICLE), 60, f"{VEHICLE} ready")
        take_off(api, watcher, VEHICLE, 10, above=8)

        pilot = Pilot(base, token)
        try:
            assert pilot.take()["holder"] == "admin"
            before = len(_manual_controls(tap))
            started = time.monotonic()
            sent = 0
            while (elapsed := time.monotonic() - started) < FLOOD_S:
                pilot.stick(x=sent % 50)  # small, varied: each frame its own
                sent += 1
                time.sleep(max(0.0, sent / FLOOD_HZ - elapsed))  # the flood's pace
            last_x = (sent - 1) % 50
            # The newest frame is the one that reaches the vehicle last.
            poll_until(
                lambda: (m := _manual_controls(tap)) and m[-1].x == last_x and m,
                2,
                "the newest frame at the flight controller",
                every_s=0.02,
            )
            flooded_s = time.monotonic() - started
            arrived = len(_manual_controls(tap)) - before
            assert sent / FLOOD_S > 5 * MAX_RATE_HZ, f"not a flood: {sent / FLOOD_S:.0f} Hz"
            # One frame per 10 ms at most, plus the one waiting when the flood began.
            assert arrived <= MAX_RATE_HZ * flooded_s + 2, (arrived, flooded_s)
            print(f"flood: {sent} frames in {FLOOD_S:g} s, {arrived} reached the vehicle")
            assert pilot.said("error") == [], pilot.said("error")
            assert watcher.lease_holders.get(VEHICLE) in (None, "admin")
        finally:
            pilot.close()
        watcher.wait_until(
            lambda v: v[VEHICLE]["state"]["armed"] and (v[VEHICLE]["state"]["alt_rel"] or 0) > 5,
            10,
            "the vehicle still flying",
        )
