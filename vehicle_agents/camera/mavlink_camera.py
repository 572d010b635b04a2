"""A camera of MAVLink's camera protocol: a component of its own beside the autopilot.

A MAVLink camera (``MAV_TYPE_CAMERA`` heartbeats, component id MAV_COMP_ID_CAMERA to
CAMERA6: a companion computer's camera manager, a gimbal camera, PX4's Gazebo camera)
tells of each photo it takes with CAMERA_IMAGE_CAPTURED: its own ``image_index``, the
vehicle's position and attitude at the shutter, and ``file_url``, where the image can be
had (MAVLink's camera protocol: an http(s) URL, or ``mftp://`` for the camera's MAVLink FTP
server). The agent takes that message as the shutter (the autopilot's own camera
messages then make no photo: the camera's is the photo) and fetches the file:

- ``http://`` and ``https://``: one GET, bounded in size (`MAX_PHOTO_BYTES`, what the hub
  takes) and in time;
- ``mftp://``: not supported. pymavlink's MAVFTP client (pymavlink.mavftp) reads the
  connection itself (``recv_match``), which the agent's link to the flight controller
  cannot share with its own reader; a camera that only serves MAVLink FTP is refused
  with that reason, shot by shot, in an event.

A message without a ``file_url`` (the field is optional in MAVLink) is a shot with no
image to fetch: told, never silently dropped.
"""

from __future__ import annotations

import asyncio
import http.client
import urllib.parse

from protocol.photos import MAX_PHOTO_BYTES, CameraIntrinsics
from vehicle_agents.camera.sources import Capture, CaptureError, Shot
from vehicle_agents.hub.http import HttpError, TooLarge, send

MAVLINK_SCHEME = "mavlink"  # --camera mavlink
FETCH_TIMEOUT_S = 30.0  # a whole 40 MiB file over a companion computer's Wi-Fi


class MavlinkCamera:
    """``mavlink``: the photos a MAVLink camera component announces, fetched from the
    address in each CAMERA_IMAGE_CAPTURED."""

    announces_shots = True  # its CAMERA_IMAGE_CAPTURED is the shutter, not the autopilot's

    def __init__(
        self,
        camera: CameraIntrinsics,
        *,
        max_bytes: int = MAX_PHOTO_BYTES,
        timeout_s: float = FETCH_TIMEOUT_S,
    ) -> None:
        self.camera = camera
        self.max_bytes = max_bytes
        self.timeout_s = timeout_s

    async def capture(self, shot: Shot) -> Capture:
        url = shot.file_url
        if not url:
            raise CaptureError(
                "the MAVLink camera gave no file address (CAMERA_IMAGE_CAPTURED.file_url "
                "is empty): there is no image to fetch"
            )
        scheme = urllib.parse.urlsplit(url).scheme.lower()
        if scheme == "mftp":
            raise CaptureError(
                f"{url}: MAVLink FTP (mftp://) file addresses are not supported; set the "
                "camera to serve its images over HTTP"
            )
        if scheme not in ("http", "https"):
            raise CaptureError(f"{url}: the camera's file address is not an http(s) URL")
        try:
            answer = await asyncio.to_thread(
                send, "GET", url, timeout_s=self.timeout_s, max_bytes=self.max_bytes
            )
        except HttpError as error:
            raise CaptureError(f"the camera refused {url}: {error}") from None
        except TooLarge as error:
            raise CaptureError(f"{url} is too large for a photo: {error}") from None
        except (OSError, ValueError, http.client.HTTPException) as error:
            # unreachable, timed out, cut short, a malformed URL
            raise CaptureError(f"could not fetch {url}: {error}") from None
        return Capture(answer.body)

    def close(self) -> None:
        """Nothing held between shots: each is one request."""
