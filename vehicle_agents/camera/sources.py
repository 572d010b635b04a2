"""Camera sources behind one interface: each takes the photo of one trigger as a JPEG.

- `SimulatedCamera`: the simulator's camera endpoint (``gcs sim --camera``) renders the
  nadir view of its synthetic ground from the pose at the shutter; a real drone's camera
  fired by the autopilot, with the photo fetched afterwards, works the same way.
- `OpenCvCamera`: a USB or CSI camera through OpenCV (V4L2; a GStreamer pipeline string
  for a CSI camera where OpenCV was built with it). OpenCV is not one of the agent's
  dependencies (the `camera` extra installs opencv-python-headless); it is imported when
  this source starts.
- `MavlinkCamera` (`mavlink_camera.py`): a camera of MAVLink's camera protocol, whose
  CAMERA_IMAGE_CAPTURED gives each photo's address.
- `FolderCamera` (`folder.py`): a camera the autopilot fires that writes its files into a
  folder (an SD card, gphoto2's downloads), each new file paired with a trigger.
"""

from __future__ import annotations

import asyncio
import time
import urllib.parse
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from protocol.photos import CameraIntrinsics, PhotoPose
from vehicle_agents.hub.http import HttpError, send

SIM_SCHEME = "sim+"  # sim+http://HOST:PORT: the simulator's camera endpoint
OPENCV_SCHEME = "opencv:"  # opencv:0, opencv:/dev/video2, opencv:<GStreamer pipeline>
FETCH_TIMEOUT_S = 30.0  # a 12 MP render on a busy simulator host takes seconds
JPEG_QUALITY = 90


class CaptureError(Exception):
    """The source could not take or deliver the photo; the message says why."""


@dataclass(frozen=True)
class Shot:
    """One trigger of the camera: the autopilot's shot counter, when the trigger reached
    the agent (monotonic seconds), the exposure's Unix time, and the pose the autopilot
    recorded at the shutter if it gave one."""

    index: int
    arrived: float
    utc: float
    feedback_pose: PhotoPose | None = None
    file_url: str | None = None  # where a MAVLink camera says the image is


@dataclass(frozen=True)
class Capture:
    """The photo, and when the source itself exposed it (agent monotonic seconds), or None
    when the exposure is the trigger's own (a camera the autopilot fired)."""

    jpeg: bytes
    exposed_at: float | None = None


class CameraSource(Protocol):
    camera: CameraIntrinsics
    # True: the camera itself tells of each photo (a MAVLink camera's
    # CAMERA_IMAGE_CAPTURED), and the autopilot's trigger messages make none.
    announces_shots: bool

    async def capture(self, shot: Shot) -> Capture: ...

    def close(self) -> None: ...


class SimulatedCamera:
    """``sim+http://HOST:PORT``: ``GET /photos/{index}`` renders the simulator's shot
    ``index`` with this camera's intrinsics (query parameters) and answers a JPEG."""

    announces_shots = False

    def __init__(self, url: str, camera: CameraIntrinsics) -> None:
        base = url.removeprefix(SIM_SCHEME).rstrip("/")
        if urllib.parse.urlsplit(base).scheme != "http":
            raise ValueError(f"the simulated camera's URL is sim+http://HOST:PORT, not {url!r}")
        self.base = base
        self.camera = camera

    def photo_url(self, index: int) -> str:
        query = urllib.parse.urlencode(self.camera.model_dump())
        return f"{self.base}/photos/{index}?{query}"

    async def capture(self, shot: Shot) -> Capture:
        try:
            answer = await asyncio.to_thread(
                send, "GET", self.photo_url(shot.index), timeout_s=FETCH_TIMEOUT_S
            )
        except HttpError as error:
            raise CaptureError(
                f"the simulator's camera refused shot {shot.index}: {error}"
            ) from None
        except OSError as error:
            raise CaptureError(f"the simulator's camera is unreachable: {error}") from None
        return Capture(answer.body)

    def close(self) -> None:
        """Nothing held between shots: each is one request."""


