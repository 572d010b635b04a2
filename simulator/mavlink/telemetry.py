"""Build the MAVLink messages that describe the simulated copter.

pymavlink is used only to construct message objects here; encoding happens per
connection in the transport. Field conventions follow ArduPilot's GCS_Common.cpp.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.mavlink_extra import (
    MAVLink_available_modes_message,
    MAVLink_component_metadata_message,
    MAVLink_current_mode_message,
)
from simulator.mavconst import MsgId, SysSensor
from simulator.params.table import PARAM_ID_LEN
from simulator.params.wire import ParamValueBytes, value_bytes
from simulator.vehicle import PhotoTaken, StatusText, Vehicle
from simulator.vehicle.stored_mission import MissionItem

MavMessage = Any  # pymavlink message classes are generated and untyped

GPS2_RAW = mavlink2.MAVLINK_MSG_ID_GPS2_RAW  # the second receiver, when there is one

# Streams every client gets without asking, in messages per sim second.
DEFAULT_RATES_HZ: dict[int, float] = {
    MsgId.HEARTBEAT: 1.0,
    MsgId.SYS_STATUS: 2.0,
    MsgId.GPS_RAW_INT: 5.0,
    MsgId.GLOBAL_POSITION_INT: 10.0,
    MsgId.ATTITUDE: 10.0,
    MsgId.VFR_HUD: 5.0,
    MsgId.BATTERY_STATUS: 1.0,
    MsgId.HOME_POSITION: 0.5,
    MsgId.EXTENDED_SYS_STATE: 1.0,
    MsgId.MISSION_CURRENT: 1.0,
}
PARAM_INDEX_NONE = 65535  # PARAM_VALUE.param_index of the echo of a PARAM_SET (-1)

# ArduCopter 4.5.7, official release: what AUTOPILOT_VERSION reports.
FIRMWARE_VERSION = (4, 5, 7)
FIRMWARE_TYPE_OFFICIAL = 255
CAPABILITIES = (
    mavlink2.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
    | mavlink2.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_GLOBAL_INT
    | mavlink2.MAV_PROTOCOL_CAPABILITY_MAVLINK2
)

_UINT16_MAX = 65535
_INT16_MAX = 32767
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


@dataclass(frozen=True)
class SecondGps:
    """A second receiver (GPS2_RAW), e.g. an RTK rover beside the primary GPS. It reports
    the true position: at RTK accuracy the simulated noise is negligible."""

    fix_type: int = mavlink2.GPS_FIX_TYPE_RTK_FIXED
    satellites: int = 18


# PX4's CAMERA_IMAGE_CAPTURED.relative_alt is camera_feedback's ground_distance: -1 m
# without a rangefinder, as this vehicle flies.
NO_GROUND_DISTANCE_MM = -1000


def quaternion(roll: float, pitch: float, yaw: float) -> list[float]:
    """(w, x, y, z) of body-to-NED Euler angles in radians (ZYX, as MAVLink's ATTITUDE)."""
    cr, sr = math.cos(roll / 2.0), math.sin(roll / 2.0)
    cp, sp = math.cos(pitch / 2.0), math.sin(pitch / 2.0)
    cy, sy = math.cos(yaw / 2.0), math.sin(yaw / 2.0)
    return [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]


def _cdeg(radians: float) -> int:
    """0..35999 centidegrees of a heading in radians."""
    return round(math.degrees(radians) * 100.0) % 36000


class TelemetryBuilder:
    """Turns the copter's state into MAVLink messages, one id at a time."""

    def __init__(self, copter: Vehicle, boot_epoch_s: float, gps2: SecondGps | None = None) -> None:
        self.copter = copter
        self.boot_epoch_s = boot_epoch_s  # wall-clock time at sim time zero, for GPS time
        self.gps2 = gps2  # None: not fitted (or unplugged), GPS2_RAW is not sent

    @property
    def supported(self) -> frozenset[int]:
        return frozenset(self._builders())

    def build(self, msg_id: int) -> MavMessage | None:
        builder = self._builders().get(msg_id)
        return builder() if builder is not None else None

    def _builders(self) -> dict[int, Any]:
        builders: dict[int, Any] = {
            MsgId.HEARTBEAT: self.heartbeat,
            MsgId.SYS_STATUS: self.sys_status,
            MsgId.GPS_RAW_INT: self.gps_raw_int,
            MsgId.ATTITUDE: self.attitude,
            MsgId.GLOBAL_POSITION_INT: self.global_position_int,
            MsgId.GPS_GLOBAL_ORIGIN: self.gps_global_origin,
            MsgId.VFR_HUD: self.vfr_hud,
            MsgId.BATTERY_STATUS: self.battery_status,
            MsgId.AUTOPILOT_VERSION: self.autopilot_version,
            MsgId.HOME_POSITION: self.home_position,
            MsgId.EXTENDED_SYS_STATE: self.extended_sys_state,
            MsgId.MISSION_CURRENT: self.mission_current,
            MsgId.EKF_STATUS_REPORT: self.ekf_status_report,
        }
        if self.gps2 is not None:  # a receiver that is not there has no messages
            builders[GPS2_RAW] = self.gps2_raw
        if self.sends_camera_trigger:
            # Sent at the shutter (`camera_trigger`), never on a clock: its interval only
            # says whether this link gets it.
            builders[MsgId.CAMERA_TRIGGER] = lambda: None
        return builders

    @property
    def sends_camera_trigger(self) -> bool:
        """PX4 tells of a shutter with CAMERA_TRIGGER and CAMERA_IMAGE_CAPTURED,
        ArduPilot (and the rover, which is ArduRover) with CAMERA_FEEDBACK."""
        personality = getattr(self.copter, "personality", None)
        return personality is not None and not personality.camera_feedback

    @property
    def sends_current_mode(self) -> bool:
        personality = getattr(self.copter, "personality", None)
        return personality is not None and personality.sends_current_mode

    @property
    def _time_boot_ms(self) -> int:
        return int(self.copter.time_s * 1000.0) & 0xFFFFFFFF

    @property
    def _time_usec(self) -> int:
        return int((self.boot_epoch_s + self.copter.time_s) * 1e6)

    # -- messages ------------------------------------------------------------

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
            121 if fix >= 3 else _UINT16_MAX,  # eph: HDOP 1.21, as SITL reports
            200 if fix >= 3 else _UINT16_MAX,  # epv
            min(round(speed * 100.0), _UINT16_MAX - 1),
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
            70 if fix >= 3 else _UINT16_MAX,  # eph: HDOP 0.7
            120 if fix >= 3 else _UINT16_MAX,  # epv
            min(round(speed * 100.0), _UINT16_MAX - 1),
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
        voltages = [min(round(battery.voltage * 1000.0), _UINT16_MAX - 1)] + [_UINT16_MAX] * 9
        return mavlink2.MAVLink_battery_status_message(
            0,
            mavlink2.MAV_BATTERY_FUNCTION_UNKNOWN,
            mavlink2.MAV_BATTERY_TYPE_LIPO,
            _INT16_MAX,  # temperature unknown
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

    def timesync(self, ts1: int) -> MavMessage:
        """The answer to a TIMESYNC request: nanoseconds since boot, the clock of
        time_boot_ms (ArduPilot: AP_HAL::micros64() * 1000)."""
        return mavlink2.MAVLink_timesync_message(int(self.copter.time_s * 1e6) * 1000, ts1)

    def available_modes(self, index: int) -> list[MavMessage] | None:
        """AVAILABLE_MODES for MAV_CMD_REQUEST_MESSAGE: every mode for ``index`` 0 (the
        first alone where the autopilot sends one per request, ArduPilot), else the one at
        ``index`` (1..N); None where the autopilot does not list its modes (the rover) or
        there is no such index."""
        personality = getattr(self.copter, "personality", None)
        modes = personality.available_modes if personality is not None else ()
        total = len(modes)
        if personality is None or not modes or not 0 <= index <= total:
            return None
        every = range(1, total + 1) if personality.lists_every_mode_at_once else (1,)
        indices = every if index == 0 else (index,)
        return [
            MAVLink_available_modes_message(
                total,
                at,
                modes[at - 1].standard_mode,
                modes[at - 1].custom_mode,
                modes[at - 1].properties,
                modes[at - 1].name.encode(),
            )
            for at in indices
        ]

    def component_metadata(self, uri: str) -> MavMessage:
        """COMPONENT_METADATA: where the general metadata file is (an mftp:// address)."""
        return MAVLink_component_metadata_message(self._time_boot_ms, 0, uri.encode())

    def current_mode(self) -> MavMessage:
        """CURRENT_MODE (PX4 sends it on each change): the mode now, and as intended."""
        custom_mode = self.copter.custom_mode()
        personality = getattr(self.copter, "personality", None)
        listed = personality.available_modes if personality is not None else ()
        standard = next(
            (mode.standard_mode for mode in listed if mode.custom_mode == custom_mode), 0
        )
        return MAVLink_current_mode_message(standard, custom_mode, custom_mode)

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
            total = _UINT16_MAX  # PX4 without a mission (ArduPilot says 0: no items after home)
        return mavlink2.MAVLink_mission_current_message(
            on_wire, total, int(copter.mission_state()), 0
        )

    # -- replies -------------------------------------------------------------

    def param_value(self, name: str, index: int | None = None) -> MavMessage:
        """PARAM_VALUE of a stored parameter; ``index`` None for the echo of a PARAM_SET."""
        table = self.copter.param_table
        value = table.get(name)
        assert value is not None, name
        param_type = table.definition(name).type
        return ParamValueBytes(
            name.encode("ascii")[:PARAM_ID_LEN],
            value_bytes(value, param_type, self.copter.param_bytewise),
            int(param_type),
            table.count,
            PARAM_INDEX_NONE if index is None else index,
        )

    @staticmethod
    def mission_item_int(item: MissionItem, target_system: int, target_component: int) -> Any:
        return mavlink2.MAVLink_mission_item_int_message(
            target_system,
            target_component,
            item.seq,
            item.frame,
            item.command,
            0,
            item.autocontinue,
            item.param1,
            item.param2,
            item.param3,
            item.param4,
            item.x,
            item.y,
            item.z,
            0,
        )

    @staticmethod
    def mission_count(count: int, target_system: int, target_component: int) -> MavMessage:
        return mavlink2.MAVLink_mission_count_message(target_system, target_component, count, 0)

    @staticmethod
    def mission_request_int(seq: int, target_system: int, target_component: int) -> MavMessage:
        return mavlink2.MAVLink_mission_request_int_message(target_system, target_component, seq, 0)

    @staticmethod
    def mission_ack(result: int, target_system: int, target_component: int) -> MavMessage:
        return mavlink2.MAVLink_mission_ack_message(target_system, target_component, result, 0)

    @staticmethod
    def mission_item_reached(seq: int) -> MavMessage:
        return mavlink2.MAVLink_mission_item_reached_message(seq)

    def camera_feedback(self, photo: PhotoTaken) -> MavMessage:
        return mavlink2.MAVLink_camera_feedback_message(
            int((self.boot_epoch_s + photo.time_s) * 1e6),
            self.copter.system_id,
            0,
            photo.index,
            round(photo.lat * 1e7),
            round(photo.lon * 1e7),
            photo.alt_msl,
            photo.alt_rel,
            math.degrees(photo.roll),
            math.degrees(photo.pitch),
            math.degrees(photo.yaw),
            0.0,
            mavlink2.CAMERA_FEEDBACK_PHOTO,
            photo.index,
        )

    def camera_trigger(self, photo: PhotoTaken) -> MavMessage:
        """PX4's CAMERA_TRIGGER (mavlink CAMERA_TRIGGER.hpp): the trigger's time on the
        flight controller's boot clock, and its sequence number."""
        return mavlink2.MAVLink_camera_trigger_message(int(photo.time_s * 1e6), photo.index)

    def camera_image_captured(self, photo: PhotoTaken) -> MavMessage:
        """PX4's CAMERA_IMAGE_CAPTURED (camera_feedback): where the vehicle was and how it
        was turned at the shutter; ``image_index`` is the trigger's sequence number."""
        return mavlink2.MAVLink_camera_image_captured_message(
            int(photo.time_s * 1000.0) & 0xFFFFFFFF,
            int((self.boot_epoch_s + photo.time_s) * 1e6),
            0,  # camera_id: the autopilot's own trigger output
            round(photo.lat * 1e7),
            round(photo.lon * 1e7),
            round(photo.alt_msl * 1000.0),
            NO_GROUND_DISTANCE_MM,  # relative_alt: PX4 puts the rangefinder's reading here
            quaternion(photo.roll, photo.pitch, photo.yaw),
            photo.index,
            1,  # capture_result: taken
            b"",
        )

    @staticmethod
    def statustext_of(severity: int, text: str) -> MavMessage:
        return mavlink2.MAVLink_statustext_message(
            int(severity), text.encode("ascii", errors="replace")[:50]
        )

    @staticmethod
    def statustext(status: StatusText) -> MavMessage:
        text = status.text.encode("ascii", errors="replace")[:50]
        return mavlink2.MAVLink_statustext_message(int(status.severity), text)

    @staticmethod
    def command_ack(
        command: int, result: int, target_system: int, target_component: int
    ) -> MavMessage:
        return mavlink2.MAVLink_command_ack_message(
            command, int(result), 0, 0, target_system, target_component
        )

    @staticmethod
    def message_interval(msg_id: int, interval_us: int) -> MavMessage:
        return mavlink2.MAVLink_message_interval_message(msg_id, interval_us)
