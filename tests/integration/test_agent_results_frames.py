"""MAV_RESULT names and the frames position commands go in, per autopilot.

The result codes come from a scripted flight controller (tests/mavlink_peer.py) over
real TCP; the frames are checked against the simulator's PX4 and ArduCopter
personalities, which refuse what the real autopilots refuse.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Awaitable, Callable
from typing import TypeVar

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.protocol import ChangeSpeedCommand, CommandOutcome
from tests.mavlink_peer import Answer, ScriptedFlightController
from vehicle_agents.commands import CommandExecutor, CommandTimeouts
from vehicle_agents.fcu_link import FcuLink, MavMessage
from vehicle_agents.mav_results import result_name

pytestmark = pytest.mark.integration

TIMEOUTS = CommandTimeouts(ack_s=0.5, attempts=3, in_progress_s=1.5)
T = TypeVar("T")


async def on_link(url: str, body: Callable[[CommandExecutor], Awaitable[T]]) -> T:
    """Run ``body`` with an executor on a live FcuLink to ``url``, telemetry flowing."""
    link = FcuLink(url)
    running = asyncio.create_task(link.run())
    try:
        await asyncio.wait_for(link.wait_identified(), 10)
        while link.latest.get("HOME_POSITION") is None:
            await link.wait_for(lambda m: m.get_type() == "HOME_POSITION", 5)
        return await body(CommandExecutor(link, TIMEOUTS))
    finally:
        running.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await running


# -- MAV_RESULT names -------------------------------------------------------------------


def test_every_standard_result_code_has_its_name_and_others_show_their_number() -> None:
    """The current standard's codes by name (pymavlink's dialect ends at 8 and calls 9
    its ENUM_END); a code newer than the table reads as its number."""
    expected = [
        "ACCEPTED",
        "TEMPORARILY_REJECTED",
        "DENIED",
        "UNSUPPORTED",
        "FAILED",
        "IN_PROGRESS",
        "CANCELLED",
        "COMMAND_LONG_ONLY",
        "COMMAND_INT_ONLY",
        "COMMAND_UNSUPPORTED_MAV_FRAME",
        "NOT_IN_CONTROL",
    ]
    assert [result_name(code) for code in range(11)] == [f"MAV_RESULT_{n}" for n in expected]
    assert result_name(11) == "MAV_RESULT 11"
    assert result_name(200) == "MAV_RESULT 200"


def test_a_refusal_names_the_result_the_flight_controller_sent() -> None:
    """Result codes 6, 9 and an unknown 42, as COMMAND_ACKs on the wire, reach the
    operator by name (or by number), never as MAV_RESULT_ENUM_END."""
    speed = mavlink2.MAV_CMD_DO_CHANGE_SPEED

    def answer(message: MavMessage) -> list[Answer]:
        return [Answer(0.0, int(message.param2))]  # the speed asked for is the answer

    async def body(executor: CommandExecutor) -> list[CommandOutcome]:
        return [await executor.execute(ChangeSpeedCommand(speed=code)) for code in (6, 9, 42)]

    with ScriptedFlightController() as fcu:
        fcu.scripts[speed] = answer
        outcomes = asyncio.run(on_link(f"tcp:127.0.0.1:{fcu.port}", body))
    assert [o.status for o in outcomes] == ["refused"] * 3
    assert [o.result for o in outcomes] == [
        "MAV_RESULT_CANCELLED",
        "MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME",
        "MAV_RESULT 42",
    ]
    assert outcomes[1].message.startswith(
        "MAV_CMD_DO_CHANGE_SPEED: MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME"
    )
