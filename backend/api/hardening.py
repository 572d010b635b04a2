"""Transport hardening: security headers and request-size limits (the WebSocket origin
check is the live feed's own, in backend/realtime/client_feed.py)."""

from __future__ import annotations

import re
from collections.abc import Iterable
from urllib.parse import urlsplit

from starlette.datastructures import Headers
from starlette.exceptions import HTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

SECURITY_HEADERS = {
    "x-content-type-options": "nosniff",
    "x-frame-options": "DENY",
    "referrer-policy": "no-referrer",
    "permissions-policy": "geolocation=(), camera=(), microphone=()",
    "cross-origin-opener-policy": "same-origin",
}


def tile_sources(tile_urls: Iterable[str]) -> list[str]:
    """The origins that serve these XYZ templates; ``{s}`` is Leaflet's a, b and c."""
    origins: list[str] = []
    for url in tile_urls:
        for subdomain in ("a", "b", "c") if "{s}" in url else ("",):
            parts = urlsplit(url.replace("{s}", subdomain))
            origin = f"{parts.scheme}://{parts.netloc}"
            if origin not in origins:
                origins.append(origin)
    return origins


def content_security_policy(*tile_urls: str) -> str:
    """Only our own bundle runs; map tiles come from the hub or the configured base maps."""
    tiles = " ".join(["'self' data: blob:", *tile_sources(tile_urls)])
    return (
        "default-src 'self'; "
        f"img-src {tiles}; "
        "style-src 'self' 'unsafe-inline'; "  # Leaflet positions tiles with inline styles
        "script-src 'self'; "
        # 'self' covers the hub's own ws:// and wss:// (CSP 3): an injected script can
        # reach no other host, and so cannot send what it reads anywhere else.
        "connect-src 'self'; "
        "frame-ancestors 'none'; base-uri 'none'; form-action 'self'"
    )


class SecurityMiddleware:
    """Adds security headers to every HTTP response and refuses bodies over the limit.

    Pure ASGI (not BaseHTTPMiddleware) so it neither buffers responses nor touches
    WebSockets, whose frames have their own limit.
    """

    def __init__(
        self,
        app: ASGIApp,
        max_body_bytes: int,
        csp: str,
        hsts: bool,
        large_bodies: dict[str, int] | None = None,
    ) -> None:
        self.app = app
        self.max_body_bytes = max_body_bytes
        # Routes that take files: path pattern -> their own limit.
        self.large_bodies = [(re.compile(p), size) for p, size in (large_bodies or {}).items()]
        self.headers = [(k.encode(), v.encode()) for k, v in SECURITY_HEADERS.items()]
        self.headers.append((b"content-security-policy", csp.encode()))
        if hsts:
            self.headers.append((b"strict-transport-security", b"max-age=31536000"))

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        limit = next(
            (size for pattern, size in self.large_bodies if pattern.match(scope["path"])),
            self.max_body_bytes,
        )
        declared = Headers(scope=scope).get("content-length")
        if declared is not None and declared.isdigit() and int(declared) > limit:
            await self._too_large(send, limit)
            return
        received = 0

        async def limited_receive() -> Message:
            nonlocal received
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > limit:
                    # A chunked body that lies about nothing but keeps growing.
                    raise BodyTooLarge(limit)
            return message

        async def send_with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = list(message.get("headers", []))
                # A page that states its own policy keeps it (the ReDoc page adds a worker).
                own = {name.lower() for name, _ in headers}
                message["headers"] = headers + [h for h in self.headers if h[0] not in own]
            await send(message)

        try:
            await self.app(scope, limited_receive, send_with_headers)
        except BodyTooLarge:
            await self._too_large(send, limit)

    async def _too_large(self, send: Send, limit: int) -> None:
        body = b'{"detail":"request body is over the ' + str(limit).encode() + b'-byte limit"}'
        await send(
            {
                "type": "http.response.start",
                "status": 413,
                "headers": [(b"content-type", b"application/json"), *self.headers],
            }
        )
        await send({"type": "http.response.body", "body": body})


class BodyTooLarge(HTTPException):
    """Raised from ``receive``: an HTTPException, so that the route that was reading the
    body lets it through (FastAPI turns any other error there into a 400) and the app
    answers it as a 413."""

    def __init__(self, limit: int) -> None:
        super().__init__(413, f"request body is over the {limit}-byte limit")
