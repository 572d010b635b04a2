"""Whether the vehicle is ready to fly, and if not, why: from what the autopilot reports.

A 3D fix is not enough: ArduCopter refuses a take-off for about 20 s more, until its EKF
uses the GPS. Three sources say more, as QGroundControl reads them:

* EKF_STATUS_REPORT (ArduPilot): the estimator has an absolute horizontal position
  (EKF_POS_HORIZ_ABS, or PRED_POS_HORIZ_ABS on the ground) and is not in constant-
  position mode, which is what guided flight and take-off need;
* SYS_STATUS: the MAV_SYS_STATUS_PREARM_CHECK bit is healthy when the pre-arm checks
  pass (ArduPilot and PX4 both report it), and each sensor that must work has its bit;
* the texts the autopilot sends while a check fails: ArduPilot's "PreArm: ..." (repeated
  every 30 s while disarmed), PX4's "Preflight Fail: ...". These name the reason.

An armed vehicle is ready (it is flying or about to); with none of the messages yet,
readiness is unknown (None), never guessed.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Protocol

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.fcu.modes import is_armed

# ArduPilot repeats a failing pre-arm check every 30 s while disarmed; older texts are
# stale (the check may since have passed and another failed).
PREARM_TEXT_WINDOW_S = 35.0
PREARM_PREFIXES = ("PreArm: ", "Preflight Fail: ", "Preflight: ")

_PREARM = mavlink2.MAV_SYS_STATUS_PREARM_CHECK
# Sensors without which no autopilot arms, and how to name them to an operator. The RC
# receiver is left out: a vehicle flown from a GCS alone reports it missing and flies.
_SENSORS: tuple[tuple[int, str], ...] = (
    (mavlink2.MAV_SYS_STATUS_SENSOR_3D_GYRO, "gyro"),
    (mavlink2.MAV_SYS_STATUS_SENSOR_3D_ACCEL, "accelerometer"),
    (mavlink2.MAV_SYS_STATUS_SENSOR_3D_MAG, "compass"),
    (mavlink2.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE, "barometer"),
    (mavlink2.MAV_SYS_STATUS_SENSOR_GPS, "GPS"),
    (mavlink2.MAV_SYS_STATUS_AHRS, "AHRS"),
    (mavlink2.MAV_SYS_STATUS_SENSOR_BATTERY, "battery"),
)
_ABSOLUTE_POSITION = mavlink2.EKF_POS_HORIZ_ABS | mavlink2.EKF_PRED_POS_HORIZ_ABS


class TimedText(Protocol):
    time: float  # Unix seconds
    text: str


@dataclass(frozen=True)
class Readiness:
    ready: bool | None
    reason: str | None = None


def readiness(
    latest: Mapping[str, MavMessage], statustexts: Iterable[TimedText], now: float
) -> Readiness:
    """Ready to fly or not (and why), from the latest messages and recent STATUSTEXTs."""
    heartbeat = latest.get("HEARTBEAT")
    if heartbeat is None:
        return Readiness(None)
    if is_armed(heartbeat):
        return Readiness(True)
    status = latest.get("SYS_STATUS")
    ekf = latest.get("EKF_STATUS_REPORT")
    if status is None and ekf is None:
        return Readiness(None)
    reasons: list[str] = []
    prearm_failing = False
    if status is not None:
        present = int(status.onboard_control_sensors_present)
        enabled = int(status.onboard_control_sensors_enabled)
        healthy = int(status.onboard_control_sensors_health)
        prearm_failing = bool(present & _PREARM) and not healthy & _PREARM
        reasons += [
            f"{name} unhealthy"
            for bit, name in _SENSORS
            if present & enabled & bit and not healthy & bit
        ]
    if ekf is not None and (problem := _ekf_problem(int(ekf.flags))) is not None:
        reasons.insert(0, problem)
    if prearm_failing:
        text = _latest_prearm_text(statustexts, now)
        if text is not None:
            reasons.insert(0, text)
        elif not reasons:
            reasons.append("pre-arm checks failing")
    if reasons:
        return Readiness(False, "; ".join(dict.fromkeys(reasons)))
    return Readiness(True)


def _ekf_problem(flags: int) -> str | None:
    if flags & mavlink2.EKF_UNINITIALIZED or not flags & mavlink2.EKF_ATTITUDE:
        return "EKF not initialised"
    if flags & mavlink2.EKF_GPS_GLITCHING:
        return "GPS glitching"
    if flags & mavlink2.EKF_CONST_POS_MODE or not flags & _ABSOLUTE_POSITION:
        return "EKF has no position estimate yet (not using the GPS)"
    return None


def _latest_prearm_text(texts: Iterable[TimedText], now: float) -> str | None:
    found = None
    for entry in texts:
        if now - entry.time > PREARM_TEXT_WINDOW_S:
            continue
        for prefix in PREARM_PREFIXES:
            if entry.text.startswith(prefix):
                found = entry.text.removeprefix(prefix).strip()
    return found
