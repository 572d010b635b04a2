"""The simulated autopilot's word of a shutter: ArduPilot's CAMERA_FEEDBACK, PX4's
CAMERA_TRIGGER and CAMERA_IMAGE_CAPTURED."""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator.mavlink.message_context import MavMessage, MessageContext
from simulator.vehicle import PhotoTaken

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


class CameraMessages(MessageContext):
    """A photo taken, as the autopilot tells of it."""

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
