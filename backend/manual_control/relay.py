"""Manual input from a lease holder's feed to the vehicle's agent, newest wins.

A stalled agent link must never queue stale stick positions behind fresh ones: each
vehicle has one slot, a new frame replaces an unsent one, and one task sends. The same
slot caps the rate: at most one frame per ``1 / max_rate_hz`` goes to a vehicle, so a
client flooding faster than 100 Hz, or a stalled client's burst arriving at once,
collapses to its newest frame; every frame replaced unsent is counted and never flown.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable

from starlette.websockets import WebSocketDisconnect

from backend.fleet.registry import FleetRegistry
from protocol.messages import ManualFrame

log = logging.getLogger(__name__)


class ManualRelay:
    def __init__(
        self,
        registry: FleetRegistry,
        max_rate_hz: float = 100.0,
        on_collapse: Callable[[], None] | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._registry = registry
        self._min_interval_s = 1.0 / max_rate_hz
        self._on_collapse = on_collapse
        self._clock = clock
        self._slots: dict[str, ManualFrame] = {}
        self._sent_at: dict[str, float] = {}
        self._ready = asyncio.Event()
        self.collapsed = 0  # frames replaced before they were sent
        self.forwarded = 0

    def put(self, vehicle_id: str, frame: ManualFrame) -> None:
        if vehicle_id in self._slots:
            self.collapsed += 1
            if self._on_collapse is not None:
                self._on_collapse()
        self._slots[vehicle_id] = frame
        self._ready.set()

    async def run(self) -> None:
        wait_s: float | None = None
        while True:
            if wait_s is None:
                await self._ready.wait()
            else:  # a frame waits out the rate cap; a newer one may replace it meanwhile
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(self._ready.wait(), wait_s)
            self._ready.clear()
            wait_s = await self._send_due()

    async def _send_due(self) -> float | None:
        """Send every slot whose vehicle may have a frame now; how long until the next."""
        now = self._clock()
        soonest: float | None = None
        for vehicle_id in list(self._slots):
            due = self._sent_at.get(vehicle_id, -1e9) + self._min_interval_s
            if due > now:
                soonest = due - now if soonest is None else min(soonest, due - now)
                continue
            frame = self._slots.pop(vehicle_id)
            self._sent_at[vehicle_id] = now
            channel = self._registry.get(vehicle_id).channel
            if channel is None:
                continue  # offline: the agent's deadman holds the vehicle
            try:
                await channel.send_frame(frame)
                self.forwarded += 1
            except (RuntimeError, OSError, WebSocketDisconnect) as error:
                log.info("manual input to %s not sent: %s", vehicle_id, error)
        return soonest
