"""The simulated vehicle's state as the MAVLink messages streamed on a clock (and a few
sent once on request): heartbeat, status, GPS, position, attitude, battery, home, EKF,
mission progress and the autopilot's version."""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator.mavconst import SysSensor
from simulator.mavlink.message_context import INT16_MAX, UINT16_MAX, MavMessage, MessageContext

# ArduCopter 4.5.7, official release: what AUTOPILOT_VERSION reports.
FIRMWARE_VERSION = (4, 5, 7)
FIRMWARE_TYPE_OFFICIAL = 255
CAPABILITIES = (
    mavlink2.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
    | mavlink2.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_GLOBAL_INT
    | mavlink2.MAV_PROTOCOL_CAPABILITY_MAVLINK2
)

_ALL_SENSORS = (
    SysSensor.SENSOR_3D_GYRO
    | SysSensor.SENSOR_3D_ACCEL
    | SysSensor.SENSOR_3D_MAG
    | SysSensor.SENSOR_ABSOLUTE_PRESSURE
    | SysSensor.SENSOR_GPS
    | SysSensor.SENSOR_ANGULAR_RATE_CONTROL
    | SysSensor.SENSOR_ATTITUDE_STABILIZATION
    | SysSensor.SENSOR_YAW_POSITION
    | SysSensor.SENSOR_Z_ALTITUDE_CONTROL
    | SysSensor.SENSOR_XY_POSITION_CONTROL
    | SysSensor.SENSOR_MOTOR_OUTPUTS
    | SysSensor.SENSOR_RC_RECEIVER
    | SysSensor.AHRS
    | SysSensor.LOGGING
    | SysSensor.SENSOR_BATTERY
    | SysSensor.PREARM_CHECK
)


def _cdeg(radians: float) -> int:
    """0..35999 centidegrees of a heading in radians."""
    return round(math.degrees(radians) * 100.0) % 36000


