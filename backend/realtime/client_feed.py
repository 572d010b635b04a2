"""A dashboard or integration's live feed: the fleet, then coalesced per-vehicle updates."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time

from starlette.requests import HTTPConnection
from starlette.websockets import WebSocket, WebSocketDisconnect

from backend.audit import AuditAction, principal_audit_entry
from backend.auth.credentials import presented_principal, presented_token
from backend.auth.policy import (
    CLIENT_MESSAGE_PERMISSIONS,
    Permission,
    authorize,
    authorize_message,
)
from backend.control.lease import Lease, LeaseRefused
from backend.errors import Forbidden, VehicleNotFound
from backend.observability.metrics import Surface
from backend.realtime import manual_control
from backend.realtime.bus import LatestSubscription, Topic
from backend.realtime.collaborators import FeedServices
from backend.realtime.frames import FrameTooLarge, PeerConnection
from backend.realtime.live_events import EventSubscription
from backend.realtime.manual_relay import ManualRelay
from backend.realtime.scan_feed import ScanSubscription
from protocol.messages import (
    MAX_SCAN_SUBSCRIPTIONS,
    CloseCode,
    ControlRequest,
    ErrorReply,
    FleetSnapshot,
    ManualFrame,
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
    VehicleChange,
    VehicleSummary,
    VehicleUpdate,
    client_to_hub,
    decode,
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


# A vehicle's autopilot, vehicle type and modes: what its hello said.
VehicleInfo = tuple[str, str, tuple[str, ...]]


def _info(summary: VehicleSummary) -> VehicleInfo:
    return (summary.autopilot, summary.vehicle_type, tuple(summary.modes))


def vehicle_change(summary: VehicleSummary, sent: dict[str, VehicleInfo]) -> VehicleChange:
    """The update for `summary`, with its hello's info only if this feed has not sent
    it yet (`sent`, what it has sent per vehicle, is brought up to date)."""
    info = _info(summary)
    changed = sent.get(summary.id) != info
    sent[summary.id] = info
    # The summary's fields are validated already; this runs per client per update.
    return VehicleChange.model_construct(
        id=summary.id,
        autopilot=summary.autopilot if changed else None,
        vehicle_type=summary.vehicle_type if changed else None,
        modes=list(summary.modes) if changed else None,
        connected=summary.connected,
        last_seen=summary.last_seen,
        state=summary.state,
    )


class ClientFeed(PeerConnection):
    surface: Surface = "client_ws"

    def __init__(self, websocket: WebSocket, hub: FeedServices) -> None:
        super().__init__(websocket, hub.settings.max_frame_bytes, hub.settings.max_bad_frames)
        self.hub = hub
        self.user = ""
        self.token_id: int | None = None
        self._manual = ManualRelay(
            hub.registry, hub.leases.limits.max_rate_hz, on_collapse=self._count_collapse
        )
        self.scans = ScanSubscription()
        self.map = LatestSubscription()  # newest per layer, never a queue
        self.map_layers: set[MapLayer] = set()

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
        updates = LatestSubscription()
        events = EventSubscription()
        surveys = LatestSubscription()
        # Subscribe before the snapshot, so no change falls between the two.
        self.hub.bus.subscribe(Topic.VEHICLE_STATE, updates)
        self.hub.bus.subscribe(Topic.VEHICLE_EVENT, events)
        self.hub.bus.subscribe(Topic.SURVEYS, surveys)
        try:
            fleet = [record.summary() for record in self.hub.registry.all()]
            await self.send(FleetSnapshot(vehicles=fleet))
            # Who flies what by hand, and how the last leases ended (a hub restart's
            # revocations among them).
            for state in list(self.hub.leases.last_states.values()):
                await self.send(state)
            sent = {summary.id: _info(summary) for summary in fleet}
            async with asyncio.TaskGroup() as tasks:
                pusher = tasks.create_task(self._push(updates, sent))
                event_pusher = tasks.create_task(self._push_events(events))
                scan_pusher = tasks.create_task(self._push_scans())
                survey_pusher = tasks.create_task(self._push_surveys(surveys))
                map_pusher = tasks.create_task(self._push_map())
                relay = tasks.create_task(self._manual.run())
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
            with contextlib.suppress(RuntimeError):
                await self.close(CloseCode.MESSAGE_TOO_BIG, str(group.exceptions[0]))
        except* WebSocketDisconnect:
            pass
        finally:
            self.hub.bus.unsubscribe(Topic.VEHICLE_STATE, updates)
            self.hub.bus.unsubscribe(Topic.VEHICLE_EVENT, events)
            self.hub.bus.unsubscribe(Topic.SURVEYS, surveys)
            if self.scans.vehicles:
                self.hub.bus.unsubscribe(Topic.SCANS, self.scans)
            if self.map_layers:
                self.hub.bus.unsubscribe(Topic.MAP, self.map)
            self.hub.client_feeds.discard(self)

    async def _end_at_expiry(self, expires_at: float | None, *pushers: asyncio.Task[None]) -> None:
        """A token's lifetime bounds the feed it opened, as a revocation does."""
        if expires_at is None:
            return
        await asyncio.sleep(max(0.0, expires_at - time.time()))
        for pusher in pushers:
            pusher.cancel()  # nothing more goes out on an expired token
        log.info("closing client %s: the token of %s expired", self.peer, self.user)
        await self.close(CloseCode.UNAUTHORIZED, "token expired: log in again")

    async def _push(self, updates: LatestSubscription, sent: dict[str, VehicleInfo]) -> None:
        interval = self.hub.settings.ui_update_interval_s
        while True:
            for summary in await updates.drain():
                await self.send(VehicleUpdate(vehicle=vehicle_change(summary, sent)))
            # Pacing, not synchronisation: updates arriving meanwhile coalesce per vehicle.
            await asyncio.sleep(interval)

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
                message = decode(client_to_hub, frame)
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
                await self._manual_input(message)
            elif isinstance(message, ControlRequest):
                await self._control(message)
            elif isinstance(message, SubscribeScans | UnsubscribeScans):
                await self._scan_subscription(message)
            elif isinstance(message, SubscribeMap | UnsubscribeMap):
                await self._map_subscription(message)

    async def _manual_input(self, message: ManualInput) -> None:
        """Forward the lease holder's input, newest first; refuse and count the rest."""
        try:
            self.hub.leases.admit(message.vehicle_id, self.user, message.seq)
        except LeaseRefused as refusal:
            # Never forwarded. Old or too-fast frames are a client's jitter: counted
            # silently; input without the lease is said, since the pilot must know.
            if "lease" in refusal.message:
                await self.send(ErrorReply(code="forbidden", message=refusal.message))
            return
        self._manual.put(
            message.vehicle_id,
            # Its fields were validated as the ManualInput arrived: the hot path (25 Hz
            # per pilot) builds the relayed frame without validating them again.
            ManualFrame.model_construct(
                type="manual",
                seq=message.seq,
                axes=message.axes,
                source=message.source,
                sent_ms=message.sent_ms,
            ),
        )

    def _count_collapse(self) -> None:
        self.hub.leases.refused.too_fast += 1

    async def _control(self, message: ControlRequest) -> None:
        vehicle_id = message.vehicle_id
        leases = self.hub.leases
        outcome, reason = "ok", ""
        ended: Lease | None = None
        try:
            if self.hub.registry.get(vehicle_id).channel is None:
                raise LeaseRefused(f"{vehicle_id} is offline")
            if message.action == "acquire":
                lease = await manual_control.acquire(self.hub, vehicle_id, self.principal)
            elif message.action == "release":
                ended = leases.release(vehicle_id, self.principal)
                reason = f"released by {self.user}"
            else:
                ended = leases.revoke(vehicle_id, self.principal)
                reason = f"revoked by {self.user}"
        except (Forbidden, VehicleNotFound) as refusal:
            outcome = "refused"
            reason = refusal.message
            await self.send(ErrorReply(code="forbidden", message=reason))
        await self.hub.record(
            principal_audit_entry(
                self.principal,
                self.peer,
                AuditAction.CONTROL_LEASE,
                vehicle_id,
                outcome,
                {"action": message.action, "reason": reason},
            )
        )
        if outcome != "ok":
            return
        if message.action == "acquire":
            await manual_control.announce(self.hub, manual_control.lease_state(lease))
        elif ended is not None:
            await manual_control.end(self.hub, ended, reason, stop_vehicle=True)
