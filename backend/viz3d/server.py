"""The viser server the hub owns: on loopback only, on a port the OS picks.

viser serves its browser client (one self-contained HTML page) and the scene's WebSocket
on one port. Nothing but the hub reaches that port: the browser goes through the hub's
``/viz/`` routes, which check the session first (``backend.viz3d.gateway``).
"""

from __future__ import annotations

import base64
import contextlib
import hashlib
import hmac
import io
import logging
import re
import secrets
from pathlib import Path
from typing import Any

import viser
from viser import _messages as viser_messages

from protocol.messages import CloseCode

log = logging.getLogger(__name__)

LOOPBACK = "127.0.0.1"
# The header the hub's relay sends viser's socket, carrying VizServer.key.
VIZ_KEY_HEADER = "X-Gcs-Viz-Key"
_INLINE_SCRIPT = re.compile(rb"<script(?![^>]*\bsrc=)[^>]*>(.*?)</script>", re.DOTALL)


class VizServer:
    """A started viser server; ``stop()`` ends it (its thread and its clients)."""

    def __init__(self, server: viser.ViserServer, key: str) -> None:
        self.viser = server
        self.port = server.get_port()
        self.page_policy = page_policy(client_page())
        # What the hub's relay presents in VIZ_KEY_HEADER (require_relay_key).
        self.key = key

    @classmethod
    def start(cls, label: str = "Fleet GCS") -> VizServer:
        # port=0: the OS picks a free port, so two hubs (or tests) never collide. viser
        # prints a banner with its own address; that address is not for operators (the
        # hub's /viz/ is), so the banner goes to the debug log instead.
        banner = io.StringIO()
        with contextlib.redirect_stdout(banner):
            server = viser.ViserServer(host=LOOPBACK, port=0, label=label, verbose=False)
        log.debug("viser: %s", banner.getvalue())
        close_share_links(server)
        key = secrets.token_urlsafe(32)
        require_relay_key(server, key)
        started = cls(server, key)
        log.info("3D view (viser %s) on %s:%d", viser.__version__, LOOPBACK, started.port)
        return started

    @property
    def http_url(self) -> str:
        return f"http://{LOOPBACK}:{self.port}"

    @property
    def ws_url(self) -> str:
        return f"ws://{LOOPBACK}:{self.port}"

    @property
    def relay_headers(self) -> dict[str, str]:
        """What a scene socket to ``ws_url`` must send: the hub's relay, and tests."""
        return {VIZ_KEY_HEADER: self.key}

    def stop(self) -> None:
        with contextlib.redirect_stdout(io.StringIO()):  # viser prints "Server stopped"
            self.viser.stop()


def require_relay_key(server: viser.ViserServer, key: str) -> None:
    """viser's port is on loopback, but any local process (another user's, a browser
    page's fetch to 127.0.0.1) could open its WebSocket and read the fleet's scene past
    the hub's login. So a scene socket must present this start's random key, which only
    the hub's relay knows; any other is closed before viser sends it anything (its
    senders start after the connect callbacks). viser's HTTP side serves only its own
    client's static page. (viser is pinned: this reaches into its connection object.)"""
    sockets = server._websock_server
    expected = key.encode()

    async def admit(client: Any) -> None:
        connection = sockets._live_connections.get(client.client_id)
        if connection is None:
            return
        request = connection.request
        presented = ((request and request.headers.get(VIZ_KEY_HEADER)) or "").encode()
        if not hmac.compare_digest(presented, expected):
            log.warning("3D view: a scene socket without the hub's key was refused")
            await connection.close(
                CloseCode.FORBIDDEN, "the 3D view is reached through the hub's /viz/"
            )

    # First, so that no other callback works for a socket that is being refused.
    sockets._client_connect_cb.insert(0, admit)


def close_share_links(server: viser.ViserServer) -> None:
    """viser's share button asks its server to open a public tunnel to the scene, which
    would show the fleet to anyone with the link, past the hub's login. The button is
    hidden, and the server no longer acts on the request even if a client sends it.
    (viser is pinned: this reaches into its connection object by name.)"""
    server.gui.configure_theme(show_share_button=False)
    connection = server._websock_server
    for message in (viser_messages.ShareUrlRequest, viser_messages.ShareUrlDisconnect):
        connection.unregister_handler(message)


def client_page() -> bytes:
    """viser's browser client: one HTML page with its code inline."""
    root = Path(viser.__file__).resolve().parent / "client" / "build" / "index.html"
    return root.read_bytes()


def page_policy(page: bytes) -> str:
    """The Content-Security-Policy of the 3D view's page.

    viser's page is one inline script that unpacks a WebAssembly zstd decoder and then
    adds the client's module script. So: that inline script by its hash (nothing else
    inline runs), 'strict-dynamic' to trust the script it adds, WebAssembly compilation,
    and blob: workers. 'unsafe-eval' too: the client's Emscripten (embind) module builds
    its call wrappers with ``new Function``; with 'strict-dynamic' and the hash, only
    viser's own code is there to call it. Everything else is the hub's own origin, as for
    the dashboard, and only the hub's own pages may frame it (the dashboard embeds it).
    """
    hashes = " ".join(
        "'sha256-" + base64.b64encode(hashlib.sha256(body).digest()).decode() + "'"
        for body in _INLINE_SCRIPT.findall(page)
    )
    return (
        "default-src 'self'; "
        f"script-src 'self' {hashes} 'strict-dynamic' 'unsafe-eval' 'wasm-unsafe-eval'; "
        "style-src 'self' 'unsafe-inline'; "
        "img-src 'self' data: blob:; "
        "font-src 'self' data:; "
        "connect-src 'self' data: blob:; "
        "worker-src 'self' blob:; "
        "frame-ancestors 'self'; base-uri 'none'; form-action 'self'"
    )
