"""The 3D view under /viz/: the hub's login and roles stand in front of viser."""

from __future__ import annotations

import socket
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from protocol.messages import CloseCode
from tests.conftest import ADMIN_PASSWORD, hub_settings
from tests.support.api import access_token
from tests.support.hub_server import running_hub
from tests.viz_wire import SUBPROTOCOL, scene_messages, scene_socket

PASSWORD = "correct horse battery staple"


@pytest.fixture
def hub(tmp_path: Path) -> Iterator[str]:
    """The suite's hub with its 3D view on (`hub_settings` leaves it off)."""
    with running_hub(hub_settings(tmp_path, viz_enabled=True)) as base_url:
        yield base_url


def _viz_ws(hub: str) -> str:
    return hub.replace("http://", "ws://") + "/viz"


def _viewer_token(hub: str, admin_api: httpx.Client) -> str:
    response = admin_api.post(
        "/api/v1/users", json={"username": "vera", "password": PASSWORD, "role": "viewer"}
    )
    assert response.status_code == 201, response.text
    return access_token(hub, "vera", PASSWORD)


@pytest.mark.parametrize("path", ["/viz", "/viz/", "/viz/index.html", "/viz/anything/deeper"])
def test_http_without_a_session_is_refused(hub: str, path: str) -> None:
    response = httpx.get(hub + path, follow_redirects=False)
    assert response.status_code == 401
    assert response.headers["www-authenticate"] == "Bearer"
    assert "<html" not in response.text.lower()  # nothing of viser's page


def test_http_with_a_bad_token_is_refused(hub: str) -> None:
    response = httpx.get(hub + "/viz/", headers={"Authorization": "Bearer not-a-token"})
    assert response.status_code == 401


@pytest.mark.parametrize("headers", [{}, {"Authorization": "Bearer not-a-token"}])
def test_websocket_without_a_session_is_closed_4401(hub: str, headers: dict[str, str]) -> None:
    with (
        pytest.raises(ConnectionClosed) as closed,
        connect(_viz_ws(hub), subprotocols=[SUBPROTOCOL], additional_headers=headers) as ws,  # type: ignore[list-item]
    ):
        ws.recv(timeout=10)
    assert closed.value.rcvd is not None
    assert closed.value.rcvd.code == CloseCode.UNAUTHORIZED


def test_a_viewer_gets_the_page_and_sees_the_scene(hub: str, admin_api: httpx.Client) -> None:
    token = _viewer_token(hub, admin_api)
    auth = {"Authorization": f"Bearer {token}"}
    page = httpx.get(hub + "/viz/", headers=auth)
    assert page.status_code == 200
    assert page.headers["content-type"].startswith("text/html")
    assert '<div id="root">' in page.text
    policy = page.headers["content-security-policy"]
    assert "frame-ancestors 'self'" in policy
    assert "'strict-dynamic'" in policy
    assert page.headers["x-frame-options"] == "SAMEORIGIN"
    assert httpx.get(hub + "/viz", headers=auth).status_code == 307  # to /viz/

    # The client's own handshake: viser's subprotocol, answered through the relay.
    with connect(_viz_ws(hub), subprotocols=[SUBPROTOCOL], additional_headers=auth) as ws:  # type: ignore[list-item]
        assert ws.subprotocol == SUBPROTOCOL
        frame = ws.recv(timeout=10)
        assert isinstance(frame, bytes)
        kinds = {message["type"] for message in scene_messages(frame)}
        # The scene's set-up (its theme) reaches the viewer.
        assert "ThemeConfigurationMessage" in kinds, kinds


def test_the_session_cookie_lets_the_dashboard_in(hub: str) -> None:
    with httpx.Client(base_url=hub) as browser:
        login = browser.post(
            "/api/v1/auth/login", json={"username": "admin", "password": ADMIN_PASSWORD}
        )
        assert login.status_code in (200, 201, 204), login.text
        assert browser.get("/viz/").status_code == 200


def test_a_foreign_origin_is_refused(hub: str, admin_token: str) -> None:
    headers = {"Authorization": f"Bearer {admin_token}", "Origin": "http://evil.example"}
    with (
        pytest.raises(ConnectionClosed) as closed,
        connect(_viz_ws(hub), subprotocols=[SUBPROTOCOL], additional_headers=headers) as ws,  # type: ignore[list-item]
    ):
        ws.recv(timeout=10)
    assert closed.value.rcvd is not None
    assert closed.value.rcvd.code == CloseCode.FORBIDDEN


def _other_address() -> str | None:
    """An address of this machine that is not loopback, if it has one."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("192.0.2.1", 9))  # no packet is sent: this only picks a route
        except OSError:
            return None
        address: str = probe.getsockname()[0]
    return None if address.startswith("127.") else address


def test_viser_listens_on_loopback_only() -> None:
    from backend.viz3d.server import VizServer

    viz = VizServer.start()
    try:
        with socket.create_connection(("127.0.0.1", viz.port), timeout=5):
            pass
        other = _other_address()
        if other is not None:
            with pytest.raises(ConnectionRefusedError):
                socket.create_connection((other, viz.port), timeout=5).close()
        # The share button's public tunnel: the server does not act on its request.
        handlers = viz.viser._websock_server._incoming_handlers
        assert not any("ShareUrl" in kind.__name__ for kind in handlers)
    finally:
        viz.stop()


def test_vipers_own_port_refuses_a_scene_socket_without_the_hubs_key() -> None:
    """A local process that finds viser's loopback port gets no scene: the socket is
    closed 4403 before anything is sent. The hub's relay, with this start's key, gets in."""
    from backend.viz3d.server import VIZ_KEY_HEADER, VizServer

    viz = VizServer.start()
    try:
        for headers in ({}, {VIZ_KEY_HEADER: "guessed"}):
            with scene_socket(viz, headers) as ws, pytest.raises(ConnectionClosed) as closed:
                ws.recv(timeout=10)  # closed before viser sends anything
            assert closed.value.rcvd is not None
            assert closed.value.rcvd.code == CloseCode.FORBIDDEN
        with scene_socket(viz) as ws:
            kinds = {message["type"] for message in scene_messages(ws.recv(timeout=10))}  # type: ignore[arg-type]
            assert "ThemeConfigurationMessage" in kinds, kinds
    finally:
        viz.stop()
