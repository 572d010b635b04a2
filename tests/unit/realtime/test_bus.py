from __future__ import annotations

import asyncio

from backend.realtime.bus import InProcessBus, LatestSubscription, ReliableSubscription, Topic


def test_reliable_subscription_applies_backpressure_and_keeps_order() -> None:
    async def scenario() -> None:
        bus = InProcessBus()
        queue = ReliableSubscription(maxsize=2)
        bus.subscribe(Topic.STORAGE, queue)
        await bus.publish(Topic.STORAGE, "v", 1)
        await bus.publish(Topic.STORAGE, "v", 2)
        blocked = asyncio.create_task(bus.publish(Topic.STORAGE, "v", 3))
        await asyncio.sleep(0)  # let the publisher run until it blocks
        assert not blocked.done(), "a full reliable queue makes the publisher wait"
        assert await queue.get() == 1
        await asyncio.wait_for(blocked, 1)
        assert [await queue.get(), await queue.get()] == [2, 3]

    asyncio.run(scenario())


def test_latest_subscription_keeps_newest_per_key() -> None:
    async def scenario() -> None:
        bus = InProcessBus()
        latest = LatestSubscription()
        bus.subscribe(Topic.VEHICLE_STATE, latest)
        for value in range(5):
            await bus.publish(Topic.VEHICLE_STATE, "a", ("a", value))
        await bus.publish(Topic.VEHICLE_STATE, "b", ("b", 0))
        assert sorted(await latest.drain()) == [("a", 4), ("b", 0)]
        assert latest.replaced == 4
        bus.unsubscribe(Topic.VEHICLE_STATE, latest)
        await bus.publish(Topic.VEHICLE_STATE, "a", ("a", 9))
        assert not latest._ready.is_set()

    asyncio.run(scenario())
