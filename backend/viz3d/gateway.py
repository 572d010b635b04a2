"""The way into the 3D view: the hub's ``/viz/`` routes check the caller, then pass HTTP
requests and the scene's WebSocket on to the viser server on loopback.

The check is the live feed's (``backend.realtime.client_feed``): a bearer token or the
dashboard's session cookie, the READ permission (a viewer may look), and for WebSockets
the page's origin. Nothing reaches viser before it passes.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from typing import Protocol

import httpx
from starlette.requests import HTTPConnection
from starlette.responses import JSONResponse, Response
from starlette.websockets import WebSocket, WebSocketDisconnect
from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed, InvalidHandshake
from websockets.typing import Subprotocol

from backend.auth.accounts import Accounts
from backend.auth.credentials import presented_principal, presented_token
from backend.auth.policy import Permission, Principal, authorize
from backend.errors import Forbidden
from backend.realtime.client_feed import origin_allowed
from backend.realtime.collaborators import ClientConnection as FeedConnection
from backend.realtime.frames import close_reason
from backend.settings import HubSettings
from backend.viz3d.server import VizServer
from protocol.messages import CloseCode

log = logging.getLogger(__name__)

# Request headers passed on to viser; the caller's cookie and Authorization stay here.
_REQUEST_HEADERS = ("accept", "accept-encoding", "if-none-match", "if-modified-since")
_RESPONSE_HEADERS = ("content-type", "content-encoding", "etag", "last-modified")
# viser's own frames can be large (a point cloud, a mesh); its client accepts 50 MB.
MAX_SCENE_FRAME_BYTES = 50 * 1024 * 1024
UPSTREAM_OPEN_TIMEOUT_S = 5.0
# RFC 6455 codes for the two ways the view itself ends a socket.
GOING_AWAY = 1001
TRY_AGAIN_LATER = 1013


class VizServices(Protocol):
    """What the 3D view's gateway uses of the hub."""

    @property
    def settings(self) -> HubSettings: ...

    @property
    def accounts(self) -> Accounts: ...

    @property
    def client_feeds(self) -> set[FeedConnection]: ...

    @property
    def viz(self) -> VizServer | None: ...

    @property
    def viz_http(self) -> httpx.AsyncClient | None: ...


