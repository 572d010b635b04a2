"""Acks that arrive together: the flight controller's IN_PROGRESS and its final ACK in
one read from the wire reach the command exchange in one batch, and both count."""

from __future__ import annotations

import asyncio
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import ChangeSpeedCommand
from vehicle_agents.control.executor import CommandExecutor
from vehicle_agents.fcu.commands import CommandTimeouts
from vehicle_agents.fcu.link import FcuLink

VEHICLE = 1


class _Wire:
    """Stands in for pymavlink's connection object: what the agent writes is answered
    with the frames a flight controller would send, handed over as the reader thread
    does, in one batch."""

    def __init__(self, link: FcuLink, answers: list[Any]) -> None:
        self.mav = self
        self._link = link
        self._answers = answers

    def send(self, message: Any) -> None:
        mav = mavlink2.MAVLink(None, srcSystem=VEHICLE, srcComponent=1)
        frames = [mav.decode(bytearray(answer.pack(mav))) for answer in self._answers]
        self._link._inbox.extend(frames)
        asyncio.get_running_loop().call_soon(self._link._deliver_inbox)


def _ack(result: int, progress: int = 0) -> Any:
    return mavlink2.MAVLink_command_ack_message(
        mavlink2.MAV_CMD_DO_CHANGE_SPEED, result, progress, 0, 254, 190
    )


def test_a_final_ack_right_behind_in_progress_is_not_missed() -> None:
    link = FcuLink("tcp:127.0.0.1:1")
    link.target_system = VEHICLE
    heartbeat = mavlink2.MAVLink_heartbeat_message(2, 3, 0, 0, 4, 3)
    link.received_at["HEARTBEAT"] = float("inf")  # counts as connected
    link.latest["HEARTBEAT"] = heartbeat
    wire = _Wire(
        link, [_ack(mavlink2.MAV_RESULT_IN_PROGRESS, 50), _ack(mavlink2.MAV_RESULT_ACCEPTED)]
    )
    link._connection = wire
    executor = CommandExecutor(link, CommandTimeouts(ack_s=0.5, attempts=1, in_progress_s=1.0))
    outcome = asyncio.run(executor.execute(ChangeSpeedCommand(speed=3.0)))
    assert outcome.status == "accepted", outcome
