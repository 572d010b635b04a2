"""Flight-mode names per autopilot: the autopilot's own list, else a fixed table.

PX4 (1.15 on) and ArduPilot (4.7 on) list their modes with MAVLink's standard-modes
protocol (AVAILABLE_MODES; `vehicle_agents.fcu.available_modes` reads it), which is the truth:
a build without ZIGZAG does not list it. `mode_table_for` is the fallback for autopilots
that do not answer: pymavlink's tables, less what the autopilots no longer have (PX4
dropped RATTITUDE and RTGS; a standard ArduCopter build has no ZIGZAG, FOLLOW, SYSTEMID,
TURTLE, FLOWHOLD, the removed POSITION and OF_LOITER, and AUTOROTATE only on a
helicopter). Reported modes keep pymavlink's name for their custom mode where it has
one, so "MISSION", "POSCTL" and "LOITER" mean the same whichever way the list came.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu.dialect import mavutil

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


# Modes pymavlink's tables list that the autopilots' own lists lack (see the docstring).
PX4_NOT_SELECTABLE = frozenset({"RATTITUDE", "RTGS"})
ARDUCOPTER_NOT_IN_STANDARD_BUILD = frozenset(
    {"ZIGZAG", "FOLLOW", "SYSTEMID", "TURTLE", "FLOWHOLD", "POSITION", "OF_LOITER", "RATE_ACRO"}
)
HELICOPTER_ONLY = frozenset({"AUTOROTATE"})
_COPTER_TYPES = frozenset({"multirotor", "helicopter"})


@dataclass(frozen=True)
class ModeTable:
    """Which mode names a vehicle accepts and how to encode them."""

    autopilot: str
    vehicle_type: str
    settings: dict[str, ModeSetting]
    # Where the names came from: the autopilot's AVAILABLE_MODES, or the fixed table.
    reported: bool = False

    @property
    def names(self) -> list[str]:
        return sorted(self.settings)

    def name_of(self, custom_mode: int) -> str | None:
        """The listed mode a HEARTBEAT's custom_mode is, if the autopilot listed it: for
        the modes pymavlink's tables lack (PX4's Orbit, Precision Landing)."""
        if not self.reported:
            return None
        return next(
            (
                name
                for name, setting in self.settings.items()
                if shows_mode(self.autopilot, custom_mode, setting)
            ),
            None,
        )

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


def _pymavlink_settings(autopilot: str, mav_type: int) -> dict[str, ModeSetting]:
    """pymavlink's whole table for this autopilot and vehicle type."""
    if autopilot == "px4":
        return {
            name: ModeSetting(base, main, sub)
            for name, (base, main, sub) in mavutil().px4_map.items()
        }
    flag = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    return {
        name: ModeSetting(flag, number)
        for name, number in (mavutil().mode_mapping_byname(mav_type) or {}).items()
    }


def mode_table_for(heartbeat: Any) -> ModeTable:
    """The fallback table, for an autopilot that does not list its modes."""
    autopilot = autopilot_name(heartbeat.autopilot)
    vehicle_type = vehicle_type_name(heartbeat.type)
    settings = _pymavlink_settings(autopilot, heartbeat.type)
    missing: frozenset[str] = frozenset()
    if autopilot == "px4":
        missing = PX4_NOT_SELECTABLE
    elif autopilot == "ardupilot" and vehicle_type in _COPTER_TYPES:
        missing = ARDUCOPTER_NOT_IN_STANDARD_BUILD
        if vehicle_type != "helicopter":
            missing |= HELICOPTER_ONLY
    kept = {name: setting for name, setting in settings.items() if name not in missing}
    return ModeTable(autopilot, vehicle_type, kept)


@dataclass(frozen=True)
class ReportedMode:
    """One AVAILABLE_MODES message, as the agent reads it."""

    custom_mode: int
    standard_mode: int
    name: str  # mode_name: empty for PX4's standard modes
    selectable: bool
    advanced: bool


