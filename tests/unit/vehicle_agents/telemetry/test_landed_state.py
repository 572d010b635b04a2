"""Is it flying: the autopilot's EXTENDED_SYS_STATE where it sends one, a marked guess
otherwise. Real pymavlink messages, packed and parsed as the link delivers them."""

from __future__ import annotations

from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.telemetry.snapshot import snapshot

NOW = 1000.0


def _wire(message: Any) -> Any:
    """The message as the agent's link hands it over: packed, then parsed."""
    sender = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    return mavlink2.MAVLink(None).decode(bytearray(message.pack(sender)))


def _heartbeat(armed: bool, mav_type: int = mavlink2.MAV_TYPE_QUADROTOR) -> Any:
    base = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    if armed:
        base |= mavlink2.MAV_MODE_FLAG_SAFETY_ARMED
    return _wire(
        mavlink2.MAVLink_heartbeat_message(
            mav_type, mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA, base, 4, mavlink2.MAV_STATE_ACTIVE, 3
        )
    )


def _position(relative_alt_m: float) -> Any:
    return _wire(
        mavlink2.MAVLink_global_position_int_message(
            0, -353632620, 1491652370, 600_000, round(relative_alt_m * 1000), 0, 0, 0, 9000
        )
    )


def _hud(climb: float) -> Any:
    return _wire(mavlink2.MAVLink_vfr_hud_message(0, 0, 90, 50, 600, climb))


def _landed(state: int) -> Any:
    return _wire(mavlink2.MAVLink_extended_sys_state_message(0, state))


@pytest.mark.parametrize(
    ("reported", "expected"),
    [
        (mavlink2.MAV_LANDED_STATE_ON_GROUND, "on_ground"),
        (mavlink2.MAV_LANDED_STATE_TAKEOFF, "takeoff"),
        (mavlink2.MAV_LANDED_STATE_IN_AIR, "in_air"),
        (mavlink2.MAV_LANDED_STATE_LANDING, "landing"),
    ],
)
def test_the_autopilots_landed_state_is_taken_as_it_says(reported: int, expected: str) -> None:
    # Low and slow, yet in the air (ArduCopter landing, a take-off from a pit): it says so.
    latest = {"HEARTBEAT": _heartbeat(True), "GLOBAL_POSITION_INT": _position(0.3)}
    latest["EXTENDED_SYS_STATE"] = _landed(reported)
    state = snapshot(latest, True, received_at={"EXTENDED_SYS_STATE": NOW - 1}, now=NOW)
    assert state.landed_state == expected
    assert state.landed_state_source == "autopilot"


@pytest.mark.parametrize(
    ("armed", "alt_rel", "climb", "expected"),
    [
        (False, 0.0, 0.0, "on_ground"),
        (False, 30.0, 0.0, "on_ground"),  # disarmed: the motors are off
        (True, 0.2, 0.0, "on_ground"),  # armed, idling on the pad
        (True, 12.0, 0.0, "in_air"),
        (True, -0.5, 1.5, "in_air"),  # climbing away from a roof below home
    ],
)
def test_without_one_it_is_derived_and_marked_so(
    armed: bool, alt_rel: float, climb: float, expected: str
) -> None:
    latest = {
        "HEARTBEAT": _heartbeat(armed),
        "GLOBAL_POSITION_INT": _position(alt_rel),
        "VFR_HUD": _hud(climb),
        "EXTENDED_SYS_STATE": _landed(mavlink2.MAV_LANDED_STATE_UNDEFINED),  # old firmware
    }
    state = snapshot(latest, True, now=NOW)
    assert state.landed_state == expected
    assert state.landed_state_source == "derived"


def test_a_stale_report_gives_way_to_the_guess() -> None:
    latest = {
        "HEARTBEAT": _heartbeat(False),
        "EXTENDED_SYS_STATE": _landed(mavlink2.MAV_LANDED_STATE_IN_AIR),
    }
    state = snapshot(latest, True, received_at={"EXTENDED_SYS_STATE": NOW - 60}, now=NOW)
    assert (state.landed_state, state.landed_state_source) == ("on_ground", "derived")


def test_a_rover_up_a_hill_is_on_the_ground() -> None:
    latest = {
        "HEARTBEAT": _heartbeat(True, mavlink2.MAV_TYPE_GROUND_ROVER),
        "GLOBAL_POSITION_INT": _position(25.0),
        "VFR_HUD": _hud(1.0),
    }
    state = snapshot(latest, True, vehicle_type="rover", now=NOW)
    assert (state.landed_state, state.landed_state_source) == ("on_ground", "derived")


def test_unknown_before_the_first_heartbeat() -> None:
    state = snapshot({}, False, now=NOW)
    assert state.landed_state is None
    assert state.landed_state_source is None
