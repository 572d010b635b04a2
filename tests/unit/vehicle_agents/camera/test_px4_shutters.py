"""PX4's two messages of a shutter (CAMERA_TRIGGER, CAMERA_IMAGE_CAPTURED) to one photo
each, from real bytes, through the simulator's photo endpoint: none counted twice, none
lost, a lane end's pair of shutters a millisecond apart two photos."""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator.vehicle import PhotoTaken
from tests.support.cameras import (
    BOOT_EPOCH,
    CAMERA,
    Clock,
    _feed_streams,
    photo_server,
    trigger_for,
)
from tests.support.waiting import poll_until_async
from vehicle_agents.camera.queue import QueuedPhoto
from vehicle_agents.camera.sources import SimulatedCamera
from vehicle_agents.camera.trigger import SHOT_QUEUE, CameraTrigger
from vehicle_agents.telemetry.shutters import ShutterMatcher

AUTOPILOT = mavlink2.MAV_COMP_ID_AUTOPILOT1

UNREACHABLE_CAMERA = SimulatedCamera("sim+http://127.0.0.1:9", CAMERA)


def _over_the_wire(message: Any, component: int = AUTOPILOT) -> Any:
    """Packed into MAVLink 2 bytes by the sender's component and parsed back."""
    sender = mavlink2.MAVLink(None, srcSystem=1, srcComponent=component)
    [received] = mavlink2.MAVLink(None).parse_buffer(message.pack(sender)) or []
    return received


def trigger(seq: int) -> object:
    return _over_the_wire(mavlink2.MAVLink_camera_trigger_message(int(42.5e6), seq))


def captured(
    index: int, lat: float = 10.0001, result: int = 1, component: int = AUTOPILOT
) -> object:
    # yawed 90 degrees (a quaternion about the down axis)
    half = 0.7071067811865476
    return _over_the_wire(
        mavlink2.MAVLink_camera_image_captured_message(
            42_500,
            int((BOOT_EPOCH + 42.5) * 1e6),
            0,
            round(lat * 1e7),
            200_000_000,
            150_000,
            -1000,  # relative_alt: PX4 puts the rangefinder's reading (none) here
            [half, 0.0, 0.0, half],
            index,
            result,
            b"",
        ),
        component,
    )


async def _take(tmp_path: Path, messages: list[object], shots: int) -> CameraTrigger:
    clock = Clock()
    async with photo_server() as server:
        for index in range(shots):
            server.taken(PhotoTaken(index, 42.5, 10.0, 20.0, 150.0, 50.0, 0.0, 0.0, 0.2))
        camera = trigger_for(server, tmp_path, clock)
        _feed_streams(camera, clock)
        clock.now = 100.05
        for message in messages:
            camera.on_message(message)
        task = asyncio.create_task(camera.run())
        try:
            await poll_until_async(
                lambda: camera.stats.queued + camera.stats.no_pose >= camera.stats.triggers,
                10,
                "every trigger taken",
            )
        finally:
            task.cancel()
        return camera


def test_each_shutter_is_one_photo_whichever_of_its_messages_come(tmp_path: Path) -> None:
    """Shutter 0: both messages; 1 and 2, a lane end's pair: both triggers, then both
    captures; 3: only its CAMERA_IMAGE_CAPTURED (a link that never asked for triggers)."""
    messages = [
        trigger(0),
        captured(0),
        trigger(1),
        trigger(2),
        captured(1),
        captured(2),
        captured(3, lat=10.0003),
    ]
    camera = asyncio.run(_take(tmp_path, messages, shots=4))
    assert camera.stats.triggers == 4
    assert camera.stats.repeats == 3
    assert camera.stats.queued == 4
    assert len(camera.queue) == 4
    photos: list[QueuedPhoto] = []
    while (photo := camera.queue.oldest({p.photo_id for p in photos})) is not None:
        photos.append(photo)
    by_index = {p.meta.index: p.meta.pose for p in photos}
    assert sorted(by_index) == [0, 1, 2, 3]
    # The capture's own pose, even when its trigger came first: the autopilot's record
    # at the shutter, yaw from its quaternion.
    assert by_index[1].lat == pytest.approx(10.0001, abs=1e-7)
    assert by_index[1].yaw == pytest.approx(90.0, abs=1e-4)  # a float32 quaternion
    assert by_index[3].lat == pytest.approx(10.0003, abs=1e-7)
    assert by_index[3].alt_rel == pytest.approx(50.0)  # alt less home's, from the streams


