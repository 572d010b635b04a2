"""Keeps the 3D scene in step with the fleet, in batches at a bounded rate.

Vehicle changes arrive on the bus as they happen (50 vehicles at 10 Hz is 500 a second).
The mirror takes them newest-wins per vehicle, and at most once per period applies what
has changed as one atomic scene update: the browser gets a bounded number of updates a
second whatever the fleet's size and rate, and never a stale state before a newer one.
"""

from __future__ import annotations

import asyncio
import logging

from backend.fleet.registry import FleetRegistry
from backend.realtime.bus import Bus, LatestSubscription, Topic
from backend.viz3d.scene import FleetScene

log = logging.getLogger(__name__)


class SceneMirror:
    def __init__(
        self, scene: FleetScene, bus: Bus, registry: FleetRegistry, interval_s: float
    ) -> None:
        self.scene = scene
        self.bus = bus
        self.registry = registry
        self.interval_s = interval_s

    async def run(self) -> None:
        updates = LatestSubscription()
        # Subscribe before reading the registry, so no change falls between the two.
        self.bus.subscribe(Topic.VEHICLE_STATE, updates)
        try:
            # viser's calls serialise and compress; a worker thread keeps that off the
            # hub's event loop. One batch at a time: each waits for the one before.
            known = [record.summary() for record in self.registry.all()]
            await asyncio.to_thread(self.scene.apply, known)
            while True:
                batch = await updates.drain()
                await asyncio.to_thread(self.scene.apply, batch)
                # Pacing, not synchronisation: changes arriving meanwhile coalesce.
                await asyncio.sleep(self.interval_s)
        finally:
            self.bus.unsubscribe(Topic.VEHICLE_STATE, updates)
