"""Vehicle state to every client feed: batched, encoded once, paced per vehicle.

One task per hub takes the vehicles' newest states off the bus and hands each client feed
the same batch, encoded once as one ``vehicles`` frame, however many feeds there are.

Pacing, both leading-edge (a change goes out at once when nothing held it back, so a
quiet fleet's updates are not delayed by a fixed tick):
- a vehicle's state goes out at most once per ``vehicle_interval_s``; a newer one that
  comes sooner waits for the rest of the interval and replaces any it overtook;
- batches go out at most once per ``batch_interval_s``: what changes meanwhile joins the
  next batch, so a feed's frame rate is bounded whatever the fleet's size.

What a vehicle's hello said (autopilot, vehicle type, modes) goes in a batch only when it
changed since the last batch; a feed that has not seen it yet (it connected since) gets a
batch of its own (``FeedSink`` decides, in backend/realtime/client_feed.py).
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from backend.realtime.bus import Bus, LatestSubscription, Topic
from protocol.messages import VehicleBatch, VehicleChange, VehicleSummary, encode

# A vehicle's autopilot, vehicle type and modes: what its hello said.
VehicleInfo = tuple[str, str, tuple[str, ...]]


def vehicle_info(summary: VehicleSummary) -> VehicleInfo:
    return (summary.autopilot, summary.vehicle_type, tuple(summary.modes))


def vehicle_change(summary: VehicleSummary, with_info: bool) -> VehicleChange:
    """The update for ``summary``, with its hello's info only if ``with_info``."""
    # The summary's fields are validated already; this runs per vehicle per batch.
    return VehicleChange.model_construct(
        id=summary.id,
        autopilot=summary.autopilot if with_info else None,
        vehicle_type=summary.vehicle_type if with_info else None,
        modes=list(summary.modes) if with_info else None,
        connected=summary.connected,
        last_seen=summary.last_seen,
        airborne_since=summary.airborne_since,
        state=summary.state,
    )


def encode_batch(changes: list[VehicleChange]) -> str:
    return encode(VehicleBatch.model_construct(type="vehicles", vehicles=changes))


@dataclass(frozen=True)
class Broadcast:
    """One batch: the states in it, which of them carry their info, and the frame."""

    summaries: tuple[VehicleSummary, ...]
    with_info: frozenset[str]
    text: str


class FeedSink(Protocol):
    def deliver(self, broadcast: Broadcast) -> None:
        """Take a batch without waiting (the fanout never waits on a client)."""
        ...


class VehicleFanout:
    def __init__(
        self,
        bus: Bus,
        vehicle_interval_s: float,
        batch_interval_s: float,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._bus = bus
        self._vehicle_interval_s = vehicle_interval_s
        self._batch_interval_s = batch_interval_s
        self._clock = clock
        self._updates = LatestSubscription()
        self._feeds: set[FeedSink] = set()
        # Held back by the per-vehicle interval: the newest state, and when it may go.
        self._held: dict[str, VehicleSummary] = {}
        self._sent_at: dict[str, float] = {}
        self._info: dict[str, VehicleInfo] = {}
        self._last_batch = -math.inf
        self.batches = 0

    def join(self, feed: FeedSink) -> None:
        if not self._feeds:
            # On the bus only while someone listens: no feed, no batches to build.
            self._bus.subscribe(Topic.VEHICLE_STATE, self._updates)
        self._feeds.add(feed)

    def leave(self, feed: FeedSink) -> None:
        self._feeds.discard(feed)
        if not self._feeds:
            self._bus.unsubscribe(Topic.VEHICLE_STATE, self._updates)
            # Off the bus, what is pending only grows stale: a feed that joins later
            # starts from its snapshot, and must not get an older state after it.
            self._updates.take()
            self._held.clear()

    async def run(self) -> None:
        while True:
            await self._wait_for_due()
            wait = self._last_batch + self._batch_interval_s - self._clock()
            if wait > 0:
                # Pacing, not synchronisation: what arrives meanwhile joins this batch.
                await asyncio.sleep(wait)
            self._broadcast()

    async def _wait_for_due(self) -> None:
        """Until a state is due: a new one (unless its vehicle went out too recently), or
        a held one whose interval has passed."""
        while True:
            self._take_new()
            now = self._clock()
            if self._held:
                soonest = min(self._sent_at.get(v, -math.inf) for v in self._held)
                due_in = soonest + self._vehicle_interval_s - now
                if due_in <= 0:
                    return
                with contextlib.suppress(TimeoutError):
                    async with asyncio.timeout(due_in):
                        await self._updates.wait()
            else:
                await self._updates.wait()

    def _take_new(self) -> None:
        for summary in self._updates.take():
            self._held[summary.id] = summary

    def _broadcast(self) -> None:
        self._take_new()
        now = self._clock()
        going: list[VehicleSummary] = []
        for vehicle_id, summary in list(self._held.items()):
            if now - self._sent_at.get(vehicle_id, -math.inf) >= self._vehicle_interval_s:
                going.append(summary)
                del self._held[vehicle_id]
                self._sent_at[vehicle_id] = now
        if not going:
            return
        self._last_batch = now
        with_info = set()
        changes = []
        for summary in going:
            info = vehicle_info(summary)
            changed = self._info.get(summary.id) != info
            if changed:
                self._info[summary.id] = info
                with_info.add(summary.id)
            changes.append(vehicle_change(summary, changed))
        broadcast = Broadcast(tuple(going), frozenset(with_info), encode_batch(changes))
        self.batches += 1
        for feed in list(self._feeds):
            feed.deliver(broadcast)
