"""The realtime bus: topics with a delivery rule per subscription.

Two rules cover the hub's traffic:
- ``ReliableSubscription``: every message, in order, through a bounded queue. A full
  queue makes the publisher wait, so backpressure reaches the agent's socket rather
  than memory growing (stored telemetry).
- ``LatestSubscription``: newest-wins per key. A message replaces the unsent one with
  the same key, so a slow reader sees current state, never a backlog (UI updates,
  and later manual-control input).

``Bus`` is the interface; ``InProcessBus`` implements it for one hub. A NATS-backed
bus for several hubs implements the same three methods.
"""

from __future__ import annotations

import asyncio
from collections.abc import Hashable
from enum import StrEnum
from typing import Any, Protocol


class Topic(StrEnum):
    STORAGE = "storage"  # TelemetryEnvelope and StoredEvent, in order, for the writer
    VEHICLE_STATE = "vehicle.state"  # VehicleSummary, for clients
    VEHICLE_EVENT = "vehicle.event"  # LiveEvent, for clients (backend.realtime.live_events)
    SCANS = "scans"  # ScanDelivery (backend/scans), newest per vehicle, for subscribers
    SURVEYS = "surveys"  # SurveyUpdate, newest per survey, for clients
    MAP = "map"  # PointMapUpdate and ObstaclesUpdate, newest per layer, for subscribers


class Subscription(Protocol):
    def offer(self, key: Hashable, message: Any) -> bool:
        """Take a message without waiting; False if it must wait for room."""
        ...

    async def put(self, key: Hashable, message: Any) -> None: ...


class ReliableSubscription:
    def __init__(self, maxsize: int) -> None:
        self._queue: asyncio.Queue[Any] = asyncio.Queue(maxsize)

    def offer(self, key: Hashable, message: Any) -> bool:
        try:
            self._queue.put_nowait(message)
        except asyncio.QueueFull:
            return False
        return True

    async def put(self, key: Hashable, message: Any) -> None:
        await self._queue.put(message)

    async def get(self) -> Any:
        return await self._queue.get()

    def get_nowait(self) -> Any:
        """Raises asyncio.QueueEmpty when nothing is waiting."""
        return self._queue.get_nowait()

    def qsize(self) -> int:
        return self._queue.qsize()

    @property
    def maxsize(self) -> int:
        return self._queue.maxsize


class LatestSubscription:
    def __init__(self) -> None:
        self._pending: dict[Hashable, Any] = {}
        self._ready = asyncio.Event()
        self.replaced = 0  # messages overtaken before delivery: the coalescing at work

    def offer(self, key: Hashable, message: Any) -> bool:
        if key in self._pending:
            self.replaced += 1
        self._pending[key] = message
        self._ready.set()
        return True

    async def put(self, key: Hashable, message: Any) -> None:
        self.offer(key, message)

    async def wait(self) -> None:
        """Until something is pending (``take`` then takes it)."""
        await self._ready.wait()

    def take(self) -> list[Any]:
        """Everything pending, newest per key, without waiting (perhaps nothing)."""
        self._ready.clear()
        messages = list(self._pending.values())
        self._pending.clear()
        return messages

    async def drain(self) -> list[Any]:
        """Everything pending, newest per key, waiting until there is something."""
        await self._ready.wait()
        self._ready.clear()
        messages = list(self._pending.values())
        self._pending.clear()
        return messages


class Bus(Protocol):
    def subscribe(self, topic: Topic, subscription: Subscription) -> None: ...

    def unsubscribe(self, topic: Topic, subscription: Subscription) -> None: ...

    async def publish(self, topic: Topic, key: Hashable, message: Any) -> None: ...

    def subscribers(self, topic: Topic) -> int:
        """How many take this topic now: a publisher can skip building what nobody reads."""
        ...


class InProcessBus:
    def __init__(self) -> None:
        self._subscriptions: dict[Topic, list[Subscription]] = {topic: [] for topic in Topic}

    def subscribe(self, topic: Topic, subscription: Subscription) -> None:
        self._subscriptions[topic].append(subscription)

    def unsubscribe(self, topic: Topic, subscription: Subscription) -> None:
        self._subscriptions[topic].remove(subscription)

    def subscribers(self, topic: Topic) -> int:
        return len(self._subscriptions[topic])

    async def publish(self, topic: Topic, key: Hashable, message: Any) -> None:
        for subscription in list(self._subscriptions[topic]):
            # The fast path avoids a coroutine per subscriber when there is room.
            if not subscription.offer(key, message):
                await subscription.put(key, message)
