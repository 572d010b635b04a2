"""The events a dashboard's live feed carries, and the queue that bounds them per client.

Events are not state: a newer one does not replace an older one, so the newest-wins rule
of vehicle updates does not fit. Each client gets every event in order, through a bounded
queue with this policy:

- A full queue drops the least severe event it holds (the oldest of those), never the
  newest critical one: a debug-text storm cannot push a failsafe out of an operator's view.
- A batch goes out at most every ``GCS_UI_UPDATE_INTERVAL_S``, and identical events within
  it (a STATUSTEXT an autopilot repeats) are sent once with a count.
"""

from __future__ import annotations

import asyncio
from collections import deque
from collections.abc import Hashable
from typing import Any

from backend.storage.records import StoredEvent
from protocol.messages import MAX_LIVE_EVENTS, EventBatch, LiveEvent

# Enough for a burst from a whole fleet between two batches; beyond it, drop by severity.
DEFAULT_QUEUE_EVENTS = 512
# What a dashboard opened now is shown of the time before it (a reload, a second operator):
# the fleet's link-ups and the rest, not an empty log until the next event.
RECENT_EVENTS = 200
# A missing severity ranks below MAV_SEVERITY_DEBUG (7): it goes first.
_NO_SEVERITY_RANK = 8


def live_event(event: StoredEvent) -> LiveEvent:
    return LiveEvent(
        vehicle_id=event.vehicle_id,
        time=event.time,
        kind=event.kind,
        severity=event.severity,
        text=event.text,
        mission_item=event.mission_item,
        photo=event.photo,
    )


def _rank(event: LiveEvent) -> int:
    return _NO_SEVERITY_RANK if event.severity is None else event.severity


class EventSubscription:
    """A bus subscription (``Topic.VEHICLE_EVENT``) for one client."""

    def __init__(self, maxsize: int = DEFAULT_QUEUE_EVENTS) -> None:
        self._maxsize = maxsize
        self._events: list[LiveEvent] = []
        self._ready = asyncio.Event()
        self._dropped = 0

    def offer(self, key: Hashable, message: Any) -> bool:
        assert isinstance(message, LiveEvent)
        self._events.append(message)
        if len(self._events) > self._maxsize:
            # The oldest of the least severe: max() returns the first maximum.
            victim = max(range(len(self._events)), key=lambda i: _rank(self._events[i]))
            del self._events[victim]
            self._dropped += 1
        self._ready.set()
        return True

    async def put(self, key: Hashable, message: Any) -> None:
        self.offer(key, message)

    async def next_batch(self) -> EventBatch:
        """The oldest waiting events, repeats folded, waiting until there is one."""
        await self._ready.wait()
        taken, self._events = self._events[:MAX_LIVE_EVENTS], self._events[MAX_LIVE_EVENTS:]
        if not self._events:
            self._ready.clear()
        dropped, self._dropped = self._dropped, 0
        return EventBatch(events=coalesce(taken), dropped=dropped)


class RecentEvents:
    """The hub's newest live events (``Topic.VEHICLE_EVENT``), which a client feed sends
    first: bounded, the oldest going first."""

    def __init__(self, limit: int = RECENT_EVENTS) -> None:
        self._events: deque[LiveEvent] = deque(maxlen=limit)

    def offer(self, key: Hashable, message: Any) -> bool:
        assert isinstance(message, LiveEvent)
        self._events.append(message)
        return True

    async def put(self, key: Hashable, message: Any) -> None:
        self.offer(key, message)

    def replay_into(self, subscription: EventSubscription) -> None:
        """Queue the recent events for a new client, oldest first (the dashboard folds
        an event it already holds, one that also came live)."""
        for event in list(self._events):
            subscription.offer(event.vehicle_id, event)


def coalesce(events: list[LiveEvent]) -> list[LiveEvent]:
    """One event per (vehicle, kind, severity, text), in the order each first came, with
    the newest time and the count."""
    folded: dict[tuple[str, str, int | None, str], LiveEvent] = {}
    for event in events:
        key = (event.vehicle_id, event.kind, event.severity, event.text)
        if (seen := folded.get(key)) is None:
            folded[key] = event
        else:
            folded[key] = seen.model_copy(
                update={"time": max(seen.time, event.time), "repeat": seen.repeat + event.repeat}
            )
    return list(folded.values())
