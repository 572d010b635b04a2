"""What each mission item's MAV_CMD needs: a place for a waypoint, a global frame for a
position, times and speeds that mean something. A mission with a bad item is refused
whole, naming each item and what is wrong with it.

Shared by the agent (checked again before anything is sent) and the hub (the mission
check, the upload and the AUTO gate), so it lives in the protocol's leaf package.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import MissionItem

# The modes that fly the stored mission, by the names the agent lists (its mode names
# for PX4 are pymavlink's, which the AVAILABLE_MODES list is named after too): ArduPilot's
# AUTO (every vehicle type) and PX4's MISSION (AUTO.MISSION in PX4's own terms, custom main
# mode 4, sub mode 4). The hub's AUTO gate and the agent's mission pause both read this.
MISSION_MODES = frozenset({"AUTO", "MISSION"})


def mission_mode(modes: Iterable[str]) -> str | None:
    """The name under which this vehicle's mode list has the mode that flies the mission."""
    return next((mode for mode in modes if mode in MISSION_MODES), None)


def known_command(command: int) -> bool:
    return command in mavlink2.enums["MAV_CMD"]


# -- what each command needs ------------------------------------------------------------

_CMD = mavlink2
# Waypoints are places: latitude and longitude 0, 0 is never where one is meant to be.
_WAYPOINTS = frozenset({_CMD.MAV_CMD_NAV_WAYPOINT, _CMD.MAV_CMD_NAV_SPLINE_WAYPOINT})
# Positioned commands that ArduPilot reads as "where the vehicle is" at 0, 0 (loiter here,
# land here); PX4 has no such reading and would fly to 0, 0.
_HERE_AT_ZERO = frozenset(
    {
        _CMD.MAV_CMD_NAV_LOITER_UNLIM,
        _CMD.MAV_CMD_NAV_LOITER_TURNS,
        _CMD.MAV_CMD_NAV_LOITER_TIME,
        _CMD.MAV_CMD_NAV_LOITER_TO_ALT,
        _CMD.MAV_CMD_NAV_LAND,
        _CMD.MAV_CMD_NAV_VTOL_LAND,
        _CMD.MAV_CMD_NAV_PAYLOAD_PLACE,
    }
)
_TAKEOFFS = frozenset({_CMD.MAV_CMD_NAV_TAKEOFF, _CMD.MAV_CMD_NAV_VTOL_TAKEOFF})
# Commands whose position or altitude is read in the item's frame.
_POSITIONED = _WAYPOINTS | _HERE_AT_ZERO | _TAKEOFFS
# What a vehicle on the ground or water cannot do.
_AIRBORNE_ONLY = _TAKEOFFS | frozenset(
    {
        _CMD.MAV_CMD_NAV_LAND,
        _CMD.MAV_CMD_NAV_VTOL_LAND,
        _CMD.MAV_CMD_NAV_LOITER_TO_ALT,
        _CMD.MAV_CMD_NAV_PAYLOAD_PLACE,
    }
)
# Vehicles that go along the ground or water (or under it): no take-off, no landing, and
# an altitude that is not a height to keep.
GROUND_VEHICLES = frozenset({"rover", "boat", "submarine"})
GLOBAL_FRAMES = frozenset(
    {
        _CMD.MAV_FRAME_GLOBAL,
        _CMD.MAV_FRAME_GLOBAL_RELATIVE_ALT,
        _CMD.MAV_FRAME_GLOBAL_INT,
        _CMD.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
        _CMD.MAV_FRAME_GLOBAL_TERRAIN_ALT,
        _CMD.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT,
    }
)
_RELATIVE_FRAMES = frozenset(
    {_CMD.MAV_FRAME_GLOBAL_RELATIVE_ALT, _CMD.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT}
)
# DO_CHANGE_SPEED's speed: -1 leaves it unchanged, -2 restores the default (MAVLink spec).
_SPEED_SENTINELS = (-1.0, -2.0)


def _param_spec(command: int, index: int) -> str:
    """The MAVLink spec's text for a command's param ``index`` (1..4), "" if it has none."""
    entry = mavlink2.enums["MAV_CMD"].get(command)
    return (entry.param.get(index, "") if entry is not None else "").strip()


def _takes_unset(command: int, index: int) -> bool:
    """Whether param ``index`` may be NaN ("unset", null in our JSON): where the spec
    gives NaN a meaning (a yaw of NaN keeps the heading mode) or calls it empty, so the
    autopilot does not read it. Elsewhere NaN has no defined meaning (a hold time, a
    speed) and an autopilot may read it as anything."""
    text = _param_spec(command, index)
    return "NaN" in text or text.rstrip(".") == "Empty"


def _param_label(command: int, index: int) -> str:
    """The spec text's first words ("Hold time", "Speed"), to name the parameter."""
    return re.split(r"[.(,]", _param_spec(command, index))[0].strip() or "unused"


def _unset_problems(item: MissionItem) -> list[str]:
    params = (item.param1, item.param2, item.param3, item.param4)
    return [
        f"param{index} ({_param_label(item.command, index)}) is "
        "empty (null), and this command gives it no unset value: give a number"
        for index, value in enumerate(params, start=1)
        if value is None and not _takes_unset(item.command, index)
    ]