class OpenCvCamera:
    """A camera OpenCV opens (``opencv:0``, ``opencv:/dev/video2``, or a GStreamer
    pipeline), set to the camera model's image size. The exposure is the grab: the agent
    grabs when the autopilot's trigger arrives, so the pose is interpolated to that
    instant, not taken from the trigger."""

    announces_shots = False

    def __init__(
        self,
        device: str,
        camera: CameraIntrinsics,
        monotonic: Callable[[], float] = time.monotonic,
    ) -> None:
        self.device = device.removeprefix(OPENCV_SCHEME)
        self.camera = camera
        self._monotonic = monotonic
        self._capture: Any = None
        self._cv2: Any = None

    def _open(self) -> Any:
        if self._capture is not None:
            return self._capture
        try:
            from common.opencv import cv2  # the `camera` extra; without its side effect
        except ImportError:
            raise CaptureError(
                "the OpenCV camera needs OpenCV: pip install opencv-python-headless "
                "(the agent's `camera` extra)"
            ) from None
        device: int | str = int(self.device) if self.device.isdigit() else self.device
        capture = cv2.VideoCapture(device)
        if not capture.isOpened():
            raise CaptureError(f"OpenCV could not open camera {self.device!r}")
        capture.set(cv2.CAP_PROP_FRAME_WIDTH, self.camera.image_width_px)
        capture.set(cv2.CAP_PROP_FRAME_HEIGHT, self.camera.image_height_px)
        capture.set(cv2.CAP_PROP_BUFFERSIZE, 1)  # the newest frame, not one queued earlier
        self._cv2, self._capture = cv2, capture
        return capture

    def _take(self) -> Capture:
        capture = self._open()
        if not capture.grab():
            raise CaptureError(f"camera {self.device!r} gave no frame")
        exposed_at = self._monotonic()
        ok, frame = capture.retrieve()
        if not ok or frame is None:
            raise CaptureError(f"camera {self.device!r} gave no frame")
        height, width = frame.shape[:2]
        if (width, height) != (self.camera.image_width_px, self.camera.image_height_px):
            raise CaptureError(
                f"camera {self.device!r} delivers {width}x{height} px, the camera model says "
                f"{self.camera.image_width_px}x{self.camera.image_height_px}: set the model "
                "to a size the camera supports"
            )
        ok, encoded = self._cv2.imencode(
            ".jpg", frame, [self._cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY]
        )
        if not ok:
            raise CaptureError("OpenCV could not encode the frame as JPEG")
        return Capture(encoded.tobytes(), exposed_at)

    async def capture(self, shot: Shot) -> Capture:
        return await asyncio.to_thread(self._take)

    def close(self) -> None:
        if self._capture is not None:
            self._capture.release()
            self._capture = None


def open_source(
    spec: str, camera: CameraIntrinsics, notify: Callable[[str, int], None]
) -> CameraSource:
    """The source a ``--camera`` value names; ``notify`` tells the operator of what a
    source finds wrong outside any one shot (a folder's file no trigger claims)."""
    # Imported here: they build on this module's Shot and Capture.
    from vehicle_agents.camera.folder import FOLDER_SCHEME, FolderCamera
    from vehicle_agents.camera.mavlink_camera import MAVLINK_SCHEME, MavlinkCamera

    if spec.startswith(SIM_SCHEME):
        return SimulatedCamera(spec, camera)
    if spec.startswith(OPENCV_SCHEME):
        return OpenCvCamera(spec, camera)
    if spec == MAVLINK_SCHEME:
        return MavlinkCamera(camera)
    if spec.startswith(FOLDER_SCHEME):
        return FolderCamera(spec, camera, notify)
    raise ValueError(
        f"unknown camera {spec!r}: sim+http://HOST:PORT (the simulator), opencv:DEVICE, "
        "mavlink (a MAVLink camera component) or folder:PATH (files the camera writes)"
    )
