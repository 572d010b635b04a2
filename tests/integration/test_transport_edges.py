"""Transport edges: a chunked body over the limit is a 413 like a declared one, and the
socket's origin check compares the scheme as well as the host."""

from __future__ import annotations

import json
from collections.abc import Iterator

import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from protocol.messages import CLIENT_WS_PATH, CloseCode
from tests.support.api import api_client


def _chunks(total: int, size: int = 64 * 1024) -> Iterator[bytes]:
    yield b'{"value": "'
    for _ in range(total // size):
        yield b"x" * size
    yield b'"}'


def test_chunked_body_over_the_limit_is_413(hub: str, admin_token: str) -> None:
    with api_client(hub, admin_token) as api:
        # A generator has no length, so httpx sends it chunked, without Content-Length.
        response = api.put(
            "/api/v1/vehicles/v1/params/WPNAV_SPEED", content=_chunks(2 * 1024 * 1024)
        )
    assert response.status_code == 413, response.text
    assert "limit" in response.json()["detail"]


def _open_feed(hub: str, token: str, origin: str) -> dict[str, object]:
    url = hub.replace("http://", "ws://") + CLIENT_WS_PATH
    headers = {"Authorization": f"Bearer {token}", "Origin": origin}
    with connect(url, additional_headers=headers) as socket:
        first: dict[str, object] = json.loads(socket.recv(timeout=5))
        return first


def test_websocket_origin_must_match_the_scheme_too(hub: str, admin_token: str) -> None:
    host = hub.removeprefix("http://")
    assert _open_feed(hub, admin_token, f"http://{host}")["type"] == "fleet"
    with pytest.raises(ConnectionClosed) as closed:
        _open_feed(hub, admin_token, f"https://{host}")
    assert closed.value.rcvd is not None
    assert closed.value.rcvd.code == CloseCode.FORBIDDEN
