"""Each photo the camera takes is an event with its place (issue 17): ArduPilot's
CAMERA_FEEDBACK, PX4's CAMERA_TRIGGER and CAMERA_IMAGE_CAPTURED, pushed as real MAVLink
bytes by a scripted flight controller to the agent's link run in-process
(tests/support/fcu_reports.py)."""

from __future__ import annotations

import asyncio

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from tests.support.fcu_reports import (
    ARDUPILOT,
    LAT,
    LON,
    PX4,
    agent_on,
)
from tests.support.mavlink_peer import ScriptedFlightController
from vehicle_agents.fcu.messages import MavMessage

pytestmark = pytest.mark.integration


def feedback(index: int, target_system: int, flags: int) -> MavMessage:
    # As AP_Camera::send_feedback fills it: target_system is the vehicle's own id.
    return mavlink2.MAVLink_camera_feedback_message(
        0, target_system, 0, index, LAT, LON, 620.5, 30.25, 0, 0, 90, 0, flags, index
    )


def test_camera_feedback_becomes_a_camera_event_with_the_photo() -> None:
    async def run() -> None:
        with ScriptedFlightController(autopilot=ARDUPILOT) as fcu:
            async with agent_on(fcu) as agent:
                fcu.push(
                    feedback(1, fcu.system_id, mavlink2.CAMERA_FEEDBACK_PHOTO),
                    feedback(2, fcu.system_id, mavlink2.CAMERA_FEEDBACK_VIDEO),
                    feedback(3, fcu.system_id, mavlink2.CAMERA_FEEDBACK_PHOTO),
                )
                events = await agent.events(2)
                await agent.no_more_events()
        assert [e["kind"] for e in events] == ["camera", "camera"]
        assert events[0]["photo"] == {
            "index": 1,
            "lat": LAT / 1e7,
            "lon": LON / 1e7,
            "alt_rel": 30.25,
        }
        assert events[1]["photo"]["index"] == 3
        assert events[0]["text"].startswith("photo 1 at -35.3632620, 149.1652370")

    asyncio.run(run())


def test_camera_feedback_without_an_image_source_is_counted_and_said_once() -> None:
    """SITL's camera (ArduPilot's CAM1_TYPE 1, PX4's TRIG_INTERFACE 3) tells of each
    shutter with no image anywhere: the agent without --camera counts each, and says
    once that no image will follow."""

    async def run() -> None:
        with ScriptedFlightController(autopilot=ARDUPILOT) as fcu:
            async with agent_on(fcu, has_image_source=False) as agent:
                fcu.push(
                    feedback(1, fcu.system_id, mavlink2.CAMERA_FEEDBACK_PHOTO),
                    feedback(2, fcu.system_id, mavlink2.CAMERA_FEEDBACK_PHOTO),
                )
                events = await agent.events(3)
                await agent.no_more_events()
        assert [e["kind"] for e in events] == ["camera", "upload", "camera"]
        assert events[1]["text"] == (
            "photo 1: the autopilot's camera fired, but no image source is configured "
            "(--camera): shots are counted, no image is uploaded"
        )
        assert events[1]["severity"] == mavlink2.MAV_SEVERITY_NOTICE

    asyncio.run(run())


def test_px4s_camera_trigger_becomes_a_camera_event_where_the_drone_was() -> None:
    """PX4's CAMERA_TRIGGER carries no position: the photo is placed at the latest
    GLOBAL_POSITION_INT; none is reported before the autopilot has a position."""

    async def run() -> None:
        with ScriptedFlightController(autopilot=PX4) as fcu:
            async with agent_on(fcu) as agent:
                fcu.push(mavlink2.MAVLink_camera_trigger_message(0, 0))  # no position yet
                await agent.no_more_events()
                fcu.push(
                    mavlink2.MAVLink_global_position_int_message(
                        1000, LAT, LON, 614_500, 30_250, 0, 0, 0, 0
                    ),
                    mavlink2.MAVLink_camera_trigger_message(1_764_288_000_000_000, 1),
                )
                events = await agent.events(1)
        assert events[0]["kind"] == "camera"
        assert events[0]["photo"] == {
            "index": 1,
            "lat": LAT / 1e7,
            "lon": LON / 1e7,
            "alt_rel": 30.25,
        }

    asyncio.run(run())


def captured(index: int, lat: int = LAT) -> MavMessage:
    """PX4's CAMERA_IMAGE_CAPTURED (camera_feedback), level and facing north, 30.25 m
    above home; its relative_alt is the rangefinder's (-1 m: none)."""
    return mavlink2.MAVLink_camera_image_captured_message(
        42_000, 0, 0, lat, LON, 614_500, -1000, [1.0, 0.0, 0.0, 0.0], index, 1, b""
    )


def test_px4s_two_messages_of_a_shutter_are_one_camera_event_and_a_close_pair_two() -> None:
    """PX4 tells of each shutter with CAMERA_TRIGGER (where asked for) and
    CAMERA_IMAGE_CAPTURED, with one index: one event each, whichever comes first or alone;
    a lane end's two shutters a millisecond apart are two."""

    async def run() -> None:
        with ScriptedFlightController(autopilot=PX4) as fcu:
            async with agent_on(fcu) as agent:
                fcu.push(
                    mavlink2.MAVLink_global_position_int_message(
                        1000, LAT, LON, 614_500, 30_250, 0, 0, 0, 0
                    ),
                    mavlink2.MAVLink_camera_trigger_message(0, 0),
                    captured(0),
                    mavlink2.MAVLink_camera_trigger_message(0, 1),  # the lane end's pair
                    mavlink2.MAVLink_camera_trigger_message(0, 2),
                    captured(1),
                    captured(2),
                    captured(3, lat=LAT + 100),  # no CAMERA_TRIGGER: the link never asked
                )
                events = await agent.events(4)
                await agent.no_more_events()
        assert [e["kind"] for e in events] == ["camera"] * 4
        assert [e["photo"]["index"] for e in events] == [0, 1, 2, 3]
        assert events[3]["photo"] == {
            "index": 3,
            "lat": (LAT + 100) / 1e7,
            "lon": LON / 1e7,
            "alt_rel": 30.25,
        }

    asyncio.run(run())
