"""The viser server the hub owns: on loopback only, on a port the OS picks.

viser serves its browser client (one self-contained HTML page) and the scene's WebSocket
on one port. Nothing but the hub reaches that port: the browser goes through the hub's
``/viz/`` routes, which check the session first (``backend.viz3d.gateway``).
"""

from __future__ import annotations

import base64
import contextlib
import hashlib
import io
import logging
import re
from pathlib import Path

import viser
from viser import _messages as viser_messages

log = logging.getLogger(__name__)

LOOPBACK = "127.0.0.1"
_INLINE_SCRIPT = re.compile(rb"<script(?![^>]*\bsrc=)[^>]*>(.*?)</script>", re.DOTALL)


class VizServer:
    """A started viser server; ``stop()`` ends it (its thread and its clients)."""

    def __init__(self, server: viser.ViserServer) -> None:
        self.viser = server
        self.port = server.get_port()
        self.page_policy = page_policy(client_page())

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
        started = cls(server)
        log.info("3D view (viser %s) on %s:%d", viser.__version__, LOOPBACK, started.port)
        return started

    @property
    def http_url(self) -> str:
        return f"http://{LOOPBACK}:{self.port}"

    @property
    def ws_url(self) -> str:
        return f"ws://{LOOPBACK}:{self.port}"

    def stop(self) -> None:
        with contextlib.redirect_stdout(io.StringIO()):  # viser prints "Server stopped"
            self.viser.stop()


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
