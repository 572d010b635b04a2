"""A dashboard or integration's live feed: the fleet, then coalesced per-vehicle updates."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time

from starlette.requests import HTTPConnection
from starlette.websockets import WebSocket, WebSocketDisconnect

from backend.auth.credentials import presented_principal, presented_token
from backend.auth.policy import (
    CLIENT_MESSAGE_PERMISSIONS,
    Permission,
    authorize,
    authorize_message,
)
from backend.errors import Forbidden
from backend.manual_control.pilot import PilotChannel
from backend.observability import metrics
from backend.observability.metrics import Surface
from backend.realtime.bus import LatestSubscription, Topic
from backend.realtime.collaborators import FeedServices
from backend.realtime.frames import FrameTooLarge, PeerConnection
from backend.realtime.live_events import EventSubscription
from backend.realtime.vehicle_fanout import (
    Broadcast,
    VehicleInfo,
    encode_batch,
    vehicle_change,
    vehicle_info,
)
from protocol.messages import (
    MAX_SCAN_SUBSCRIPTIONS,
    CloseCode,
    ControlRequest,
    ErrorReply,
    FleetSnapshot,
    ManualInput,
    MapLayer,
    MapSubscriptions,
    Ping,
    PointMapUpdate,
    Pong,
    ProtocolError,
    ScanSubscriptions,
    SubscribeMap,
    SubscribeScans,
    UnsubscribeMap,
    UnsubscribeScans,
    VehicleSummary,
    client_to_hub,
)

log = logging.getLogger(__name__)


def origin_allowed(connection: HTTPConnection, allowed_origins: list[str]) -> bool:
    """Browsers send Origin on WebSockets and CORS does not cover them, so check here:
    the page's own origin and the configured ones may connect; non-browser clients
    (agents, scripts) send no Origin and authenticate with tokens instead."""
    origin = connection.headers.get("origin")
    if origin is None:
        return True
    if origin in allowed_origins:
        return True
    # The page's own origin is scheme and host: an http:// page (a MITM on the field LAN
    # can serve one) must not open the socket of a hub served over https://, nor the reverse.
    secure = connection.url.scheme in ("https", "wss")
    own = f"{'https' if secure else 'http'}://{connection.headers.get('host', '')}"
    return origin.lower() == own.lower()


class SlowClient(Exception):
    """A feed that took no vehicle update for longer than the hub waits."""


class VehicleFeed:
    """One feed's side of the fanout (backend/realtime/vehicle_fanout.py), with the policy
    for a client that reads slowly: while a frame is on its way, one more batch waits as
    it is; past that, batches fold into the newest state per vehicle (counted as
    coalesced). So a feed holds at most one encoded batch and one state per vehicle,
    however far behind it is; its sender closes it once one frame takes longer than the
    hub waits (``GCS_SLOW_CLIENT_TIMEOUT_S``)."""

    def __init__(self, sent: dict[str, VehicleInfo]) -> None:
        # What this feed has sent of each vehicle's hello (its snapshot, then updates).
        self._sent = sent
        self._shared: Broadcast | None = None
        self._pending: dict[str, VehicleSummary] = {}
        self._ready = asyncio.Event()

    @property
    def pending(self) -> int:
        shared = len(self._shared.summaries) if self._shared is not None else 0
        return shared + len(self._pending)

    def deliver(self, broadcast: Broadcast) -> None:
        if self._shared is None and not self._pending:
            self._shared = broadcast
        else:
            if self._shared is not None:
                self._fold(self._shared.summaries)
                self._shared = None
            self._fold(broadcast.summaries)
        self._ready.set()

    def _fold(self, summaries: tuple[VehicleSummary, ...]) -> None:
        replaced = 0
        for summary in summaries:
            replaced += summary.id in self._pending
            self._pending[summary.id] = summary
        if replaced:
            metrics.DROPPED.labels(reason="coalesced").inc(replaced)

    async def next_frame(self) -> str:
        """The next ``vehicles`` frame for this feed: the shared one when this feed has
        seen what it leaves out, else one of its own."""
        await self._ready.wait()
        self._ready.clear()
        if (shared := self._shared) is not None:
            self._shared = None
            if all(
                summary.id in shared.with_info
                or self._sent.get(summary.id) == vehicle_info(summary)
                for summary in shared.summaries
            ):
                for summary in shared.summaries:
                    if summary.id in shared.with_info:
                        self._sent[summary.id] = vehicle_info(summary)
                return shared.text
            return self._own(shared.summaries)
        summaries, self._pending = tuple(self._pending.values()), {}
        return self._own(summaries)

    def _own(self, summaries: tuple[VehicleSummary, ...]) -> str:
        changes = []
        for summary in summaries:
            info = vehicle_info(summary)
            changed = self._sent.get(summary.id) != info
            self._sent[summary.id] = info
            changes.append(vehicle_change(summary, changed))
        return encode_batch(changes)


class ClientFeed(PeerConnection):
    surface: Surface = "client_ws"

    def __init__(self, websocket: WebSocket, hub: FeedServices) -> None:
        super().__init__(websocket, hub.settings.max_frame_bytes, hub.settings.max_bad_frames)
        self.hub = hub
        self.user = ""
        self.token_id: int | None = None
        # Its manual-control messages: the lease and the sticks (backend/manual_control/).
        self._pilot = PilotChannel(hub, self.send, self.peer)
        self.scans = hub.scan_subscription()
        self.map = LatestSubscription()  # newest per layer, never a queue
        self.map_layers: set[MapLayer] = set()
        self.vehicles = VehicleFeed({})

    async def serve(self) -> None:
        await self.websocket.accept()
        if not origin_allowed(self.websocket, self.hub.settings.cors_origins):
            origin = self.websocket.headers.get("origin")
            log.warning("refused client from %s: origin %s not allowed", self.peer, origin)
            await self.close(CloseCode.FORBIDDEN, f"origin {origin} is not allowed")
            return
        principal = await presented_principal(self.websocket, self.hub.accounts)
        if principal is None:
            # The reason says how to get in: a script reads it, and a close reason has at
            # most 123 bytes, so the details are in docs/websockets.md.
            reason = (
                "not authenticated: send 'Authorization: Bearer <token>' or the dashboard's "
                "session cookie (docs/websockets.md)"
                if presented_token(self.websocket) is None
                else "the token is invalid, expired or revoked: log in again"
            )
            await self.close(CloseCode.UNAUTHORIZED, reason)
            return
        try:
            authorize(principal, Permission.READ)
        except Forbidden as refusal:
            await self.close(CloseCode.FORBIDDEN, refusal.message)
            return
        self.principal = principal
        self.user = principal.name
        self.token_id = principal.token_id
        self.hub.client_feeds.add(self)
        metrics.CONNECTIONS.labels(kind="dashboard").inc()
        sent: dict[str, VehicleInfo] = {}
        self.vehicles = VehicleFeed(sent)
        events = EventSubscription()
        surveys = LatestSubscription()
        # Joined before the snapshot, so no change falls between the two.
        self.hub.fanout.join(self.vehicles)
        self.hub.bus.subscribe(Topic.VEHICLE_EVENT, events)
        self.hub.recent_events.replay_into(events)
        self.hub.bus.subscribe(Topic.SURVEYS, surveys)
        try:
            fleet = [record.summary() for record in self.hub.registry.all()]
            await self.send(FleetSnapshot(vehicles=fleet))
            # Who flies what by hand, and how the last leases ended (a hub restart's
            # revocations among them).
            for state in list(self.hub.manual_control.leases.last_states.values()):
                await self.send(state)
            sent.update({summary.id: vehicle_info(summary) for summary in fleet})
            async with asyncio.TaskGroup() as tasks:
                pusher = tasks.create_task(self._push(self.vehicles))
                event_pusher = tasks.create_task(self._push_events(events))
                scan_pusher = tasks.create_task(self._push_scans())
                survey_pusher = tasks.create_task(self._push_surveys(surveys))
                map_pusher = tasks.create_task(self._push_map())
                relay = tasks.create_task(self._pilot.relay.run())
                expiry = tasks.create_task(
                    self._end_at_expiry(
                        principal.expires_at,
                        pusher,
                        event_pusher,
                        scan_pusher,
                        survey_pusher,
                        map_pusher,
                    )
                )
                await self._listen()
                pusher.cancel()
                survey_pusher.cancel()
                event_pusher.cancel()
                scan_pusher.cancel()
                map_pusher.cancel()
                relay.cancel()
                expiry.cancel()
        except* FrameTooLarge as group:
            log.warning("closing client %s: %s", self.peer, group.exceptions[0])
            with contextlib.suppress(WebSocketDisconnect):
                await self.close(CloseCode.MESSAGE_TOO_BIG, str(group.exceptions[0]))
        except* SlowClient:
            metrics.DROPPED.labels(reason="slow_client").inc()
            wait_s = self.hub.settings.slow_client_timeout_s
            log.warning("closing client %s: it read nothing for %.0f s", self.peer, wait_s)
            # Its socket may take nothing more, not even the close frame: do not wait long.
            with contextlib.suppress(Exception):
                async with asyncio.timeout(1.0):
                    await self.close(CloseCode.TOO_SLOW, f"too slow: read nothing for {wait_s:g} s")
        except* WebSocketDisconnect:
            pass
        finally:
            self.hub.fanout.leave(self.vehicles)
            self.hub.bus.unsubscribe(Topic.VEHICLE_EVENT, events)
            self.hub.bus.unsubscribe(Topic.SURVEYS, surveys)
            if self.scans.vehicles:
                self.hub.bus.unsubscribe(Topic.SCANS, self.scans)
            if self.map_layers:
                self.hub.bus.unsubscribe(Topic.MAP, self.map)
            self.hub.client_feeds.discard(self)
            metrics.CONNECTIONS.labels(kind="dashboard").dec()

    async def _end_at_expiry(self, expires_at: float | None, *pushers: asyncio.Task[None]) -> None:
        """A token's lifetime bounds the feed it opened, as a revocation does."""
        if expires_at is None:
            return
        await asyncio.sleep(max(0.0, expires_at - time.time()))
        for pusher in pushers:
            pusher.cancel()  # nothing more goes out on an expired token
        log.info("closing client %s: the token of %s expired", self.peer, self.user)
        await self.close(CloseCode.UNAUTHORIZED, "token expired: log in again")

    @property
    def pending(self) -> int:
        """Vehicle updates waiting for this client (the metrics' queue depth)."""
        return self.vehicles.pending

    async def _push(self, vehicles: VehicleFeed) -> None:
        limit_s = self.hub.settings.slow_client_timeout_s
        while True:
            frame = await vehicles.next_frame()
            try:
                async with asyncio.timeout(limit_s):
                    await self.send_text(frame)
            except TimeoutError:
                raise SlowClient from None

    async def _push_events(self, events: EventSubscription) -> None:
        interval = self.hub.settings.ui_update_interval_s
        while True:
            await self.send(await events.next_batch())
            # Pacing: events arriving meanwhile go out together in the next batch.
            await asyncio.sleep(interval)

    async def _push_surveys(self, surveys: LatestSubscription) -> None:
        """Survey progress, newest per survey: the survey service paces it already."""
        while True:
            for update in await surveys.drain():
                await self.send(update)

    async def _push_scans(self) -> None:
        """The newest scan of each subscribed vehicle. A client that stops reading stalls
        this send; meanwhile newer scans replace the unsent one, so the hub holds at most
        one scan per subscribed vehicle for it, never a queue."""
        while True:
            for delivery in await self.scans.drain():
                await self.send_bytes(delivery.data)

    async def _scan_subscription(self, message: SubscribeScans | UnsubscribeScans) -> None:
        had_any = bool(self.scans.vehicles)
        if isinstance(message, SubscribeScans):
            if len(self.scans.vehicles) >= MAX_SCAN_SUBSCRIPTIONS:
                await self.reject(
                    ErrorReply(
                        code="invalid_message",
                        message=f"vehicle_id: at most {MAX_SCAN_SUBSCRIPTIONS} scan "
                        "subscriptions per feed",
                    )
                )
                return
            self.scans.vehicles.add(message.vehicle_id)
        else:
            self.scans.vehicles.discard(message.vehicle_id)
        # On the bus only while it wants something: nobody pays for scans they did not ask for.
        if self.scans.vehicles and not had_any:
            self.hub.bus.subscribe(Topic.SCANS, self.scans)
        elif had_any and not self.scans.vehicles:
            self.hub.bus.unsubscribe(Topic.SCANS, self.scans)
        await self.send(ScanSubscriptions(vehicles=sorted(self.scans.vehicles)))

    async def _push_map(self) -> None:
        """The map layers this feed asked for, newest only: a reader that stalls holds at
        most one point map and one obstacle list, never a queue."""
        while True:
            for update in await self.map.drain():
                layer = "points" if isinstance(update, PointMapUpdate) else "obstacles"
                if layer in self.map_layers:
                    await self.send(update)

    async def _map_subscription(self, message: SubscribeMap | UnsubscribeMap) -> None:
        had_any = bool(self.map_layers)
        asked = set(message.layers)
        added = asked - self.map_layers if isinstance(message, SubscribeMap) else set()
        if isinstance(message, SubscribeMap):
            self.map_layers |= asked
        else:
            self.map_layers -= asked
        if self.map_layers and not had_any:
            self.hub.bus.subscribe(Topic.MAP, self.map)
        elif had_any and not self.map_layers:
            self.hub.bus.unsubscribe(Topic.MAP, self.map)
        await self.send(MapSubscriptions(layers=sorted(self.map_layers)))
        # What a new layer holds now, so the client need not wait for its next change.
        for update in await self.hub.map_now(added):
            self.map.offer(update.type, update)

    async def _listen(self) -> None:
        while (frame := await self.receive()) is not None:
            try:
                message = client_to_hub.decode(frame)
            except ProtocolError as error:
                await self.reject(error.reply())
                continue
            try:
                authorize_message(self.principal, message.type, CLIENT_MESSAGE_PERMISSIONS)
            except Forbidden as refusal:
                await self.reject(ErrorReply(code="forbidden", message=refusal.message))
                continue
            if isinstance(message, Ping):
                await self.send(Pong(nonce=message.nonce))
            elif isinstance(message, ManualInput):
                await self._pilot.input(message, self.user)
            elif isinstance(message, ControlRequest):
                await self._pilot.control(message, self.principal)
            elif isinstance(message, SubscribeScans | UnsubscribeScans):
                await self._scan_subscription(message)
            elif isinstance(message, SubscribeMap | UnsubscribeMap):
                await self._map_subscription(message)
