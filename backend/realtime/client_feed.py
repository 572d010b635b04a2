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
from backend.realtime.bus import LatestSubscription, Topic
from backend.realtime.collaborators import FeedServices
from backend.realtime.frames import FrameTooLarge, PeerConnection
from backend.realtime.scan_feed import ScanSubscription
from protocol.messages import (
    MAX_SCAN_SUBSCRIPTIONS,
    CloseCode,
    ErrorReply,
    FleetSnapshot,
    Ping,
    Pong,
    ProtocolError,
    ScanSubscriptions,
    SubscribeScans,
    UnsubscribeScans,
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


class ClientFeed(PeerConnection):
    def __init__(self, websocket: WebSocket, hub: FeedServices) -> None:
        super().__init__(websocket, hub.settings.max_frame_bytes, hub.settings.max_bad_frames)
        self.hub = hub
        self.user = ""
        self.token_id: int | None = None
        self.scans = ScanSubscription()

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
        # Subscribe before the snapshot, so no change falls between the two.
        self.hub.bus.subscribe(Topic.VEHICLE_STATE, updates)
        try:
            await self.send(
                FleetSnapshot(vehicles=[record.summary() for record in self.hub.registry.all()])
            )
            async with asyncio.TaskGroup() as tasks:
                pusher = tasks.create_task(self._push(updates))
                scan_pusher = tasks.create_task(self._push_scans())
                expiry = tasks.create_task(self._end_at_expiry(principal.expires_at, pusher))
                await self._listen()
                pusher.cancel()
                scan_pusher.cancel()
                expiry.cancel()
        except* FrameTooLarge as group:
            log.warning("closing client %s: %s", self.peer, group.exceptions[0])
            with contextlib.suppress(RuntimeError):
                await self.close(CloseCode.MESSAGE_TOO_BIG, str(group.exceptions[0]))
        except* WebSocketDisconnect:
            pass
        finally:
            self.hub.bus.unsubscribe(Topic.VEHICLE_STATE, updates)
            if self.scans.vehicles:
                self.hub.bus.unsubscribe(Topic.SCANS, self.scans)
            self.hub.client_feeds.discard(self)

    async def _end_at_expiry(self, expires_at: float | None, pusher: asyncio.Task[None]) -> None:
        """A token's lifetime bounds the feed it opened, as a revocation does."""
        if expires_at is None:
            return
        await asyncio.sleep(max(0.0, expires_at - time.time()))
        pusher.cancel()  # nothing more goes out on an expired token
        log.info("closing client %s: the token of %s expired", self.peer, self.user)
        await self.close(CloseCode.UNAUTHORIZED, "token expired: log in again")

    async def _push(self, updates: LatestSubscription) -> None:
        interval = self.hub.settings.ui_update_interval_s
        while True:
            for summary in await updates.drain():
                await self.send(VehicleUpdate(vehicle=summary))
            # Pacing, not synchronisation: updates arriving meanwhile coalesce per vehicle.
            await asyncio.sleep(interval)

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
            elif isinstance(message, SubscribeScans | UnsubscribeScans):
                await self._scan_subscription(message)
