"""A camera trigger fed by hand: its clock, its streams, a photo server."""

from __future__ import annotations

import asyncio
import contextlib
import io
from collections.abc import AsyncIterator
from pathlib import Path

from PIL import Image
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.photos import CameraIntrinsics, PhotoPose
from simulator.config import ListenAddress
from simulator.outputs.photos import PhotoServer
from tests.support.waiting import poll_until_async
from vehicle_agents.camera.queue import PhotoQueue
from vehicle_agents.camera.sources import SimulatedCamera
from vehicle_agents.camera.trigger import CameraTrigger
from vehicle_agents.sensors.fcu_time import FcuClock, PoseHistory

CAMERA = CameraIntrinsics(
    sensor_width_mm=13.2,
    sensor_height_mm=8.8,
    image_width_px=120,
    image_height_px=80,
    focal_length_mm=8.8,
)


BOOT_EPOCH = 1_764_288_000.0


def render(pose: PhotoPose, camera: CameraIntrinsics) -> bytes:
    out = io.BytesIO()
    size = (camera.image_width_px, camera.image_height_px)
    Image.new("RGB", size, (round(pose.yaw) % 256, 80, 40)).save(out, "JPEG")
    return out.getvalue()


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


@contextlib.asynccontextmanager
async def photo_server() -> AsyncIterator[PhotoServer]:
    photos = PhotoServer(ListenAddress("tcp", "127.0.0.1", 0), render, BOOT_EPOCH)
    await photos.start()
    try:
        yield photos
    finally:
        await photos.stop()


def trigger_for(server: PhotoServer, tmp_path: Path, clock: Clock) -> CameraTrigger:
    assert server.address is not None
    source = SimulatedCamera(f"sim+http://127.0.0.1:{server.address.port}", CAMERA)
    poses = PoseHistory(FcuClock(), monotonic=clock)
    queue = PhotoQueue(tmp_path, budget_bytes=10_000_000)
    return CameraTrigger("sim_1", source, poses, queue, lambda t, s: None, monotonic=clock)


def _feed_streams(trigger: CameraTrigger, clock: Clock) -> None:
    listeners = [trigger.poses.on_message, trigger.on_message]
    for boot_ms, lat, yaw in ((10_000, 10.0, 0.1), (10_100, 10.0002, 0.3)):
        clock.now = 100.0 + (boot_ms - 10_000) / 1000
        for message in (
            mavlink2.MAVLink_global_position_int_message(
                boot_ms, round(lat * 1e7), 200_000_000, 150_000, 50_000, 0, 0, 0, 0
            ),
            mavlink2.MAVLink_attitude_message(boot_ms, 0.0, 0.0, yaw, 0, 0, 0),
        ):
            for listen in listeners:
                listen(message)


async def queued(trigger: CameraTrigger) -> None:
    task = asyncio.create_task(trigger.run())
    try:
        await poll_until_async(lambda: trigger.stats.queued, 10, "the photo queued")
    finally:
        task.cancel()


def feedback(index: int, lat: float, lon: float) -> object:
    return mavlink2.MAVLink_camera_feedback_message(
        int((BOOT_EPOCH + 42.5) * 1e6),
        1,
        0,
        index,
        round(lat * 1e7),
        round(lon * 1e7),
        612.5,
        30.25,
        2.0,
        -1.0,
        91.0,
        0.0,
        mavlink2.CAMERA_FEEDBACK_PHOTO,
        index,
    )