def test_two_shutters_numbered_alike_are_two_photos_none_overwritten(tmp_path: Path) -> None:
    """Two CAMERA_TRIGGERs with one number in one millisecond: two shutters, and the
    second photo must not take the first one's place in the queue."""
    camera = asyncio.run(_take(tmp_path, [trigger(5), trigger(5)], shots=6))
    assert camera.stats.triggers == 2
    assert camera.stats.queued == 2
    assert len(camera.queue) == 2


def test_a_camera_components_own_captures_are_not_the_autopilots_triggers() -> None:
    """A MAVLink camera beside the autopilot (Gazebo's, in PX4 SITL) numbers its own
    CAMERA_IMAGE_CAPTURED: not matched to the autopilot's triggers, not a photo here."""
    camera = CameraTrigger(
        "sim_1",
        source=UNREACHABLE_CAMERA,  # the shots are counted; none is fetched
        poses=None,  # type: ignore[arg-type]
        queue=None,  # type: ignore[arg-type]
        notify=lambda text, severity: None,
        monotonic=Clock(),
    )
    camera.on_message(captured(0, component=mavlink2.MAV_COMP_ID_CAMERA))
    assert camera.stats.triggers == 0


def test_a_failed_capture_is_counted_and_said() -> None:
    said: list[str] = []
    camera = CameraTrigger(
        "sim_1",
        source=UNREACHABLE_CAMERA,  # the shots are counted; none is fetched
        poses=None,  # type: ignore[arg-type]
        queue=None,  # type: ignore[arg-type]
        notify=lambda text, severity: said.append(text),
        monotonic=Clock(),
    )
    camera.on_message(captured(4, result=0))
    assert camera.stats.triggers == 1
    assert camera.stats.failed_on_board == 1
    assert said == ["photo 4 not taken: the camera failed"]


def test_the_matcher_pairs_by_index_only_and_forgets_a_restarted_counter() -> None:
    shutters = ShutterMatcher()
    assert shutters.is_new("CAMERA_TRIGGER", 0, 1.0)
    assert not shutters.is_new("CAMERA_IMAGE_CAPTURED", 0, 1.001)
    assert shutters.is_new("CAMERA_TRIGGER", 0, 1.002)  # numbered alike: another shutter
    assert not shutters.is_new("CAMERA_IMAGE_CAPTURED", 0, 1.003)
    assert shutters.is_new("CAMERA_IMAGE_CAPTURED", 0, 60.0)  # after a reboot


def test_a_trigger_the_full_queue_cannot_hold_is_counted_and_said() -> None:
    """More triggers than wait for the camera: the one dropped says so, as an event."""
    said: list[str] = []
    camera = CameraTrigger(
        "sim_1",
        source=UNREACHABLE_CAMERA,  # the shots are counted; none is fetched
        poses=None,  # type: ignore[arg-type]
        queue=None,  # type: ignore[arg-type]
        notify=lambda text, severity: said.append(text),
        monotonic=Clock(),
    )

    async def burst() -> None:  # the shot queue is the event loop's
        for seq in range(SHOT_QUEUE + 1):
            camera.on_message(trigger(seq))

    asyncio.run(burst())
    assert (camera.stats.triggers, camera.stats.dropped_triggers) == (SHOT_QUEUE + 1, 1)
    assert said == [
        f"photo {SHOT_QUEUE} not taken: {SHOT_QUEUE} triggers already wait for the camera "
        "(1 dropped so far)"
    ]
