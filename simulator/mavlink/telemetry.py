"""Build the MAVLink messages that describe the simulated copter.

The builder joins the state, reply and camera messages (each in its own module, on the
shared `MessageContext`) and says which ids it streams and builds.
"""

from __future__ import annotations

from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator.mavconst import MsgId
from simulator.mavlink.camera_messages import CameraMessages
from simulator.mavlink.message_context import MavMessage
from simulator.mavlink.reply_messages import ReplyMessages
from simulator.mavlink.state_messages import StateMessages

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


class TelemetryBuilder(StateMessages, ReplyMessages, CameraMessages):
    """Turns the copter's state into MAVLink messages, one id at a time."""

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
