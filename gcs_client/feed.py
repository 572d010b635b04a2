"""The live feed (WebSocket ``/api/v1/ws``, docs/websockets.md) as an async iterator that
reconnects, and a view of the fleet kept up to date from it.

What "resume" can mean here is what the hub offers. The feed has no cursor to resume
from: a vehicle's state is not a stream of deltas but its newest snapshot, and every new
connection starts with the whole fleet (``fleet``), so after a reconnect the client
yields that snapshot and is current again. Events are a stream: those the vehicles sent
while the client was away are in the flight log (``GET /api/v1/events``), and the client
yields them, oldest first, as one ``events`` batch before the new connection's own.
"""

from __future__ import annotations

import asyncio
import contextlib
import random
import time
from collections.abc import AsyncGenerator, AsyncIterator, Callable
from typing import TYPE_CHECKING

import websockets
from websockets.asyncio.client import ClientConnection
from websockets.exceptions import ConnectionClosed, InvalidHandshake

from gcs_client.errors import FeedClosed, HubError, HubUnreachable, WaitTimedOut
from gcs_client.models import (
    FEEDMESSAGE_ADAPTER,
    ClientMessage,
    EventBatch,
    FeedMessage,
    FleetSnapshot,
    LiveEvent,
    VehicleBatch,
    VehicleChange,
    VehicleState,
    VehicleSummary,
)

if TYPE_CHECKING:
    from gcs_client.hub import Hub

# Close codes after which connecting again cannot help (docs/websockets.md, "Close
# codes"): 4401 is retried once after logging in again, when the client can.
FINAL_CLOSE_CODES = frozenset({1008, 1009, 4401, 4403})
# Waits between attempts to reconnect: full jitter, doubling from the first to the cap.
FIRST_WAIT_S = 0.25
MAX_WAIT_S = 10.0
# Events fetched from the flight log after a reconnect, at most (the newest).
RESUME_EVENTS = 1000


def feed_url(hub_url: str) -> str:
    """The live feed's address: the hub's, with ws:// for http:// (wss:// for https://)."""
    return "ws" + hub_url.removeprefix("http") + "/api/v1/ws"


class LiveFeed:
    """``async for message in hub.feed():`` every message the hub sends, typed, across
    reconnects. ``connections`` counts the connections made so far."""

    def __init__(self, hub: Hub, *, reconnect: bool, resume_events: bool) -> None:
        self._hub = hub
        self._reconnect = reconnect
        self._resume_events = resume_events
        self._socket: ClientConnection | None = None
        self._last_event_time: float | None = None
        self._iterator: AsyncGenerator[FeedMessage, None] | None = None
        self.connections = 0
        hub.keep_open(self)

    def __aiter__(self) -> AsyncIterator[FeedMessage]:
        if self._iterator is None:
            self._iterator = self._messages()
        return self._iterator

    async def __aenter__(self) -> LiveFeed:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.aclose()

    async def aclose(self) -> None:
        """Close the connection now (the Hub's exit does it for every feed it made):
        leaving an ``async for`` early leaves the socket open until garbage collection."""
        if self._iterator is not None:
            iterator, self._iterator = self._iterator, None
            await iterator.aclose()

    async def send(self, message: ClientMessage) -> None:
        """Send a message to the hub (a ``Ping``, a ``ControlRequest`` ...) on the
        connection open now."""
        if self._socket is None:
            raise HubError("the live feed is not connected")
        await self._socket.send(message.model_dump_json(by_alias=True))

    async def _messages(self) -> AsyncGenerator[FeedMessage, None]:
        wait_s = FIRST_WAIT_S
        while True:
            token = await self._hub.token()
            try:
                async with websockets.connect(
                    self._hub.feed_url,
                    additional_headers={"Authorization": f"Bearer {token}"},
                    open_timeout=self._hub_timeout(),
                ) as socket:
                    self._socket = socket
                    self.connections += 1
                    resuming = self.connections > 1 and self._resume_events
                    async for frame in socket:
                        if isinstance(frame, bytes):
                            continue  # LIDAR scans: only sent after subscribe_scans
                        message = FEEDMESSAGE_ADAPTER.validate_json(frame)
                        wait_s = FIRST_WAIT_S  # the hub answered: start the waits over
                        if isinstance(message, EventBatch) and message.events:
                            self._last_event_time = max(e.time for e in message.events)
                        yield message
                        if resuming and isinstance(message, FleetSnapshot):
                            resuming = False
                            if missed := await self._missed_events():
                                yield missed
                # The hub closed normally (it is stopping): connect again below.
                if not self._reconnect:
                    return
            except ConnectionClosed as closed:
                code = closed.rcvd.code if closed.rcvd is not None else 1006
                reason = closed.rcvd.reason if closed.rcvd is not None else "connection lost"
                renewed = code == 4401 and await self._hub.renew_after_refusal(token)
                # The token expired or was revoked: logged in again, connect again (after
                # the same short wait, so that a hub that keeps refusing is not hammered).
                if not renewed and (code in FINAL_CLOSE_CODES or not self._reconnect):
                    raise FeedClosed(code, reason) from None
            except (OSError, InvalidHandshake, TimeoutError) as error:
                if not self._reconnect:
                    cause = str(error) or type(error).__name__
                    where = self._hub.feed_url
                    raise HubUnreachable(f"cannot open the live feed at {where}: {cause}") from None
            finally:
                self._socket = None
            await asyncio.sleep(random.uniform(0, wait_s))
            wait_s = min(wait_s * 2, MAX_WAIT_S)

    def _hub_timeout(self) -> float:
        return float(self._hub.http.timeout.connect or 30.0)

    async def _missed_events(self) -> EventBatch | None:
        """The events the flight log stored after the last one this feed yielded."""
        since = self._last_event_time
        if since is None:
            return None
        try:
            page = await self._hub.events.page(start=since, limit=RESUME_EVENTS)
        except HubError:
            # The link dropped again, or the log is unavailable: the feed goes on without
            # this batch (the events stay in the flight log, GET /api/v1/events).
            return None
        missed = [
            LiveEvent(
                vehicle_id=record.vehicle_id,
                time=record.time,
                kind=record.kind,
                severity=record.severity,
                text=record.text,
                mission_item=record.mission_item,
            )
            for record in reversed(page.events)  # the log pages newest first
            if record.time > since
        ]
        if not missed:
            return None
        self._last_event_time = missed[-1].time
        return EventBatch(events=missed)


