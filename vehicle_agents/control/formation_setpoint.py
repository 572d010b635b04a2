"""What the formation follower sends: a setpoint (a position and velocity, or nothing
once out of the formation) and its SET_POSITION_TARGET_GLOBAL_INT, altitude above home,
velocity north-east-down."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

if TYPE_CHECKING:
    from common.geodesy import LocalFrame

# Position and velocity used; acceleration, yaw and yaw rate ignored. ArduCopter reads
# any set bit of a group as "ignore the group", PX4 each axis: both fly this the same.
POSVEL_TYPE_MASK = (
    mavlink2.POSITION_TARGET_TYPEMASK_AX_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_AY_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_AZ_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_YAW_IGNORE
    | mavlink2.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
)
# The same with a yaw: a leader flown by the agent faces along its route.
POSVEL_YAW_TYPE_MASK = POSVEL_TYPE_MASK & ~mavlink2.POSITION_TARGET_TYPEMASK_YAW_IGNORE


class Action(StrEnum):
    TRACK = "track"
    HOLD_STALE = "hold_stale"
    BACK_OFF = "back_off"
    HOLD_CLEAR = "hold_clear"  # its slot is within the separation of another vehicle
    HOLD_OBSTACLE = "hold_obstacle"  # its slot is within the clearance of a scanned obstacle
    LEFT = "left"  # out of the formation: sends nothing


@dataclass(frozen=True)
class Setpoint:
    """What to send this tick: a local position (north, east, up) and velocity."""

    action: Action
    position: tuple[float, float, float] | None
    velocity: tuple[float, float, float]
    reason: str = ""


def position_target(
    frame: LocalFrame,
    setpoint: Setpoint,
    time_boot_ms: int,
    target_system: int,
    target_component: int,
    yaw_rad: float | None = None,
) -> mavlink2.MAVLink_set_position_target_global_int_message | None:
    if setpoint.position is None:
        return None
    north, east, up = setpoint.position
    lat, lon = frame.to_geo(east, north)
    vn, ve, vu = setpoint.velocity
    return mavlink2.MAVLink_set_position_target_global_int_message(
        time_boot_ms & 0xFFFFFFFF,
        target_system,
        target_component,
        mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
        POSVEL_TYPE_MASK if yaw_rad is None else POSVEL_YAW_TYPE_MASK,
        round(lat * 1e7),
        round(lon * 1e7),
        up,
        vn,
        ve,
        -vu,
        0.0,
        0.0,
        0.0,
        0.0 if yaw_rad is None else yaw_rad,
        0.0,
    )
