"""Numbered snapshots of the vehicle, into the outbox the hub link drains."""

from __future__ import annotations

import asyncio
import time

from protocol.messages import Telemetry, VehicleState, encode
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.fcu.modes import is_armed
from vehicle_agents.hub.outbox import Outbox
from vehicle_agents.telemetry.snapshot import link_snapshot


def current_state(link: FcuLink, outbox: Outbox) -> VehicleState:
    """The vehicle now, with the agent's own delivery counters."""
    return link_snapshot(link).model_copy(
        update={"outbox_pending": len(outbox), "outbox_dropped": outbox.dropped}
    )


class TelemetryPublisher:
    """Snapshots of the vehicle into the outbox, numbered: at a fixed rate, and at once
    when a HEARTBEAT says the motors armed or disarmed. The hub's flight log finds
    flights from arm to disarm in these snapshots; an arming shorter than the period (a
    take-off landed straight away, an arm and a disarm) would otherwise fall between two
    of them and leave no flight at all."""

    def __init__(self, link: FcuLink, outbox: Outbox) -> None:
        self._link = link
        self._outbox = outbox
        self._seq = 0
        self._armed: bool | None = None  # as the last snapshot said
        # Listeners run as each message is handled, before the next one of the batch:
        # the snapshot taken here still holds the heartbeat that changed.
        link.listeners.append(self._on_message)

    def publish(self) -> None:
        state = current_state(self._link, self._outbox)
        body = encode(Telemetry(seq=self._seq, time=time.time(), state=state))
        self._outbox.put("telemetry", self._seq, body)
        self._seq += 1
        self._armed = state.armed

    def _on_message(self, message: MavMessage) -> None:
        if (
            message.get_type() == "HEARTBEAT"
            and message.get_srcComponent() == self._link.target_component  # the autopilot's
            and is_armed(message) != self._armed
        ):
            self.publish()

    async def run(self, rate_hz: float) -> None:
        period = 1.0 / rate_hz
        next_at = time.monotonic()
        while True:
            self.publish()
            next_at += period
            await asyncio.sleep(max(0.0, next_at - time.monotonic()))