def merged(known: VehicleSummary | None, change: VehicleChange | VehicleSummary) -> VehicleSummary:
    """A vehicle's summary after an update, which leaves out what it sent before."""
    given = change.model_dump(include=change.model_fields_set)
    if known is None:
        base = {"autopilot": "", "vehicle_type": "", "modes": []}
        return VehicleSummary.model_validate({**base, **given})
    return known.model_copy(update={key: getattr(change, key) for key in given})


class FleetWatch:
    """The fleet as the live feed shows it, kept current by a task of its own.

    ``async with hub.watch() as fleet:`` waits for the first snapshot; then
    ``fleet.vehicles`` holds every vehicle's newest summary, ``fleet.state(id)`` its
    latest telemetry, and ``await fleet.wait_until(...)`` follows the feed until a
    condition holds."""

    def __init__(self, hub: Hub, feed: LiveFeed) -> None:
        self.feed = feed
        # The watch closes its feed: the Hub closes the watch (its task iterates the feed,
        # which cannot be closed from outside while it runs).
        hub.release(feed)
        hub.keep_open(self)
        self.vehicles: dict[str, VehicleSummary] = {}
        self._changed = asyncio.Condition()
        self._task: asyncio.Task[None] | None = None
        self._failure: BaseException | None = None
        self._snapshot = False
        self._subscribers: list[asyncio.Queue[VehicleSummary | BaseException]] = []

    async def __aenter__(self) -> FleetWatch:
        self._task = asyncio.create_task(self._follow())
        try:
            await self.wait_until(lambda: self._snapshot, 60, "the fleet")
        except BaseException:
            await self.aclose()
            raise
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.aclose()

    async def aclose(self) -> None:
        """Stop following the feed, and close it."""
        if self._task is not None:
            task, self._task = self._task, None
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
        await self.feed.aclose()

    def state(self, vehicle_id: str) -> VehicleState:
        """The vehicle's latest telemetry (all defaults before its first)."""
        vehicle = self.vehicles.get(vehicle_id)
        return vehicle.state if vehicle is not None and vehicle.state else VehicleState()

    async def wait_until(self, done: Callable[[], object], timeout_s: float, what: str) -> None:
        """Return once ``done()`` holds; raise ``WaitTimedOut`` after ``timeout_s``, or the
        feed's own error (``FeedClosed``) if it ends first."""
        deadline = time.monotonic() + timeout_s
        async with self._changed:
            while not done():
                if self._failure is not None:
                    raise self._failure
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise WaitTimedOut(f"gave up after {timeout_s:.0f} s waiting for {what}")
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(self._changed.wait(), remaining)

    async def updates(self) -> AsyncIterator[VehicleSummary]:
        """Every vehicle now, then each one as it changes."""
        queue: asyncio.Queue[VehicleSummary | BaseException] = asyncio.Queue()
        for vehicle in self.vehicles.values():
            queue.put_nowait(vehicle)
        if self._failure is not None:
            queue.put_nowait(self._failure)
        self._subscribers.append(queue)
        try:
            while True:
                item = await queue.get()
                if isinstance(item, BaseException):
                    raise item
                yield item
        finally:
            self._subscribers.remove(queue)

    async def _follow(self) -> None:
        try:
            async for message in self.feed:
                changed: list[VehicleSummary] = []
                if isinstance(message, FleetSnapshot):
                    self.vehicles = {vehicle.id: vehicle for vehicle in message.vehicles}
                    changed = list(message.vehicles)
                    self._snapshot = True
                elif isinstance(message, VehicleBatch):
                    for change in message.vehicles:
                        vehicle = merged(self.vehicles.get(change.id), change)
                        self.vehicles[change.id] = vehicle
                        changed.append(vehicle)
                for queue in self._subscribers:
                    for vehicle in changed:
                        queue.put_nowait(vehicle)
                async with self._changed:
                    self._changed.notify_all()
        except Exception as error:  # handed to whoever waits: the caller's to handle
            self._failure = error
            for queue in self._subscribers:
                queue.put_nowait(error)
            async with self._changed:
                self._changed.notify_all()
