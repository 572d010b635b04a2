"""The simulated camera as the two kinds of real camera the agent takes photos from
besides its own (``--camera sim+http``, OpenCV):

- `CameraComponent` (``gcs sim --camera-component``): a camera of MAVLink's camera
  protocol, a component of its own (MAV_COMP_ID_CAMERA, heartbeats of MAV_TYPE_CAMERA)
  beside the autopilot. At each shutter it sends CAMERA_IMAGE_CAPTURED with its own image
  number (from 0), the pose, and ``file_url``: the photo server's address of the shot
  (``--camera``), rendered with the camera model (``--camera-model``).
- `FolderCamera` (``gcs sim --camera-folder DIR``): a camera the autopilot fires that
  writes each photo into a folder, as a camera's SD card or gphoto2 would: the rendered
  JPEG, named as a camera names it (``DSC00001.JPG``), written on a worker thread a
  moment after the autopilot's own message (CAMERA_FEEDBACK; PX4: CAMERA_TRIGGER and
  CAMERA_IMAGE_CAPTURED), which the simulator still sends.

The autopilot's own messages are unchanged in both: a survey's progress counts them.
"""

from __future__ import annotations

import logging
import urllib.parse
from pathlib import Path

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.photos import CameraIntrinsics, PhotoPose
from simulator.config import ListenAddress
from simulator.mavlink.camera_messages import quaternion
from simulator.mavlink.message_context import MavMessage
from simulator.vehicle import PhotoTaken

log = logging.getLogger(__name__)

CAMERA_COMPONENT_ID = mavlink2.MAV_COMP_ID_CAMERA  # 100
CAMERA_ID = 1  # CAMERA_IMAGE_CAPTURED.camera_id: the first (only) camera
CAPTURE_OK = 1


class CameraComponent:
    """The messages of a MAVLink camera whose photos the photo server serves."""

    def __init__(self, photos: ListenAddress, camera: CameraIntrinsics) -> None:
        self.photos = photos
        self.camera = camera
        self.images = 0  # image_index of the next photo: the camera's own count, from 0

    def restart(self) -> None:
        """The vehicle (and its camera with it) rebooted."""
        self.images = 0

    @staticmethod
    def heartbeat() -> MavMessage:
        return mavlink2.MAVLink_heartbeat_message(
            mavlink2.MAV_TYPE_CAMERA,
            mavlink2.MAV_AUTOPILOT_INVALID,
            0,
            0,
            mavlink2.MAV_STATE_ACTIVE,
            3,
        )

    def file_url(self, shot_index: int) -> str:
        query = urllib.parse.urlencode(self.camera.model_dump())
        return f"http://{self.photos.host}:{self.photos.port}/photos/{shot_index}?{query}"

    def image_captured(self, photo: PhotoTaken, pose: PhotoPose, boot_epoch_s: float) -> MavMessage:
        """The camera's CAMERA_IMAGE_CAPTURED for the shot the photo server keeps as
        ``photo.index``: the pose at the shutter, the height above home as the field says
        (a camera manager fills it from the autopilot's GLOBAL_POSITION_INT)."""
        index = self.images
        self.images += 1
        return mavlink2.MAVLink_camera_image_captured_message(
            int(photo.time_s * 1000.0) & 0xFFFFFFFF,
            int(pose.time * 1e6),
            CAMERA_ID,
            round(photo.lat * 1e7),
            round(photo.lon * 1e7),
            round(photo.alt_msl * 1000.0),
            round(photo.alt_rel * 1000.0),
            quaternion(photo.roll, photo.pitch, photo.yaw),
            index,
            CAPTURE_OK,
            self.file_url(photo.index).encode(),
        )


class FolderCamera:
    """Writes each shot's rendered photo into a folder, as a camera's card fills."""

    def __init__(self, folder: Path, camera: CameraIntrinsics) -> None:
        self.folder = folder
        self.camera = camera
        self.written = 0
        folder.mkdir(parents=True, exist_ok=True)

    def path_of(self, number: int) -> Path:
        return self.folder / f"DSC{number:05d}.JPG"

    def write(self, number: int, jpeg: bytes) -> Path:
        """Blocking: call it on a worker thread. Written in place, not renamed into it:
        a reader can see the file before it is whole, as on a camera's card."""
        path = self.path_of(number)
        with path.open("wb") as file:
            file.write(jpeg)
        self.written += 1
        return path
