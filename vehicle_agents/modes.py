"""Flight-mode names per autopilot, from pymavlink's mode tables."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.mavlink_dialect import mavutil

_AUTOPILOT_NAMES = {
    mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA: "ardupilot",
    mavlink2.MAV_AUTOPILOT_PX4: "px4",
}

_VEHICLE_TYPE_NAMES = {
    mavlink2.MAV_TYPE_QUADROTOR: "multirotor",
    mavlink2.MAV_TYPE_HEXAROTOR: "multirotor",
    mavlink2.MAV_TYPE_OCTOROTOR: "multirotor",
    mavlink2.MAV_TYPE_TRICOPTER: "multirotor",
    mavlink2.MAV_TYPE_COAXIAL: "multirotor",
    mavlink2.MAV_TYPE_HELICOPTER: "helicopter",
    mavlink2.MAV_TYPE_FIXED_WING: "fixed_wing",
    mavlink2.MAV_TYPE_GROUND_ROVER: "rover",
    mavlink2.MAV_TYPE_SURFACE_BOAT: "boat",
    mavlink2.MAV_TYPE_SUBMARINE: "submarine",
}


@dataclass(frozen=True)
class ModeSetting:
    """The three numbers MAV_CMD_DO_SET_MODE takes."""

    base_mode: int
    custom_mode: int
    custom_sub_mode: int = 0


@dataclass(frozen=True)
class ModeTable:
    """Which mode names a vehicle accepts and how to encode them."""

    autopilot: str
    vehicle_type: str
    settings: dict[str, ModeSetting]

    @property
    def names(self) -> list[str]:
        return sorted(self.settings)

    @property
    def guided_mode(self) -> str | None:
        """The mode in which the vehicle takes position targets and take-off commands."""
        for candidate in ("GUIDED", "OFFBOARD"):
            if candidate in self.settings:
                return candidate
        return None

    @property
    def hold_mode(self) -> str | None:
        """Where "stop here" lives: Copter's BRAKE stops hardest (QGroundControl's pause),
        Rover HOLD, Plane LOITER, PX4 AUTO.LOITER ("Hold")."""
        for candidate in ("BRAKE", "HOLD", "LOITER", "AUTO.LOITER"):
            if candidate in self.settings:
                return candidate
        return None


def autopilot_name(autopilot: int) -> str:
    return _AUTOPILOT_NAMES.get(autopilot, "generic")


def vehicle_type_name(mav_type: int) -> str:
    return _VEHICLE_TYPE_NAMES.get(mav_type, "other")


def mode_table_for(heartbeat: Any) -> ModeTable:
    autopilot = autopilot_name(heartbeat.autopilot)
    settings: dict[str, ModeSetting] = {}
    if autopilot == "px4":
        for name, (base, main, sub) in mavutil().px4_map.items():
            settings[name] = ModeSetting(base, main, sub)
    else:
        flag = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        for name, number in (mavutil().mode_mapping_byname(heartbeat.type) or {}).items():
            settings[name] = ModeSetting(flag, number)
    return ModeTable(autopilot, vehicle_type_name(heartbeat.type), settings)


def mode_name(heartbeat: Any) -> str:
    return str(mavutil().mode_string_v10(heartbeat))


def is_armed(heartbeat: Any) -> bool:
    """Whether a HEARTBEAT says the motors are armed (False when there is none yet)."""
    return bool(heartbeat and heartbeat.base_mode & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED)
