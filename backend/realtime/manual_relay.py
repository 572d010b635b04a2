"""Manual input from a lease holder's feed to the vehicle's agent, newest wins.

A stalled agent link must never queue stale stick positions behind fresh ones: each
vehicle has one slot, a new frame replaces an unsent one, and one task sends.
"""

from __future__ import annotations

import asyncio
import logging

from starlette.websockets import WebSocketDisconnect

from backend.fleet.registry import FleetRegistry
from protocol.messages import ManualFrame

log = logging.getLogger(__name__)


class ManualRelay:
    def __init__(self, registry: FleetRegistry) -> None:
        self._registry = registry
        self._slots: dict[str, ManualFrame] = {}
        self._ready = asyncio.Event()
        self.collapsed = 0  # frames replaced before they were sent

    def put(self, vehicle_id: str, frame: ManualFrame) -> None:
        if vehicle_id in self._slots:
            self.collapsed += 1
        self._slots[vehicle_id] = frame
        self._ready.set()

    async def run(self) -> None:
        while True:
            await self._ready.wait()
            self._ready.clear()
            slots, self._slots = self._slots, {}
            for vehicle_id, frame in slots.items():
                channel = self._registry.get(vehicle_id).channel
                if channel is None:
                    continue  # offline: the agent's deadman holds the vehicle
                try:
                    await channel.send_frame(frame)
                except (RuntimeError, OSError, WebSocketDisconnect) as error:
                    log.info("manual input to %s not sent: %s", vehicle_id, error)
