"""PX4's camera on the wire, against the simulator's PX4 personality: CAMERA_TRIGGER only
for a link that asked for it (the agent does), CAMERA_IMAGE_CAPTURED for every link, no
ArduPilot CAMERA_FEEDBACK; ArduPilot's camera keeps its CAMERA_FEEDBACK and is not asked
for CAMERA_TRIGGER. Two shutters a moment apart (a lane end's pair) are two of each."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator.config import ListenAddress, SimulatorConfig
from tests.support.simulators import serving
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.fcu.streams import StreamRequester, StreamTimeouts

pytestmark = pytest.mark.integration

CAMERA_MESSAGES = ("CAMERA_TRIGGER", "CAMERA_IMAGE_CAPTURED", "CAMERA_FEEDBACK")


def sim_config(autopilot: Any) -> SimulatorConfig:
    return SimulatorConfig(
        listen=ListenAddress("tcp", "127.0.0.1", 0), system_id=3, autopilot=autopilot
    )


async def camera_messages(port: int) -> tuple[list[MavMessage], list[MavMessage], list[int]]:
    """The agent's link (after its stream requests) and another GCS's: what each hears of
    two shutters fired together and a third, and what the agent asked intervals for."""
    agent = FcuLink(f"tcp:127.0.0.1:{port}", source_system=245)
    other = FcuLink(f"tcp:127.0.0.1:{port}", source_system=246)
    heard: dict[str, list[MavMessage]] = {"agent": [], "other": []}

    def hears(name: str) -> Callable[[MavMessage], None]:
        def keep(message: MavMessage) -> None:
            if message.get_type() in CAMERA_MESSAGES:
                heard[name].append(message)

        return keep

    agent.listeners.append(hears("agent"))
    other.listeners.append(hears("other"))
    asked: list[int] = []
    requester = StreamRequester(agent, {}, StreamTimeouts(ack_s=0.5, attempts=2))
    original = requester._set_interval

    async def recording(request: Any) -> int | None:
        asked.append(request.msg_id)
        return await original(request)

    requester._set_interval = recording  # type: ignore[method-assign]
    async with asyncio.TaskGroup() as tasks:
        running = [tasks.create_task(agent.run()), tasks.create_task(other.run())]
        await asyncio.wait_for(agent.wait_identified(), 10)
        await asyncio.wait_for(other.wait_identified(), 10)
        assert await requester.request() == "message_interval"
        for _ in range(2):  # back to back: the simulator fires both in one step
            agent.send_command_long(mavlink2.MAV_CMD_DO_DIGICAM_CONTROL, 0, [0, 0, 0, 0, 1, 0, 0])
        await asyncio.sleep(0)
        agent.send_command_long(mavlink2.MAV_CMD_DO_DIGICAM_CONTROL, 0, [0, 0, 0, 0, 1, 0, 0])

        def every_shot_heard() -> bool:
            return all(len({_index(m) for m in got}) >= 3 for got in heard.values())

        async with asyncio.timeout(10):
            while not every_shot_heard():
                await agent.wait_for(lambda m: True, 0.5)
        # what a late message would add: one more heartbeat on each link
        await agent.wait_for(lambda m: m.get_type() == "HEARTBEAT", 2)
        await other.wait_for(lambda m: m.get_type() == "HEARTBEAT", 2)
        for task in running:
            task.cancel()
    return heard["agent"], heard["other"], asked


def _index(message: MavMessage) -> int:
    kind = message.get_type()
    if kind == "CAMERA_TRIGGER":
        return int(message.seq)
    if kind == "CAMERA_IMAGE_CAPTURED":
        return int(message.image_index)
    return int(message.img_idx)


def _told(messages: list[MavMessage]) -> list[tuple[str, int]]:
    return sorted((m.get_type(), _index(m)) for m in messages)


def test_px4_sends_camera_trigger_only_where_asked_and_image_captured_to_every_link() -> None:
    with serving(sim_config("px4")) as (_server, address):
        agent, other, asked = asyncio.run(camera_messages(address.port))
    assert mavlink2.MAVLINK_MSG_ID_CAMERA_TRIGGER in asked
    # PX4 numbers its shutters from 0, in both messages
    assert _told(agent) == [
        *(("CAMERA_IMAGE_CAPTURED", i) for i in range(3)),
        *(("CAMERA_TRIGGER", i) for i in range(3)),
    ]
    assert _told(other) == [("CAMERA_IMAGE_CAPTURED", i) for i in range(3)]
    first = next(m for m in other if m.image_index == 0)
    assert first.capture_result == 1
    assert (first.lat, first.lon) != (0, 0)
    assert abs(first.q[0]) == pytest.approx(1.0, abs=0.01)  # standing level


def test_ardupilot_keeps_camera_feedback_and_is_not_asked_for_camera_trigger() -> None:
    with serving(sim_config("ardupilot")) as (_server, address):
        agent, other, asked = asyncio.run(camera_messages(address.port))
    assert mavlink2.MAVLINK_MSG_ID_CAMERA_TRIGGER not in asked
    assert _told(agent) == _told(other) == [("CAMERA_FEEDBACK", i) for i in (1, 2, 3)]
