"""The per-client event queue of the live feed: bounded, least severe dropped first,
repeats folded."""

from __future__ import annotations

import asyncio

from backend.realtime.bus import InProcessBus, Topic
from backend.realtime.live_events import EventSubscription
from protocol.messages import MAX_LIVE_EVENTS, LiveEvent


def _event(text: str, severity: int | None, at: float = 1.0, vehicle: str = "v1") -> LiveEvent:
    return LiveEvent(vehicle_id=vehicle, time=at, kind="statustext", severity=severity, text=text)


def test_a_full_queue_drops_the_least_severe_and_keeps_a_critical_one() -> None:
    async def scenario() -> list[LiveEvent]:
        bus = InProcessBus()
        queue = EventSubscription(maxsize=10)
        bus.subscribe(Topic.VEHICLE_EVENT, queue)
        await bus.publish(Topic.VEHICLE_EVENT, "v1", _event("PreArm: Need Position Estimate", 2))
        for n in range(100):
            await bus.publish(Topic.VEHICLE_EVENT, "v1", _event(f"debug {n}", 7))
        batch = await queue.next_batch()
        assert batch.dropped == 91
        return batch.events

    events = asyncio.run(scenario())
    assert events[0].text == "PreArm: Need Position Estimate"
    # the newest debug texts are kept: the oldest of the least severe went first
    assert [e.text for e in events[1:]] == [f"debug {n}" for n in range(91, 100)]


def test_repeats_fold_into_one_event_with_a_count_and_batches_fit_a_frame() -> None:
    async def scenario() -> tuple[list[LiveEvent], int]:
        queue = EventSubscription()
        for n in range(5):
            queue.offer("v1", _event("Battery 1 is low", 2, at=10.0 + n))
        queue.offer("v2", _event("Battery 1 is low", 2, at=11.0, vehicle="v2"))
        first = await queue.next_batch()
        for n in range(MAX_LIVE_EVENTS + 3):
            queue.offer("v1", _event(f"text {n}", 6))
        full = await queue.next_batch()
        rest = await queue.next_batch()
        assert len(full.events) == MAX_LIVE_EVENTS
        return first.events, len(rest.events)

    events, rest = asyncio.run(scenario())
    assert [(e.vehicle_id, e.repeat, e.time) for e in events] == [("v1", 5, 14.0), ("v2", 1, 11.0)]
    assert rest == 3
