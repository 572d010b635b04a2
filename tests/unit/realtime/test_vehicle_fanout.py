"""The vehicle fanout: one encoded batch for every feed, paced per vehicle (newest wins),
a vehicle's hello info only when it changed, and nothing stale after the last feed left."""

from __future__ import annotations

import asyncio
import contextlib
import json
from collections.abc import AsyncIterator
from typing import Any

from backend.realtime.bus import InProcessBus, Topic
from backend.realtime.vehicle_fanout import Broadcast, VehicleFanout
from protocol.messages import VehicleState, VehicleSummary


class Sink:
    def __init__(self) -> None:
        self.batches: asyncio.Queue[Broadcast] = asyncio.Queue()

    def deliver(self, broadcast: Broadcast) -> None:
        self.batches.put_nowait(broadcast)

    async def next(self) -> list[dict[str, Any]]:
        broadcast = await asyncio.wait_for(self.batches.get(), 5)
        vehicles: list[dict[str, Any]] = json.loads(broadcast.text)["vehicles"]
        return vehicles


def summary(vehicle_id: str, alt: float, modes: tuple[str, ...] = ("GUIDED",)) -> VehicleSummary:
    return VehicleSummary(
        id=vehicle_id,
        autopilot="ardupilot",
        vehicle_type="multirotor",
        modes=list(modes),
        connected=True,
        last_seen=alt,
        state=VehicleState(alt_rel=alt),
    )


@contextlib.asynccontextmanager
async def running(fanout: VehicleFanout) -> AsyncIterator[None]:
    task = asyncio.create_task(fanout.run())
    try:
        yield
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


def test_every_feed_gets_the_same_batch_with_the_newest_state_per_vehicle() -> None:
    async def scenario() -> None:
        bus = InProcessBus()
        # A long per-vehicle interval: the states that follow the first must wait, and fold.
        fanout = VehicleFanout(bus, vehicle_interval_s=0.3, batch_interval_s=0.001)
        first, second = Sink(), Sink()
        fanout.join(first)
        fanout.join(second)
        async with running(fanout):
            await bus.publish(Topic.VEHICLE_STATE, "v1", summary("v1", 1.0))
            batch = await first.next()
            # At once (leading edge), with the hello's info the first time.
            assert [(v["id"], v["state"]["alt_rel"], v["modes"]) for v in batch] == [
                ("v1", 1.0, ["GUIDED"])
            ]
            for alt in (2.0, 3.0, 4.0):
                await bus.publish(Topic.VEHICLE_STATE, "v1", summary("v1", alt))
            await bus.publish(Topic.VEHICLE_STATE, "v2", summary("v2", 9.0))
            # v2 is not held back by v1's interval.
            assert [v["id"] for v in await first.next()] == ["v2"]
            # v1's next state is its newest, once, without the info it already gave.
            [v1] = await first.next()
            assert (v1["id"], v1["state"]["alt_rel"]) == ("v1", 4.0)
            assert "modes" not in v1
            # The other feed got the very same frames.
            for _ in range(3):
                assert (await second.next()) is not None
            assert first.batches.empty()
            assert second.batches.empty()
            # New modes (the agent reconnected with another hello) go out again.
            await bus.publish(Topic.VEHICLE_STATE, "v2", summary("v2", 9.5, ("AUTO",)))
            [v2] = await first.next()
            assert v2["modes"] == ["AUTO"]

    asyncio.run(scenario())


def test_a_feed_joining_after_the_last_one_left_gets_no_stale_state() -> None:
    async def scenario() -> None:
        bus = InProcessBus()
        fanout = VehicleFanout(bus, vehicle_interval_s=0.001, batch_interval_s=0.001)
        early = Sink()
        fanout.join(early)
        async with running(fanout):
            await bus.publish(Topic.VEHICLE_STATE, "v1", summary("v1", 1.0))
            await early.next()
            # Published, not yet taken, when the last feed leaves: stale from then on.
            await bus.publish(Topic.VEHICLE_STATE, "v1", summary("v1", 2.0))
            fanout.leave(early)
            assert bus.subscribers(Topic.VEHICLE_STATE) == 0
            late = Sink()
            fanout.join(late)
            await bus.publish(Topic.VEHICLE_STATE, "v2", summary("v2", 5.0))
            # Only what was published since it joined (its snapshot has v1 as it is now).
            assert [v["id"] for v in await late.next()] == ["v2"]

    asyncio.run(scenario())