def _command_label(command: int) -> str:
    entry = mavlink2.enums["MAV_CMD"].get(command)
    return entry.name.removeprefix("MAV_CMD_") if entry is not None else f"MAV_CMD {command}"


def _frame_label(frame: int) -> str:
    entry = mavlink2.enums["MAV_FRAME"].get(frame)
    return entry.name if entry is not None else f"frame {frame}"


def item_problems(
    item: MissionItem, count: int, vehicle_type: str = "multirotor", autopilot: str = "ardupilot"
) -> list[str]:
    """What is wrong with one item of a mission of ``count`` items, for this vehicle."""
    command = item.command
    if not known_command(command):
        return [f"unknown MAV_CMD {command}"]
    problems: list[str] = []
    if vehicle_type in GROUND_VEHICLES and command in _AIRBORNE_ONLY:
        problems.append(f"a {vehicle_type} cannot do this")
    if command in _POSITIONED and item.frame not in GLOBAL_FRAMES:
        problems.append(
            f"{_frame_label(item.frame)} is not a global frame; positions in a mission are "
            "latitude, longitude and altitude (MAV_FRAME_GLOBAL, _RELATIVE_ALT or "
            "_TERRAIN_ALT, or their _INT forms)"
        )
    at_zero = item.lat == 0.0 and item.lon == 0.0
    px4 = autopilot == "px4"
    if at_zero and command in _TAKEOFFS and px4:
        # PX4 climbs, then flies to the take-off's position (ArduPilot's copters ignore it).
        problems.append(
            "latitude and longitude are 0, 0: PX4 flies to a take-off's position once it has "
            "climbed (give where the vehicle takes off)"
        )
    elif at_zero and (command in _WAYPOINTS or (command in _HERE_AT_ZERO and px4)):
        problems.append("latitude and longitude are 0, 0: not a place to go (give its position)")
    if command in _TAKEOFFS and item.frame in _RELATIVE_FRAMES and item.alt <= 0.0:
        problems.append(f"take-off altitude {item.alt:g} m is not above home")
    unset = _unset_problems(item)
    problems += unset or _parameter_problems(item, count)
    return problems


def _parameter_problems(item: MissionItem, count: int) -> list[str]:
    command, p1, p2 = item.command, item.param1, item.param2
    problems: list[str] = []
    if p1 is None or p2 is None:
        return problems  # unset where the spec allows it: no value to check
    if command == _CMD.MAV_CMD_NAV_WAYPOINT:
        if p1 < 0.0:
            problems.append(f"hold time {p1:g} s is negative")
        if p2 < 0.0:
            problems.append(f"acceptance radius {p2:g} m is negative")
    elif command == _CMD.MAV_CMD_NAV_LOITER_TIME and p1 < 0.0:
        problems.append(f"loiter time {p1:g} s is negative")
    elif command == _CMD.MAV_CMD_NAV_LOITER_TURNS and not p1 > 0.0:
        problems.append(f"{p1:g} turns: a loiter needs at least part of a turn")
    elif command == _CMD.MAV_CMD_CONDITION_DELAY and p1 < 0.0:
        problems.append(f"delay {p1:g} s is negative")
    elif command == _CMD.MAV_CMD_CONDITION_DISTANCE and p1 < 0.0:
        problems.append(f"distance {p1:g} m is negative")
    elif command == _CMD.MAV_CMD_DO_SET_CAM_TRIGG_DIST and p1 < 0.0:
        problems.append(f"trigger distance {p1:g} m is negative")
    elif command == _CMD.MAV_CMD_DO_CHANGE_SPEED:
        if p1 not in (0.0, 1.0, 2.0, 3.0):
            problems.append(
                f"speed type {p1:g} is not 0 (air), 1 (ground), 2 (climb) or 3 (descent)"
            )
        if not (math.isfinite(p2) and p2 > 0.0) and p2 not in _SPEED_SENTINELS:
            problems.append(
                f"speed {p2:g} m/s: a speed must be above 0 (or -1 to keep it, -2 for the default)"
            )
    elif command == _CMD.MAV_CMD_DO_JUMP:
        target, repeat = p1, p2
        # mission item n is sequence number n (0 is home)
        if target != int(target) or not 1 <= target <= count:
            problems.append(f"jump target {target:g} is not an item of this mission (1..{count})")
        if repeat != int(repeat) or repeat < -1:
            problems.append(f"repeat count {repeat:g} is not a whole number >= -1")
    return problems


def mission_problems(
    items: Sequence[MissionItem], vehicle_type: str = "multirotor", autopilot: str = "ardupilot"
) -> list[str]:
    """Every problem of every item, each naming its item (1 is the first after home)."""
    return [problem for _, problem in mission_problems_by_item(items, vehicle_type, autopilot)]


def mission_problems_by_item(
    items: Sequence[MissionItem], vehicle_type: str = "multirotor", autopilot: str = "ardupilot"
) -> list[tuple[int, str]]:
    """``mission_problems`` with each problem's item number beside it."""
    return [
        (number, f"item {number} ({_command_label(item.command)}): {problem}")
        for number, item in enumerate(items, start=1)
        for problem in item_problems(item, len(items), vehicle_type, autopilot)
    ]
