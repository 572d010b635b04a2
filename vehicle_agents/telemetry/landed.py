"""Is it flying? The autopilot's own landed state where it reports one (EXTENDED_SYS_STATE,
requested at 1 Hz by streams.py), the agent's guess otherwise, marked as such."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Literal

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import LandedState
from vehicle_agents.fcu.messages import MavMessage

Source = Literal["autopilot", "derived"]

_FROM_MAVLINK: Mapping[int, LandedState] = {
    mavlink2.MAV_LANDED_STATE_ON_GROUND: "on_ground",
    mavlink2.MAV_LANDED_STATE_TAKEOFF: "takeoff",
    mavlink2.MAV_LANDED_STATE_IN_AIR: "in_air",
    mavlink2.MAV_LANDED_STATE_LANDING: "landing",
}
# Vehicles that never leave the ground (the water): their altitude above home follows the
# terrain, which would read as "in the air" up a hill.
SURFACE_VEHICLES = frozenset({"rover", "boat", "submarine"})
# The autopilot's answer is trusted while fresh: a 1 Hz stream that missed five in a row
# (another GCS turned it off, until streams.py asks again) may be describing the past.
FRESH_S = 5.0
# The guess: armed and above 1 m over home, or climbing faster than 0.5 m/s (a take-off
# from a roof starts below home).
AIRBORNE_ABOVE_HOME_M = 1.0
AIRBORNE_CLIMB_M_S = 0.5


def landed_state(
    latest: Mapping[str, MavMessage],
    received_at: Mapping[str, float] | None,
    now: float,
    *,
    armed: bool | None,
    alt_rel: float | None,
    climb_rate: float | None,
    vehicle_type: str,
) -> tuple[LandedState, Source] | None:
    """The landed state and where it came from; None when nothing tells (no heartbeat)."""
    reported = latest.get("EXTENDED_SYS_STATE")
    if reported is not None and _fresh("EXTENDED_SYS_STATE", received_at, now):
        state = _FROM_MAVLINK.get(int(reported.landed_state))  # UNDEFINED: not reported
        if state is not None:
            return state, "autopilot"
    if vehicle_type in SURFACE_VEHICLES:
        return "on_ground", "derived"
    if armed is None:
        return None
    if not armed:
        return "on_ground", "derived"
    if alt_rel is None and climb_rate is None:
        return None
    high = alt_rel is not None and alt_rel > AIRBORNE_ABOVE_HOME_M
    climbing = climb_rate is not None and climb_rate > AIRBORNE_CLIMB_M_S
    return ("in_air" if high or climbing else "on_ground"), "derived"


def _fresh(kind: str, received_at: Mapping[str, float] | None, now: float) -> bool:
    if received_at is None or kind not in received_at:
        return True  # no arrival times kept: whatever arrived counts
    return now - received_at[kind] <= FRESH_S
