"""The autopilot's camera trigger to a queued, posed, geotagged photo, through the
simulator's real photo endpoint (its renderer here draws a plain test image)."""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

import pytest
from PIL import ExifTags, Image
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.photos import PhotoMeta, PhotoPose
from simulator.config import ListenAddress
from simulator.outputs.photos import PhotoServer
from simulator.vehicle import PhotoTaken
from tests.support.cameras import (
    BOOT_EPOCH,
    CAMERA,
    Clock,
    _feed_streams,
    feedback,
    photo_server,
    queued,
    render,
    trigger_for,
)
from vehicle_agents.camera.queue import PhotoQueue
from vehicle_agents.camera.sources import SimulatedCamera
from vehicle_agents.camera.trigger import CameraTrigger
from vehicle_agents.sensors.fcu_time import FcuClock, PoseHistory


def test_a_feedback_with_its_pose_becomes_a_geotagged_photo_of_that_pose(tmp_path: Path) -> None:
    async def take() -> tuple[CameraTrigger, int]:
        async with photo_server() as server:
            server.taken(PhotoTaken(3, 42.5, -35.36, 149.16, 612.5, 30.25, 0.0, 0.0, 1.5))
            trigger = trigger_for(server, tmp_path, Clock())
            trigger.on_message(feedback(3, -35.3632621, 149.1652374))
            await queued(trigger)
            return trigger, server.rendered

    trigger, rendered = asyncio.run(take())
    photo = trigger.queue.oldest()
    assert photo is not None
    assert photo.meta.pose == PhotoPose(
        lat=-35.3632621,
        lon=149.1652374,
        alt_msl=612.5,
        alt_rel=30.25,
        roll=2.0,
        pitch=-1.0,
        yaw=91.0,
        time=BOOT_EPOCH + 42.5,
    )
    assert photo.meta.index == 3
    assert photo.meta.camera == CAMERA
    assert PhotoMeta.model_validate_json((tmp_path / f"{photo.photo_id}.json").read_bytes())
    with Image.open(photo.path) as image:
        assert image.size == (120, 80)
        gps = image.getexif().get_ifd(ExifTags.IFD.GPSInfo)
        assert gps[ExifTags.GPS.GPSLatitudeRef] == "S"
    assert rendered == 1


def test_a_feedback_without_a_position_is_posed_from_the_streams(tmp_path: Path) -> None:
    """Position and attitude interpolated to the instant the trigger arrived, on the
    flight controller's clock."""
    clock = Clock()
    trigger = asyncio.run(_posed_from_streams(tmp_path, clock))
    photo = trigger.queue.oldest()
    assert photo is not None
    pose = photo.meta.pose
    assert pose.lat == pytest.approx(10.0001, abs=1e-9)
    assert pose.lon == pytest.approx(20.0)
    assert pose.alt_msl == pytest.approx(150.0)
    assert pose.alt_rel == pytest.approx(50.0)
    assert pose.yaw == pytest.approx(11.459, abs=1e-3)  # 0.2 rad
    assert pose.time == pytest.approx(BOOT_EPOCH + 42.5)


async def _posed_from_streams(tmp_path: Path, clock: Clock) -> CameraTrigger:
    async with photo_server() as server:
        server.taken(PhotoTaken(1, 10.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0))
        trigger = trigger_for(server, tmp_path, clock)
        _feed_streams(trigger, clock)
        clock.now = 100.05
        trigger.on_message(feedback(1, 0.0, 0.0))
        await queued(trigger)
        return trigger


def test_the_photo_endpoint_refuses_unknown_shots_and_bad_cameras() -> None:
    server = PhotoServer(ListenAddress("tcp", "127.0.0.1", 0), render, BOOT_EPOCH)
    status, _, body = asyncio.run(server.answer(b"GET /photos/9?sensor_width_mm=1 HTTP/1.1\r\n"))
    assert status.startswith("400")
    assert b"image_width_px" in body
    query = "&".join(f"{k}={v}" for k, v in CAMERA.model_dump().items())
    status, _, body = asyncio.run(server.answer(f"GET /photos/9?{query} HTTP/1.1\r\n".encode()))
    assert status.startswith("404")
    assert b"no shot 9" in body


def _over_the_wire(message: Any) -> Any:
    """``message`` packed into MAVLink 2 bytes by one end and parsed by another, as the
    agent's link receives it."""
    sender = mavlink2.MAVLink(None, srcSystem=1, srcComponent=100)
    sender.robust_parsing = False
    wire = message.pack(sender)
    received = mavlink2.MAVLink(None).parse_buffer(wire)
    assert received is not None
    assert len(received) == 1
    return received[0]


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_both_autopilots_camera_messages_are_the_exposure(tmp_path: Path, autopilot: str) -> None:
    """ArduPilot's CAMERA_FEEDBACK (with its pose) and PX4's CAMERA_TRIGGER (without one:
    posed from the streams at its arrival) each become one photo, from real bytes."""
    clock = Clock()

    async def take() -> CameraTrigger:
        async with photo_server() as server:
            trigger = trigger_for(server, tmp_path, clock)
            _feed_streams(trigger, clock)
            clock.now = 100.05
            if autopilot == "ardupilot":
                server.taken(PhotoTaken(7, 42.5, 10.0, 20.0, 150.0, 50.0, 0.0, 0.0, 0.2))
                message = feedback(7, 10.0001, 20.0)
            else:
                # PX4 counts its shots from 0 and stamps the exposure's UTC.
                server.taken(PhotoTaken(0, 42.5, 10.0, 20.0, 150.0, 50.0, 0.0, 0.0, 0.2))
                message = mavlink2.MAVLink_camera_trigger_message(int((BOOT_EPOCH + 42.5) * 1e6), 0)
            received = _over_the_wire(message)
            assert received.get_type() == message.get_type()
            trigger.on_message(received)
            await queued(trigger)
            return trigger

    trigger = asyncio.run(take())
    assert trigger.stats.triggers == 1
    photo = trigger.queue.oldest()
    assert photo is not None
    pose = photo.meta.pose
    assert photo.meta.index == (7 if autopilot == "ardupilot" else 0)
    assert pose.lat == pytest.approx(10.0001, abs=1e-7)
    assert pose.lon == pytest.approx(20.0, abs=1e-7)
    assert pose.time == pytest.approx(BOOT_EPOCH + 42.5)
    if autopilot == "px4":  # from the streams: the attitude halfway between 0.1 and 0.3 rad
        assert pose.yaw == pytest.approx(11.459, abs=1e-3)
        assert pose.alt_msl == pytest.approx(150.0)


def test_a_video_feedback_and_other_messages_take_no_photo(tmp_path: Path) -> None:
    clock = Clock()
    queue = PhotoQueue(tmp_path, budget_bytes=10_000_000)
    source = SimulatedCamera("sim+http://127.0.0.1:9", CAMERA)
    trigger = CameraTrigger(
        "sim_1", source, PoseHistory(FcuClock()), queue, lambda t, s: None, monotonic=clock
    )
    video = feedback(1, 10.0, 20.0)
    video.flags = 1  # CAMERA_FEEDBACK_VIDEO
    trigger.on_message(_over_the_wire(video))
    trigger.on_message(_over_the_wire(mavlink2.MAVLink_heartbeat_message(2, 3, 0, 0, 0, 3)))
    assert trigger.stats.triggers == 0