class StateMessages(MessageContext):
    """The vehicle's state, one message at a time."""

    def heartbeat(self) -> MavMessage:
        copter = self.copter
        return mavlink2.MAVLink_heartbeat_message(
            copter.mav_type,
            copter.autopilot,
            copter.base_mode(),
            copter.custom_mode(),
            int(copter.system_status()),
            3,
        )

    def sys_status(self) -> MavMessage:
        copter = self.copter
        present = _ALL_SENSORS
        enabled = present
        if copter.manual_mode:
            enabled &= ~(SysSensor.SENSOR_Z_ALTITUDE_CONTROL | SysSensor.SENSOR_XY_POSITION_CONTROL)
        healthy = present
        if copter.gps_fix_type < 3:
            healthy &= ~SysSensor.SENSOR_GPS
        if not copter.prearm_ok():
            healthy &= ~SysSensor.PREARM_CHECK
        battery = copter.battery
        return mavlink2.MAVLink_sys_status_message(
            int(present),
            int(enabled),
            int(healthy),
            200,  # load, per mille of the main loop
            round(battery.voltage * 1000.0),
            round(battery.current_a * 100.0),
            battery.remaining_pct,
            0,
            0,
            0,
            0,
            0,
            0,
        )

    def gps_raw_int(self) -> MavMessage:
        copter = self.copter
        point = copter.gps_position()
        body = copter.body
        speed = body.groundspeed
        course = _cdeg(math.atan2(body.ve, body.vn)) if speed > 0.1 else 0
        fix = copter.gps_fix_type
        alt_mm = round(point.alt * 1000.0)
        return mavlink2.MAVLink_gps_raw_int_message(
            self._time_usec,
            fix,
            round(point.lat * 1e7),
            round(point.lon * 1e7),
            alt_mm,
            121 if fix >= 3 else UINT16_MAX,  # eph: HDOP 1.21, as SITL reports
            200 if fix >= 3 else UINT16_MAX,  # epv
            min(round(speed * 100.0), UINT16_MAX - 1),
            course,
            copter.satellites,
            alt_mm,  # alt_ellipsoid: the simulated geoid is the ellipsoid
            300,  # h_acc mm
            500,  # v_acc mm
            150,  # vel_acc mm/s
            0,
            0,  # yaw: no GPS yaw
        )

    def gps2_raw(self) -> MavMessage | None:
        gps2 = self.gps2
        if gps2 is None:
            return None
        copter = self.copter
        point = copter.position()
        body = copter.body
        speed = body.groundspeed
        fix = gps2.fix_type
        alt_mm = round(point.alt * 1000.0)
        return mavlink2.MAVLink_gps2_raw_message(
            self._time_usec,
            fix,
            round(point.lat * 1e7),
            round(point.lon * 1e7),
            alt_mm,
            70 if fix >= 3 else UINT16_MAX,  # eph: HDOP 0.7
            120 if fix >= 3 else UINT16_MAX,  # epv
            min(round(speed * 100.0), UINT16_MAX - 1),
            _cdeg(math.atan2(body.ve, body.vn)) if speed > 0.1 else 0,
            gps2.satellites,
            1 if fix >= mavlink2.GPS_FIX_TYPE_DGPS else 0,  # dgps_numch: one correction source
            0,  # dgps_age ms
            0,  # yaw: no GPS yaw
            alt_mm,
            14 if fix == mavlink2.GPS_FIX_TYPE_RTK_FIXED else 300,  # h_acc mm
            20 if fix == mavlink2.GPS_FIX_TYPE_RTK_FIXED else 500,  # v_acc mm
            50,  # vel_acc mm/s
            0,
        )

    def global_position_int(self) -> MavMessage:
        copter = self.copter
        point = copter.position()
        body = copter.body
        return mavlink2.MAVLink_global_position_int_message(
            self._time_boot_ms,
            round(point.lat * 1e7),
            round(point.lon * 1e7),
            round(point.alt * 1000.0),
            round(copter.relative_alt * 1000.0),
            round(body.vn * 100.0),
            round(body.ve * 100.0),
            round(body.vd * 100.0),
            _cdeg(body.yaw),
        )

    def attitude(self) -> MavMessage:
        body = self.copter.body
        yaw = body.yaw if body.yaw <= math.pi else body.yaw - 2.0 * math.pi
        return mavlink2.MAVLink_attitude_message(
            self._time_boot_ms,
            body.roll,
            body.pitch,
            yaw,
            body.roll_rate,
            body.pitch_rate,
            body.yaw_rate,
        )

    def vfr_hud(self) -> MavMessage:
        copter = self.copter
        body = copter.body
        return mavlink2.MAVLink_vfr_hud_message(
            math.hypot(*body.airspeed_ne(copter.params)),  # the estimate, with the wind
            body.groundspeed,
            _cdeg(body.yaw) // 100,
            round(body.throttle * 100.0),
            copter.altitude_msl,
            body.climb_rate,
        )

    def battery_status(self) -> MavMessage:
        battery = self.copter.battery
        voltages = [min(round(battery.voltage * 1000.0), UINT16_MAX - 1)] + [UINT16_MAX] * 9
        return mavlink2.MAVLink_battery_status_message(
            0,
            mavlink2.MAV_BATTERY_FUNCTION_UNKNOWN,
            mavlink2.MAV_BATTERY_TYPE_LIPO,
            INT16_MAX,  # temperature unknown
            voltages,
            round(battery.current_a * 100.0),
            round(battery.consumed_mah),
            round(battery.consumed_wh * 36.0),  # hJ
            battery.remaining_pct,
            0,
            mavlink2.MAV_BATTERY_CHARGE_STATE_OK,
        )

    def home_position(self) -> MavMessage:
        copter = self.copter
        home = copter.home
        return mavlink2.MAVLink_home_position_message(
            round(home.lat * 1e7),
            round(home.lon * 1e7),
            round(home.alt * 1000.0),
            copter.home_ne[0],
            copter.home_ne[1],
            0.0,
            [1.0, 0.0, 0.0, 0.0],
            0.0,
            0.0,
            0.0,
            self._time_usec,
        )

    def gps_global_origin(self) -> MavMessage:
        origin = self.copter.frame.origin
        return mavlink2.MAVLink_gps_global_origin_message(
            round(origin.lat * 1e7),
            round(origin.lon * 1e7),
            round(origin.alt * 1000.0),
            self._time_usec,
        )

    def ekf_status_report(self) -> MavMessage:
        """Copter::send_ekf_status_report (AP_NavEKF3): attitude, velocity and height
        always; an absolute horizontal position only once the EKF uses the GPS, and
        constant-position mode until then."""
        flags = (
            mavlink2.EKF_ATTITUDE
            | mavlink2.EKF_VELOCITY_HORIZ
            | mavlink2.EKF_VELOCITY_VERT
            | mavlink2.EKF_POS_HORIZ_REL
            | mavlink2.EKF_POS_VERT_ABS
            | mavlink2.EKF_PRED_POS_HORIZ_REL
        )
        if self.copter.position_ok:
            flags |= mavlink2.EKF_POS_HORIZ_ABS | mavlink2.EKF_PRED_POS_HORIZ_ABS
        else:
            flags |= mavlink2.EKF_CONST_POS_MODE
        return mavlink2.MAVLink_ekf_status_report_message(flags, 0.1, 0.1, 0.1, 0.05, 0.0, 0.0)

    def extended_sys_state(self) -> MavMessage:
        return mavlink2.MAVLink_extended_sys_state_message(
            mavlink2.MAV_VTOL_STATE_UNDEFINED, int(self.copter.landed_state())
        )

    def autopilot_version(self) -> MavMessage:
        major, minor, patch = FIRMWARE_VERSION
        version = (major << 24) | (minor << 16) | (patch << 8) | FIRMWARE_TYPE_OFFICIAL
        encoding = (
            mavlink2.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
            if self.copter.param_bytewise
            else mavlink2.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST
        )
        return mavlink2.MAVLink_autopilot_version_message(
            CAPABILITIES | encoding,
            version,
            0,
            0,
            0,
            [0] * 8,
            [0] * 8,
            [0] * 8,
            0,
            0,
            0,
        )

    def mission_current(self) -> MavMessage:
        copter = self.copter
        on_wire = max(0, copter.mission_current - copter.mission_wire_offset)
        total = copter.mission_count
        if total == 0 and copter.autopilot == mavlink2.MAV_AUTOPILOT_PX4:
            total = UINT16_MAX  # PX4 without a mission (ArduPilot says 0: no items after home)
        return mavlink2.MAVLink_mission_current_message(
            on_wire, total, int(copter.mission_state()), 0
        )
