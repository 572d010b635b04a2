"""Encode a mode name back into HEARTBEAT numbers: the inverse of mode_string_v10.

The agent names modes with ``pymavlink.mavutil.mode_string_v10``, so the numbers come
from the same tables. ``mavutil`` is imported lazily, inside the cached function,
because importing it has side effects the hub should not pay for at start-up: it sets
``MAVLINK_DIALECT`` in the process environment, generates and imports the "all"
dialect, and reads ``~/.pymavlink/custom_mode_map.json``.
"""

from __future__ import annotations

import functools
import re

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

_MAV_TYPES = {
    "multirotor": mavlink2.MAV_TYPE_QUADROTOR,
    "helicopter": mavlink2.MAV_TYPE_HELICOPTER,
    "fixed_wing": mavlink2.MAV_TYPE_FIXED_WING,
    "rover": mavlink2.MAV_TYPE_GROUND_ROVER,
    "boat": mavlink2.MAV_TYPE_SURFACE_BOAT,
    "submarine": mavlink2.MAV_TYPE_SUBMARINE,
}

_AUTOPILOTS = {
    "ardupilot": mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA,
    "px4": mavlink2.MAV_AUTOPILOT_PX4,
}

# What mode_string_v10 prints for numbers outside its tables.
_NUMBERED = re.compile(r"^Mode\((?:0x(?P<base>[0-9a-fA-F]+)|(?P<custom>\d+))\)$")


def mav_type(vehicle_type: str) -> int:
    """MAV_TYPE for the hub's vehicle type name; MAV_TYPE_GENERIC when there is none."""
    return int(_MAV_TYPES.get(vehicle_type, mavlink2.MAV_TYPE_GENERIC))


def mav_autopilot(autopilot: str) -> int:
    return int(_AUTOPILOTS.get(autopilot, mavlink2.MAV_AUTOPILOT_GENERIC))


@functools.cache
def _modes_by_name(autopilot: str, vehicle_type: str) -> dict[str, tuple[int, int]]:
    from pymavlink import mavutil  # lazily: see the module docstring

    custom = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    if autopilot == "px4":
        return {
            name: (int(base) | custom, (int(main) << 16) | (int(sub) << 24))
            for name, (base, main, sub) in mavutil.px4_map.items()
        }
    # mode_string_v10 decodes every autopilot other than PX4 (generic ones too)
    # with ArduPilot's per-vehicle-type tables.
    table = mavutil.mode_mapping_byname(mav_type(vehicle_type)) or {}
    return {str(name): (custom, int(number)) for name, number in table.items()}


def heartbeat_mode(autopilot: str, vehicle_type: str, mode: str) -> tuple[int, int]:
    """``(base_mode, custom_mode)`` for a HEARTBEAT whose mode decodes back to ``mode``.

    ``base_mode`` never has MAV_MODE_FLAG_SAFETY_ARMED; the caller adds it. A name
    nothing knows gives ``(0, 0)``: no custom mode, which decodes as ``Mode(0x...)``.
    """
    known = _modes_by_name(autopilot, vehicle_type).get(mode)
    if known is not None:
        return known
    numbered = _NUMBERED.match(mode)
    if numbered is None:
        return 0, 0
    if numbered["base"] is not None:
        return int(numbered["base"], 16) & 0xFF & ~mavlink2.MAV_MODE_FLAG_SAFETY_ARMED, 0
    return mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, int(numbered["custom"]) & 0xFFFFFFFF
