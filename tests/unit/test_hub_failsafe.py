"""The hub-link failsafe decides from the vehicle's state: it never overrides an
autopilot that is already landing or returning, nor a pilot flying by hand."""

from __future__ import annotations

import asyncio

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import EventKind
from vehicle_agents.commands import CommandExecutor
from vehicle_agents.fcu_link import FcuLink
from vehicle_agents.hub_failsafe import HubLinkFailsafe

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