def reported_mode(message: Any) -> ReportedMode:
    properties = int(message.properties)
    name = message.mode_name
    if isinstance(name, bytes):
        name = name.decode("utf-8", "replace")
    return ReportedMode(
        custom_mode=int(message.custom_mode),
        standard_mode=int(message.standard_mode),
        name=str(name).rstrip("\x00").strip(),
        selectable=not properties & MAV_MODE_PROPERTY_NOT_USER_SELECTABLE,
        advanced=bool(properties & MAV_MODE_PROPERTY_ADVANCED),
    )


# MAV_MODE_PROPERTY and MAV_STANDARD_MODE (standard modes protocol; pymavlink 2.4.50 keeps
# them in its development dialect).
MAV_MODE_PROPERTY_ADVANCED = 1
MAV_MODE_PROPERTY_NOT_USER_SELECTABLE = 2
STANDARD_MODE_NAMES = {
    1: "POSITION_HOLD",
    2: "ORBIT",
    3: "CRUISE",
    4: "ALTITUDE_HOLD",
    5: "SAFE_RECOVERY",
    6: "MISSION",
    7: "LAND",
    8: "TAKEOFF",
}
_NOT_A_NAME = re.compile(r"[^A-Z0-9]+")


def _setting_of(autopilot: str, custom_mode: int) -> ModeSetting:
    """How DO_SET_MODE asks for the mode HEARTBEAT reports as ``custom_mode``: PX4 packs
    main mode << 16 and sub mode << 24 (px4_custom_mode.h), ArduPilot the mode number."""
    flag = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    if autopilot == "px4":
        return ModeSetting(flag, (custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF)
    return ModeSetting(flag, custom_mode)


def _wire_key(autopilot: str, setting: ModeSetting) -> tuple[int, int]:
    if autopilot == "px4":
        return (setting.custom_mode, setting.custom_sub_mode)
    return (setting.custom_mode, 0)


def reported_table(
    autopilot: str, mav_type: int, modes: list[ReportedMode], max_names: int = 64
) -> ModeTable:
    """The modes the autopilot listed that a user may select, under pymavlink's name for
    each custom mode where it has one (so names match the fallback's and the HEARTBEAT's),
    else the autopilot's own name (an external PX4 mode), else the standard mode's."""
    known = _pymavlink_settings(autopilot, mav_type)
    by_wire = {_wire_key(autopilot, setting): name for name, setting in known.items()}
    settings: dict[str, ModeSetting] = {}
    for mode in modes:
        if not mode.selectable:
            continue
        setting = _setting_of(autopilot, mode.custom_mode)
        name = by_wire.get(_wire_key(autopilot, setting))
        if name is not None:
            setting = known[name]  # the same numbers, with pymavlink's base mode
        else:
            spoken = _NOT_A_NAME.sub("_", mode.name.upper()).strip("_")
            name = (spoken or STANDARD_MODE_NAMES.get(mode.standard_mode, ""))[:32]
            name = name or f"MODE_{mode.custom_mode}"
        # Two entries for one mode (PX4's Descend is Land's custom mode): the first wins.
        if name not in settings and len(settings) < max_names:
            settings[name] = setting
    return ModeTable(autopilot, vehicle_type_name(mav_type), settings, reported=True)


def shows_mode(autopilot: str, custom_mode: int, setting: ModeSetting) -> bool:
    """Whether a HEARTBEAT's (or CURRENT_MODE's) custom_mode is the mode ``setting`` asks for."""
    return _wire_key(autopilot, _setting_of(autopilot, custom_mode)) == _wire_key(
        autopilot, setting
    )


def mode_name(heartbeat: Any) -> str:
    return str(mavutil().mode_string_v10(heartbeat))


def is_armed(heartbeat: Any) -> bool:
    """Whether a HEARTBEAT says the motors are armed (False when there is none yet)."""
    return bool(heartbeat and heartbeat.base_mode & mavlink2.MAV_MODE_FLAG_SAFETY_ARMED)
