"""Ready to fly, from the messages ArduPilot and PX4 send (pymavlink message objects)."""

from __future__ import annotations

from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.telemetry.readiness import PREARM_TEXT_WINDOW_S, Readiness, readiness

NOW = 1_000_000.0
ALL = (
    mavlink2.MAV_SYS_STATUS_SENSOR_3D_GYRO
    | mavlink2.MAV_SYS_STATUS_SENSOR_3D_ACCEL
    | mavlink2.MAV_SYS_STATUS_SENSOR_GPS
    | mavlink2.MAV_SYS_STATUS_AHRS
    | mavlink2.MAV_SYS_STATUS_SENSOR_RC_RECEIVER
    | mavlink2.MAV_SYS_STATUS_PREARM_CHECK
)
EKF_GOOD = (
    mavlink2.EKF_ATTITUDE
    | mavlink2.EKF_VELOCITY_HORIZ
    | mavlink2.EKF_POS_HORIZ_ABS
    | mavlink2.EKF_PRED_POS_HORIZ_ABS
    | mavlink2.EKF_POS_VERT_ABS
)
EKF_NO_GPS = (
    mavlink2.EKF_ATTITUDE
    | mavlink2.EKF_VELOCITY_HORIZ
    | mavlink2.EKF_POS_VERT_ABS
    | mavlink2.EKF_CONST_POS_MODE
)


@dataclass
class Text:
    time: float
    text: str


def heartbeat(armed: bool = False) -> MavMessage:
    base = mavlink2.MAV_MODE_FLAG_SAFETY_ARMED if armed else 0
    return mavlink2.MAVLink_heartbeat_message(
        mavlink2.MAV_TYPE_QUADROTOR, mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA, base, 4, 3, 3
    )


def sys_status(unhealthy: int = 0) -> MavMessage:
    return mavlink2.MAVLink_sys_status_message(
        ALL, ALL, ALL & ~unhealthy, 0, 12000, 0, 100, 0, 0, 0, 0, 0, 0
    )


def ekf(flags: int) -> MavMessage:
    return mavlink2.MAVLink_ekf_status_report_message(flags, 0.1, 0.1, 0.1, 0.1, 0.0)


def test_unknown_until_the_autopilot_has_said() -> None:
    assert readiness({}, [], NOW) == Readiness(None)
    assert readiness({"HEARTBEAT": heartbeat()}, [], NOW) == Readiness(None)


def test_ready_when_every_check_passes_and_when_armed() -> None:
    latest = {
        "HEARTBEAT": heartbeat(),
        "SYS_STATUS": sys_status(),
        "EKF_STATUS_REPORT": ekf(EKF_GOOD),
    }
    assert readiness(latest, [], NOW) == Readiness(True)
    broken = {**latest, "EKF_STATUS_REPORT": ekf(EKF_NO_GPS), "HEARTBEAT": heartbeat(armed=True)}
    assert readiness(broken, [], NOW) == Readiness(True)


def test_a_3d_fix_the_ekf_does_not_use_yet_is_not_ready() -> None:
    """The field trial's case: GPS healthy, pre-arm checks passing in STABILIZE, the EKF
    still in constant-position mode."""
    latest = {
        "HEARTBEAT": heartbeat(),
        "SYS_STATUS": sys_status(),
        "EKF_STATUS_REPORT": ekf(EKF_NO_GPS),
    }
    assert readiness(latest, [], NOW) == Readiness(
        False, "EKF has no position estimate yet (not using the GPS)"
    )


def test_the_autopilots_prearm_text_names_the_reason() -> None:
    latest = {
        "HEARTBEAT": heartbeat(),
        "SYS_STATUS": sys_status(unhealthy=mavlink2.MAV_SYS_STATUS_PREARM_CHECK),
        "EKF_STATUS_REPORT": ekf(EKF_GOOD),
    }
    texts = [
        Text(NOW - PREARM_TEXT_WINDOW_S - 1, "PreArm: Compass not calibrated"),  # stale
        Text(NOW - 5, "PreArm: Throttle below failsafe"),
        Text(NOW - 1, "Flight plan received"),
    ]
    assert readiness(latest, texts, NOW) == Readiness(False, "Throttle below failsafe")
    assert readiness(latest, texts[:1], NOW) == Readiness(False, "pre-arm checks failing")
    px4 = [Text(NOW - 2, "Preflight Fail: ekf2 missing data")]
    assert readiness(latest, px4, NOW) == Readiness(False, "ekf2 missing data")


def test_an_unhealthy_sensor_is_named_and_rc_is_not_required() -> None:
    latest = {
        "HEARTBEAT": heartbeat(),
        "SYS_STATUS": sys_status(
            unhealthy=mavlink2.MAV_SYS_STATUS_SENSOR_GPS
            | mavlink2.MAV_SYS_STATUS_SENSOR_RC_RECEIVER
            | mavlink2.MAV_SYS_STATUS_PREARM_CHECK
        ),
    }
    assert readiness(latest, [Text(NOW, "PreArm: GPS 1: Bad fix")], NOW) == Readiness(
        False, "GPS 1: Bad fix; GPS unhealthy"
    )
