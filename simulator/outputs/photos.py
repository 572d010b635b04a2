"""The simulated camera's photos, over HTTP: ``GET /photos/{index}`` renders shot ``index``.

When the autopilot fires the camera (a mission's DO_SET_CAM_TRIGG_DIST or
DO_DIGICAM_CONTROL), the simulator sends CAMERA_FEEDBACK (playing PX4:
CAMERA_IMAGE_CAPTURED, and CAMERA_TRIGGER where asked for) and keeps the shot's true pose
here. The agent's simulated camera source then fetches the photo, as it would fetch one
from a real camera the autopilot fired: the image is the nadir view of the synthetic
ground (simulator/world/ground.py) from that pose, through the camera the query names (the
agent's camera model: ``sensor_width_mm``, ``sensor_height_mm``, ``image_width_px``,
``image_height_px``, ``focal_length_mm``), rendered on a worker thread so the physics
keeps its pace, and answered as a JPEG.

A tiny HTTP/1.1 server on asyncio streams: GET only, one request per connection; the
simulator has no web framework and needs none for this. Unknown shots are 404, bad
camera figures 400 with the reason.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import re
import urllib.parse
from collections import OrderedDict
from collections.abc import Callable

from pydantic import ValidationError

from common.geodesy import GeoPoint
from protocol.photos import CameraIntrinsics, PhotoPose
from simulator.config import ListenAddress
from simulator.vehicle import PhotoTaken

log = logging.getLogger(__name__)

Renderer = Callable[[PhotoPose, CameraIntrinsics], bytes]
"""A shot's pose and the camera, to the photo as JPEG bytes."""

SHOTS_KEPT = 2000  # the newest shots' poses; an older one is 404
REQUEST_LINE = re.compile(rb"^(GET|HEAD) (/photos/(\d+))(?:\?(\S*))? HTTP/1\.[01]\r?\n$")
MAX_HEADER_BYTES = 16 * 1024
READ_TIMEOUT_S = 10.0
RENDERS_AT_ONCE = 2  # a render takes a core; more wait their turn


class PhotoServer:
    def __init__(self, listen: ListenAddress, render: Renderer, boot_epoch_s: float) -> None:
        self.listen = listen
        self.render = render
        self.boot_epoch_s = boot_epoch_s
        self.address: ListenAddress | None = None
        self.shots: OrderedDict[int, PhotoPose] = OrderedDict()
        self.rendered = 0
        self._server: asyncio.Server | None = None
        self._renders = asyncio.Semaphore(RENDERS_AT_ONCE)

    async def start(self) -> ListenAddress:
        self._server = await asyncio.start_server(
            self._on_client, self.listen.host, self.listen.port, limit=MAX_HEADER_BYTES
        )
        port = int(self._server.sockets[0].getsockname()[1])
        self.address = ListenAddress("tcp", self.listen.host, port)
        log.info("camera photos on http://%s:%d/photos/{index}", self.listen.host, port)
        return self.address

    async def stop(self) -> None:
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()
            self._server = None

    def restart(self, boot_epoch_s: float) -> None:
        """The vehicle rebooted: its shot counter starts again."""
        self.shots.clear()
        self.boot_epoch_s = boot_epoch_s

    def taken(self, photo: PhotoTaken) -> None:
        """The camera fired: keep where it was, for the agent's fetch."""
        self.shots[photo.index] = pose_of(photo, self.boot_epoch_s)
        while len(self.shots) > SHOTS_KEPT:
            self.shots.popitem(last=False)

    async def _on_client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        try:
            async with asyncio.timeout(READ_TIMEOUT_S):
                line = await reader.readline()
                while (header := await reader.readline()) not in (b"\r\n", b"\n", b""):
                    del header  # no header changes the answer
            status, content_type, body = await self.answer(line)
            head = (
                f"HTTP/1.1 {status}\r\nContent-Type: {content_type}\r\n"
                f"Content-Length: {len(body)}\r\nConnection: close\r\n\r\n"
            )
            writer.write(head.encode() + (b"" if line.startswith(b"HEAD") else body))
            await writer.drain()
        except (TimeoutError, ConnectionError, OSError, ValueError, asyncio.LimitOverrunError):
            pass
        finally:
            writer.close()
            with contextlib.suppress(ConnectionError, OSError):
                await writer.wait_closed()

    async def answer(self, line: bytes) -> tuple[str, str, bytes]:
        """The status line's text, the content type and the body for one request line."""
        match = REQUEST_LINE.match(line)
        if match is None:
            return _text("400 Bad Request", "expected GET /photos/{index}?<camera>")
        index = int(match.group(3))
        query = urllib.parse.parse_qs((match.group(4) or b"").decode("ascii", "replace"))
        try:
            camera = CameraIntrinsics.model_validate({k: v[-1] for k, v in query.items()})
        except ValidationError as error:
            problems = "; ".join(
                f"{'.'.join(str(p) for p in e['loc'])}: {e['msg']}" for e in error.errors()
            )
            return _text("400 Bad Request", f"the camera's figures: {problems}")
        pose = self.shots.get(index)
        if pose is None:
            return _text(
                "404 Not Found", f"no shot {index} (the camera has taken {len(self.shots)})"
            )
        async with self._renders:
            try:
                jpeg = await asyncio.to_thread(self.render, pose, camera)
            except ValueError as error:  # e.g. a camera that does not look at the ground
                return _text(
                    "422 Unprocessable Entity", f"shot {index} cannot be rendered: {error}"
                )
        self.rendered += 1
        return "200 OK", "image/jpeg", jpeg


JPEG_QUALITY = 90


def nadir_renderer(origin: GeoPoint, seed: int = 1) -> Renderer:
    """Photos of the synthetic ground laid around ``origin`` (its elevation the ground's):
    every simulator given the same origin and seed sees the same ground and targets."""
    from common.opencv import cv2  # the simulator extra's; only a simulator with a camera
    from simulator.sensors.camera import render_nadir
    from simulator.world.ground import Ground

    ground = Ground.around(origin.lat, origin.lon, origin.alt, seed=seed)

    def render(pose: PhotoPose, camera: CameraIntrinsics) -> bytes:
        rgb = render_nadir(pose, camera, ground)
        ok, encoded = cv2.imencode(
            ".jpg", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY]
        )
        if not ok:
            raise ValueError("OpenCV could not encode the photo")
        return bytes(encoded.tobytes())

    return render


def pose_of(photo: PhotoTaken, boot_epoch_s: float) -> PhotoPose:
    """The shot's true pose (the simulator's own, before any sensor noise)."""
    return PhotoPose(
        lat=photo.lat,
        lon=photo.lon,
        alt_msl=photo.alt_msl,
        alt_rel=photo.alt_rel,
        roll=math.degrees(math.remainder(photo.roll, 2 * math.pi)),
        pitch=max(-90.0, min(90.0, math.degrees(photo.pitch))),
        yaw=math.degrees(photo.yaw) % 360.0,
        time=boot_epoch_s + photo.time_s,
    )


def _text(status: str, text: str) -> tuple[str, str, bytes]:
    return status, "text/plain; charset=utf-8", text.encode()
