"""The agent's flight-controller side in-process against a `ScriptedFlightController`
(tests/support/mavlink_peer.py): its `FcuLink` and `EventSource`, with the events read back from
a real `Outbox`, and the MAVLink messages the report tests push."""

from __future__ import annotations

import asyncio
import contextlib
import json
import time
from collections.abc import AsyncIterator, Callable
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import VehicleState
from tests.support.mavlink_peer import ScriptedFlightController
from vehicle_agents.agent import EventSource
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.hub.outbox import Outbox
from vehicle_agents.telemetry.snapshot import link_snapshot

PX4 = mavlink2.MAV_AUTOPILOT_PX4
ARDUPILOT = mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA
NO_MISSION = mavlink2.MISSION_STATE_NO_MISSION
ACTIVE = mavlink2.MISSION_STATE_ACTIVE
LAT, LON = -353632620, 1491652370


class Agent:
    """The agent's FCU side, in-process: its link, its events, its snapshot."""

    def __init__(self, link: FcuLink, outbox: Outbox) -> None:
        self.link, self.outbox = link, outbox

    async def events(self, count: int, timeout_s: float = 5.0) -> list[dict[str, Any]]:
        got: list[dict[str, Any]] = []
        async with asyncio.timeout(timeout_s):
            while len(got) < count:
                got.append(json.loads(await self.outbox.next_frame()))
        return got

    async def no_more_events(self, quiet_s: float = 1.5) -> None:
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(quiet_s):
                extra = json.loads(await self.outbox.next_frame())
                raise AssertionError(f"unexpected event {extra}")

    async def state_until(
        self, check: Callable[[VehicleState], bool], timeout_s: float = 8.0
    ) -> VehicleState:
        deadline = time.monotonic() + timeout_s
        while not check(state := link_snapshot(self.link)):
            assert time.monotonic() < deadline, f"state never matched: {state}"
            await self.link.wait_for(lambda m: True, 0.5)
        return state

    async def received(self, kind: str, timeout_s: float = 5.0) -> MavMessage:
        message = await self.link.wait_for(lambda m: m.get_type() == kind, timeout_s)
        assert message is not None, f"no {kind} arrived"
        return message


@contextlib.asynccontextmanager
async def agent_on(
    fcu: ScriptedFlightController, *, has_image_source: bool = True
) -> AsyncIterator[Agent]:
    link = FcuLink(f"tcp:127.0.0.1:{fcu.port}")
    running = asyncio.create_task(link.run())
    try:
        await asyncio.wait_for(link.wait_identified(), 10)
        assert link.modes is not None
        outbox = Outbox("test", 1000)
        events = EventSource(outbox, link.modes.autopilot, has_image_source=has_image_source)
        link.listeners.append(events.on_message)
        yield Agent(link, outbox)
    finally:
        running.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await running


def current(seq: int, total: int, state: int = ACTIVE) -> MavMessage:
    return mavlink2.MAVLink_mission_current_message(seq, total, state, 0)


def reached(seq: int) -> MavMessage:
    return mavlink2.MAVLink_mission_item_reached_message(seq)


def text(body: str, text_id: int = 0, chunk: int = 0) -> MavMessage:
    return mavlink2.MAVLink_statustext_message(
        mavlink2.MAV_SEVERITY_INFO, body.encode(), text_id, chunk
    )
