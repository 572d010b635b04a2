"""A MAVLink camera component's photos: its CAMERA_IMAGE_CAPTURED is the shutter, its
file_url fetched over real HTTP (the simulator's photo endpoint, or a plain server that
answers too much), bad addresses refused with the reason."""

from __future__ import annotations

import asyncio
import http.server
import math
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator.outputs.cameras import CameraComponent
from simulator.outputs.photos import pose_of
from simulator.vehicle import PhotoTaken
from tests.support.cameras import (
    BOOT_EPOCH,
    CAMERA,
    Clock,
    feedback,
    photo_server,
    queued,
)
from tests.support.waiting import poll_until_async
from vehicle_agents.camera.mavlink_camera import MavlinkCamera
from vehicle_agents.camera.queue import PhotoQueue
from vehicle_agents.camera.sources import CaptureError, Shot
from vehicle_agents.camera.trigger import CameraTrigger
from vehicle_agents.sensors.fcu_time import FcuClock, PoseHistory

SHOT = PhotoTaken(3, 42.5, -35.36, 149.16, 612.5, 30.25, 0.0, 0.0, 1.5)


def _over_the_wire(message: Any, component: int) -> Any:
    sender = mavlink2.MAVLink(None, srcSystem=1, srcComponent=component)
    received = mavlink2.MAVLink(None).parse_buffer(message.pack(sender))
    assert received is not None
    return received[0]


def _shot(url: str | None) -> Shot:
    return Shot(0, 100.0, BOOT_EPOCH, None, url)


def _trigger(tmp_path: Path, source: MavlinkCamera, said: list[str]) -> CameraTrigger:
    poses = PoseHistory(FcuClock(), monotonic=Clock())
    queue = PhotoQueue(tmp_path, budget_bytes=10_000_000)
    return CameraTrigger(
        "cam_1", source, poses, queue, lambda text, _severity: said.append(text), monotonic=Clock()
    )


def test_the_cameras_capture_is_the_photo_fetched_from_its_address(tmp_path: Path) -> None:
    """The simulator's camera component's message, from component 100, becomes one photo
    with the pose the message gives; the autopilot's feedback of the same shutter makes
    none of its own."""
    said: list[str] = []

    async def take() -> CameraTrigger:
        async with photo_server() as server:
            assert server.address is not None
            server.taken(SHOT)
            component = CameraComponent(server.address, CAMERA)
            captured = component.image_captured(SHOT, pose_of(SHOT, BOOT_EPOCH), BOOT_EPOCH)
            trigger = _trigger(tmp_path, MavlinkCamera(CAMERA), said)
            trigger.on_message(_over_the_wire(feedback(3, -35.36, 149.16), 1))
            trigger.on_message(_over_the_wire(captured, mavlink2.MAV_COMP_ID_CAMERA))
            trigger.on_message(_over_the_wire(captured, mavlink2.MAV_COMP_ID_CAMERA))  # resent
            await queued(trigger)
            return trigger

    trigger = asyncio.run(take())
    assert (trigger.stats.triggers, trigger.stats.queued, trigger.stats.repeats) == (1, 1, 1)
    photo = trigger.queue.oldest()
    assert photo is not None
    assert photo.meta.index == 0  # the camera's own count
    pose = photo.meta.pose
    assert (pose.lat, pose.lon, pose.alt_msl, pose.alt_rel) == (-35.36, 149.16, 612.5, 30.25)
    assert (pose.roll, pose.pitch) == (pytest.approx(0.0), pytest.approx(0.0))
    assert pose.yaw == pytest.approx(math.degrees(1.5), abs=1e-4)
    assert pose.time == pytest.approx(BOOT_EPOCH + 42.5)
    assert said == []


@pytest.fixture
def oversize_server() -> Iterator[str]:
    """Answers 2,000 bytes: /declared with a Content-Length, /undeclared without one."""

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            self.send_response(200)
            self.send_header("Content-Type", "image/jpeg")
            if self.path == "/declared":
                self.send_header("Content-Length", "2000")
            self.end_headers()
            self.wfile.write(b"\xff" * 2000)

        def log_message(self, *args: Any) -> None:
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


@pytest.mark.parametrize("path", ["/declared", "/undeclared"])
def test_a_file_larger_than_a_photo_may_be_is_refused(oversize_server: str, path: str) -> None:
    camera = MavlinkCamera(CAMERA, max_bytes=1000, timeout_s=5)
    with pytest.raises(CaptureError, match=r"too large for a photo: .*1000"):
        asyncio.run(camera.capture(_shot(oversize_server + path)))


def test_a_file_the_camera_does_not_have_is_refused_with_its_404() -> None:
    async def fetch() -> None:
        async with photo_server() as server:
            assert server.address is not None
            url = CameraComponent(server.address, CAMERA).file_url(41)  # never taken
            await MavlinkCamera(CAMERA, timeout_s=5).capture(_shot(url))

    with pytest.raises(
        CaptureError, match=r"the camera refused .*/photos/41.*HTTP 404.*no shot 41"
    ):
        asyncio.run(fetch())


@pytest.mark.parametrize(
    ("url", "message"),
    [
        ("mftp:///DCIM/IMG_0001.JPG", "MAVLink FTP .* not supported"),
        ("ftp://camera/IMG_0001.JPG", "not an http\\(s\\) URL"),
        (None, "no file address"),
        ("http://127.0.0.1:1/none.jpg", "could not fetch"),
    ],
)
def test_an_address_the_agent_cannot_fetch_says_why(url: str | None, message: str) -> None:
    with pytest.raises(CaptureError, match=message):
        asyncio.run(MavlinkCamera(CAMERA, timeout_s=5).capture(_shot(url)))


def test_an_unfetchable_photo_is_said_in_an_event_not_dropped(tmp_path: Path) -> None:
    said: list[str] = []
    captured = mavlink2.MAVLink_camera_image_captured_message(
        42_500, 0, 1, 0, 0, 0, 0, [1, 0, 0, 0], 7, 1, b"mftp:///DCIM/IMG_0007.JPG"
    )

    async def take() -> CameraTrigger:
        trigger = _trigger(tmp_path, MavlinkCamera(CAMERA), said)
        trigger.on_message(_over_the_wire(captured, mavlink2.MAV_COMP_ID_CAMERA))
        task = asyncio.create_task(trigger.run())
        try:
            await poll_until_async(lambda: said, 10, "the failure said")
        finally:
            task.cancel()
        return trigger

    trigger = asyncio.run(take())
    assert trigger.stats.capture_failed == 1
    assert said == [
        "photo 7 not taken: mftp:///DCIM/IMG_0007.JPG: MAVLink FTP (mftp://) file addresses "
        "are not supported; set the camera to serve its images over HTTP"
    ]