class Refusal(Exception):
    def __init__(self, status: int, close_code: int, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.close_code = close_code
        self.message = message


async def admit(connection: HTTPConnection, hub: VizServices) -> Principal:
    """The caller, if it may see the 3D view; raises Refusal (401/4401, 403/4403)."""
    principal = await presented_principal(connection, hub.accounts)
    if principal is None:
        message = (
            "not authenticated: log in, or send 'Authorization: Bearer <token>'"
            if presented_token(connection) is None
            else "the token is invalid, expired or revoked: log in again"
        )
        raise Refusal(401, CloseCode.UNAUTHORIZED, message)
    try:
        authorize(principal, Permission.READ)
    except Forbidden as refusal:
        raise Refusal(403, CloseCode.FORBIDDEN, refusal.message) from None
    return principal


def refusal_response(refusal: Refusal) -> JSONResponse:
    headers = {"WWW-Authenticate": "Bearer"} if refusal.status == 401 else {}
    return JSONResponse({"detail": refusal.message}, status_code=refusal.status, headers=headers)


def unavailable() -> JSONResponse:
    return JSONResponse(
        {"detail": "the 3D view is not running (GCS_VIZ_ENABLED, or the hub is starting)"},
        status_code=503,
        headers={"Retry-After": "5"},
    )


async def forward_http(request: HTTPConnection, hub: VizServices, path: str) -> Response:
    """A GET under /viz/, answered by viser (its client page), for an admitted caller."""
    try:
        await admit(request, hub)
    except Refusal as refusal:
        return refusal_response(refusal)
    if hub.viz is None or hub.viz_http is None:
        return unavailable()
    headers = {name: value for name in _REQUEST_HEADERS if (value := request.headers.get(name))}
    try:
        async with hub.viz_http.stream(
            "GET", f"{hub.viz.http_url}/{path}", headers=headers
        ) as answer:
            # Raw: the body keeps viser's own Content-Encoding (gzip), passed on as is.
            body = b"".join([chunk async for chunk in answer.aiter_raw()])
    except httpx.HTTPError as error:
        log.warning("3D view: viser did not answer %s: %s", path, error)
        return unavailable()
    passed = {name: value for name in _RESPONSE_HEADERS if (value := answer.headers.get(name))}
    # The page states its own policy (SecurityMiddleware keeps it): viser's inline
    # loader by hash, WebAssembly, and framing by the dashboard only.
    passed["content-security-policy"] = hub.viz.page_policy
    passed["x-frame-options"] = "SAMEORIGIN"
    passed["cache-control"] = "no-store"  # behind a login: no shared caches
    return Response(body, status_code=answer.status_code, headers=passed)


class _Ended(Exception):
    """One direction of the relay is over; the other is cancelled with it."""


class VizRelay:
    """One browser's scene WebSocket, relayed frame by frame to viser and back.

    Backpressure: each direction forwards one frame and waits until it is sent before it
    reads the next, with no queue in between. A slow browser therefore stops the hub
    reading from viser, and viser's own buffer then keeps only the newest state per scene
    node (its redundancy keys) instead of a backlog growing in the hub. Both directions
    run in one task group: when either side closes or fails, the other is cancelled and
    both sockets are closed.
    """

    def __init__(self, websocket: WebSocket, hub: VizServices) -> None:
        self.websocket = websocket
        self.hub = hub
        self.user = ""
        self.token_id: int | None = None
        self.peer = f"{websocket.client.host}:{websocket.client.port}" if websocket.client else "?"
        self._closed = False

    async def close(self, code: int, reason: str) -> None:
        """Revocation (the hub's ``drop_user_feeds``) and expiry end the relay."""
        if self._closed:
            return
        self._closed = True
        with contextlib.suppress(RuntimeError, WebSocketDisconnect):
            await self.websocket.close(code, close_reason(reason))

    async def serve(self) -> None:
        offered = list(self.websocket.scope.get("subprotocols", []))
        if not origin_allowed(self.websocket, self.hub.settings.cors_origins):
            origin = self.websocket.headers.get("origin")
            await self._refuse(offered, CloseCode.FORBIDDEN, f"origin {origin} is not allowed")
            return
        try:
            principal = await admit(self.websocket, self.hub)
        except Refusal as refusal:
            await self._refuse(offered, refusal.close_code, refusal.message)
            return
        viz = self.hub.viz
        if viz is None:
            await self._refuse(offered, TRY_AGAIN_LATER, "the 3D view is not running")
            return
        self.user = principal.name
        self.token_id = principal.token_id
        try:
            upstream = await connect(
                viz.ws_url,
                additional_headers=viz.relay_headers,
                subprotocols=[Subprotocol(p) for p in offered] or None,
                max_size=MAX_SCENE_FRAME_BYTES,
                compression=None,
                open_timeout=UPSTREAM_OPEN_TIMEOUT_S,
            )
        except (OSError, InvalidHandshake, TimeoutError) as error:
            log.warning("3D view: viser refused the relay for %s: %s", self.peer, error)
            await self._refuse(offered, TRY_AGAIN_LATER, "the 3D view is not running")
            return
        self.hub.client_feeds.add(self)
        try:
            await self.websocket.accept(subprotocol=upstream.subprotocol)
            async with asyncio.TaskGroup() as tasks:
                tasks.create_task(self._to_viser(upstream))
                tasks.create_task(self._to_browser(upstream))
                tasks.create_task(self._end_at_expiry(principal.expires_at))
        except* (_Ended, WebSocketDisconnect, ConnectionClosed):
            pass
        finally:
            self.hub.client_feeds.discard(self)
            await upstream.close()
            await self.close(GOING_AWAY, "the 3D view closed")

    async def _refuse(self, offered: list[str], code: int, reason: str) -> None:
        # Accepted first so the browser reads the code (4401, 4403) rather than a failed
        # handshake; the subprotocol it offered is echoed, as its client insists on one.
        await self.websocket.accept(subprotocol=offered[0] if offered else None)
        await self.close(code, reason)

    async def _to_viser(self, upstream: ClientConnection) -> None:
        while True:
            message = await self.websocket.receive()
            if message["type"] == "websocket.disconnect":
                raise _Ended
            data = message.get("bytes")
            if data is None:
                data = (message.get("text") or "").encode()
            await upstream.send(data)

    async def _to_browser(self, upstream: ClientConnection) -> None:
        async for frame in upstream:
            if isinstance(frame, bytes):
                await self.websocket.send_bytes(frame)
            else:
                await self.websocket.send_text(frame)
        raise _Ended

    async def _end_at_expiry(self, expires_at: float | None) -> None:
        """A token's lifetime bounds the view it opened, as a revocation does."""
        if expires_at is None:
            return
        await asyncio.sleep(max(0.0, expires_at - time.time()))
        await self.close(CloseCode.UNAUTHORIZED, "token expired: log in again")
        raise _Ended
