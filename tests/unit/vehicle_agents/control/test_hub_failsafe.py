"""The hub-link failsafe decides from the vehicle's state: it never overrides an
autopilot that is already landing or returning, nor a pilot flying by hand."""

from __future__ import annotations

import asyncio
import time

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from common.retry import Backoff
from protocol.messages import EventKind
from tests.support.paced import paced_at
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.control.hub_failsafe import HubLinkFailsafe, reconnect_backoff
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.sensors.paced_clock import PacedClock

COPTER_MODES = {"STABILIZE": 0, "GUIDED": 4, "RTL": 6, "LAND": 9}


def _decide(mode: str, armed: bool = True) -> tuple[str, list[str]]:
    """What the failsafe does, configured for RTL, on a link that cannot send (so an
    attempt to command shows up as 'could not command')."""
    link = FcuLink("tcp:127.0.0.1:1")
    flags = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    if armed:
        flags |= mavlink2.MAV_MODE_FLAG_SAFETY_ARMED
    link.latest["HEARTBEAT"] = mavlink2.MAVLink_heartbeat_message(
        mavlink2.MAV_TYPE_QUADROTOR,
        mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA,
        flags,
        COPTER_MODES[mode],
        mavlink2.MAV_STATE_ACTIVE,
        3,
    )
    events: list[str] = []

    def emit(kind: EventKind, text: str, severity: int | None) -> None:
        events.append(text)

    failsafe = HubLinkFailsafe(
        asyncio.Event(), asyncio.Event(), CommandExecutor(link), link, emit, "rtl", 10
    )
    return asyncio.run(failsafe._act()), events


@pytest.mark.parametrize("mode", ["LAND", "RTL"])
def test_a_vehicle_already_recovering_is_left_alone(mode: str) -> None:
    done, events = _decide(mode)
    assert done == f"took no action (rtl configured): the autopilot is in {mode}"
    assert events == [f"hub link lost for 10 s: {done}"]


def test_a_pilot_flying_by_hand_is_left_alone() -> None:
    done, _ = _decide("STABILIZE")
    assert "a pilot flies it in STABILIZE" in done


def test_a_disarmed_vehicle_is_left_alone() -> None:
    done, _ = _decide("GUIDED", armed=False)
    assert "vehicle disarmed" in done


def test_a_guided_vehicle_is_commanded_home() -> None:
    done, _ = _decide("GUIDED")
    assert done.startswith("could not command RTL")  # this link is down: the attempt shows


def test_an_armed_failsafe_caps_the_reconnect_wait_below_a_flaps_up_time() -> None:
    usual = Backoff(initial_s=0.5, max_s=10.0)
    capped = reconnect_backoff("rtl", 5.0, usual)
    assert capped.max_s == 1.25
    # However long the run of failures, no wait can sleep through a 2 s up-time.
    assert max(capped.delay(failures) for failures in range(1, 40) for _ in range(50)) <= 1.25
    assert reconnect_backoff("hold", 60.0, usual) == usual  # 15 s would be looser: kept
    assert reconnect_backoff("hold", 1.0, usual) == Backoff(initial_s=0.25, max_s=0.25)


def test_a_failsafe_that_does_nothing_keeps_the_fleet_wide_backoff() -> None:
    usual = Backoff(initial_s=0.5, max_s=10.0)
    assert reconnect_backoff("continue", 5.0, usual) == usual


def _fires_after(clock: PacedClock, timeout_s: float) -> float:
    """Wall seconds from the hub link's loss to the failsafe's action (configured to
    continue, so it only reports), on ``clock``."""
    link = FcuLink("tcp:127.0.0.1:1")
    fired = asyncio.Event()

    def emit(kind: EventKind, text: str, severity: int | None) -> None:
        fired.set()

    async def run() -> float:
        failsafe = HubLinkFailsafe(
            asyncio.Event(),
            asyncio.Event(),
            CommandExecutor(link),
            link,
            emit,
            "continue",
            timeout_s,
            clock,
        )
        failsafe._disconnected.set()
        started = time.monotonic()
        task = asyncio.create_task(failsafe.run())
        await asyncio.wait_for(fired.wait(), timeout_s + 5.0)
        task.cancel()
        return time.monotonic() - started

    return asyncio.run(run())


def test_the_timeout_runs_on_a_sped_up_autopilots_clock() -> None:
    took = _fires_after(paced_at(4.0), 2.0)
    assert 0.4 <= took < 2.0  # 2 s of a 4x simulator: 0.5 s of ours


def test_a_stalled_autopilot_clock_still_trips_the_failsafe_in_wall_time() -> None:
    # the board's clock stopped counting (frozen), or its link is gone: the wall paces
    took = _fires_after(paced_at(0.0), 0.6)
    assert 0.55 <= took < 2.0
