"""Which messages the agent asks the flight controller for, and at what rates: the plan,
and the same plan in REQUEST_DATA_STREAM's groups for autopilots without
SET_MESSAGE_INTERVAL."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

# What the agent's snapshot reads (HEARTBEAT comes at 1 Hz without asking), in the order
# they are requested: the first one also probes for SET_MESSAGE_INTERVAL support.
DEFAULT_RATES_HZ: Mapping[str, float] = {
    "GLOBAL_POSITION_INT": 10.0,
    "ATTITUDE": 10.0,
    "VFR_HUD": 4.0,
    "SYS_STATUS": 2.0,
    "GPS_RAW_INT": 2.0,
    "GPS2_RAW": 2.0,
    "BATTERY_STATUS": 1.0,
    "MISSION_CURRENT": 1.0,
    "EXTENDED_SYS_STATE": 1.0,
    "EKF_STATUS_REPORT": 1.0,  # ready to fly: the EKF uses the GPS (ArduPilot)
    "HOME_POSITION": 0.2,
}

# Messages PX4 sends on an event, not a clock, that its normal GCS link leaves out
# (mavlink_main.cpp streams CAMERA_TRIGGER only to onboard links): asked for with
# SET_MESSAGE_INTERVAL, at a rate no trigger sequence reaches, so each shutter's is sent
# (a slower rate would hold back one of two triggers a millisecond apart). Not watched:
# silence is no fault.
PX4_EVENT_RATES_HZ: Mapping[str, float] = {"CAMERA_TRIGGER": 100.0}

# REQUEST_DATA_STREAM's groups, as ArduPilot fills them (GCS_Common.cpp, the
# STREAM_*_msgs tables; ArduCopter 4.x). Messages in no group (HOME_POSITION,
# EXTENDED_SYS_STATE) can only be had through SET_MESSAGE_INTERVAL or on request.
DATA_STREAM_GROUPS: Mapping[int, tuple[str, ...]] = {
    mavlink2.MAV_DATA_STREAM_RAW_SENSORS: (
        "RAW_IMU",
        "SCALED_IMU2",
        "SCALED_IMU3",
        "SCALED_PRESSURE",
        "SCALED_PRESSURE2",
        "SCALED_PRESSURE3",
    ),
    mavlink2.MAV_DATA_STREAM_EXTENDED_STATUS: (
        "SYS_STATUS",
        "POWER_STATUS",
        "MEMINFO",
        "MISSION_CURRENT",
        "GPS_RAW_INT",
        "GPS_RTK",
        "GPS2_RAW",
        "GPS2_RTK",
        "NAV_CONTROLLER_OUTPUT",
        "FENCE_STATUS",
        "POSITION_TARGET_GLOBAL_INT",
    ),
    mavlink2.MAV_DATA_STREAM_POSITION: ("GLOBAL_POSITION_INT", "LOCAL_POSITION_NED"),
    mavlink2.MAV_DATA_STREAM_RC_CHANNELS: ("SERVO_OUTPUT_RAW", "RC_CHANNELS", "RC_CHANNELS_RAW"),
    mavlink2.MAV_DATA_STREAM_EXTRA1: ("ATTITUDE", "SIMSTATE", "AHRS2", "PID_TUNING"),
    mavlink2.MAV_DATA_STREAM_EXTRA2: ("VFR_HUD",),
    mavlink2.MAV_DATA_STREAM_EXTRA3: (
        "AHRS",
        "WIND",
        "RANGEFINDER",
        "DISTANCE_SENSOR",
        "SYSTEM_TIME",
        "BATTERY_STATUS",
        "EKF_STATUS_REPORT",
        "VIBRATION",
    ),
}
GROUP_OF = {name: group for group, names in DATA_STREAM_GROUPS.items() for name in names}

INTERVAL_DEFAULT_US = 0  # SET_MESSAGE_INTERVAL param2: the flight controller's default rate
INTERVAL_DISABLED_US = -1  # ... and: stop sending
MAX_DATA_STREAM_HZ = 65535  # REQUEST_DATA_STREAM.req_message_rate is a uint16


@dataclass(frozen=True)
class StreamRequest:
    """One message at one rate; 0 Hz stops it."""

    message: str
    msg_id: int
    rate_hz: float

    @property
    def interval_us(self) -> int:
        if self.rate_hz == 0:
            return INTERVAL_DISABLED_US
        return max(1, round(1e6 / self.rate_hz))


def message_id(name: str) -> int:
    """The MAVLink id of a message named as in the XML (``GPS2_RAW``)."""
    msg_id = getattr(mavlink2, f"MAVLINK_MSG_ID_{name}", None)
    if not isinstance(msg_id, int):
        raise ValueError(f"unknown MAVLink message {name!r} in stream_rates_hz")
    return msg_id


def stream_plan(
    overrides: Mapping[str, float], defaults: Mapping[str, float] = DEFAULT_RATES_HZ
) -> list[StreamRequest]:
    """The defaults with ``overrides`` merged over them (names are case-insensitive)."""
    merged = dict(defaults)
    for name, rate in overrides.items():
        merged[name.upper()] = rate
    plan = []
    for name, rate in merged.items():
        if not math.isfinite(rate) or rate < 0:
            raise ValueError(f"stream_rates_hz: {name} must be >= 0 Hz (0 stops it), not {rate}")
        plan.append(StreamRequest(name, message_id(name), float(rate)))
    return plan


def data_stream_rates(plan: list[StreamRequest]) -> dict[int, int]:
    """REQUEST_DATA_STREAM rates (whole Hz, 0 stops) per group: the fastest of its messages."""
    rates: dict[int, int] = {}
    for request in plan:
        group = GROUP_OF.get(request.message)
        if group is None:
            continue
        whole = min(math.ceil(request.rate_hz), MAX_DATA_STREAM_HZ)
        rates[group] = max(rates.get(group, 0), whole)
    return rates


GROUP_OF_ID = {
    getattr(mavlink2, f"MAVLINK_MSG_ID_{name}"): group
    for name, group in GROUP_OF.items()
    if hasattr(mavlink2, f"MAVLINK_MSG_ID_{name}")
}
